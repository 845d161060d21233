// XYZ / TXT / CSV / PTS reading: plain-text point lists, one point per line.
//
// Values are separated by whitespace or by commas (with optional whitespace
// around them; an empty field between two commas is an error). Lines whose
// first non-blank characters are '#' or '//' are comments; blank lines are
// skipped. Numbers are C locale decimal or exponent notation ("nan" and "inf"
// parse, and are then invalid points).
//
// Columns are named by `ScanReadOptions::columns`, space separated, in order:
//   x y z          position, meters (required)
//   r g b          color (also red green blue): 0..255, or 0..1 floats; the
//                  scale is decided by the first value that is > 1 (0..255)
//                  or fractional (0..1); mixing both is an error
//   i              intensity (also intensity), see below
//   nx ny nz       normal
//   _              a column to skip
// With explicit columns, a line may have more values than named (the rest are
// ignored) but not fewer. Without them the first data line decides, and every
// line must have that many values:
//   3 = x y z, 4 = x y z i, 6 = x y z r g b, 7 = x y z i r g b,
//   9 = x y z r g b nx ny nz (CloudCompare's order).
//
// PTS (Leica; by the extension .pts): the file is one or more blocks, each a
// line with the block's point count (a single integer) followed by that many
// points. Default columns as above (7 = x y z i r g b). Intensity is Leica's
// -2048..2047, mapped linearly to [0, 1]. A block with more or fewer points
// than its count is an error.
//
// Intensity in XYZ/TXT (and PTS values outside -2048..2047) has no standard
// scale: values already in [0, 1] are kept, 0..255 and 0..65535 are divided
// by 255 and 65535, anything else is mapped min..max -> 0..1; a warning says
// which.
//
// Positions are parsed as doubles (std::from_chars) and stored relative to an
// origin = the bounding-box center rounded to 1 m, so georeferenced
// coordinates keep their precision in float32 (as the PLY reader does for
// double properties). The file streams through a 1 MiB buffer.
//
// Errors name the file and the 1-based line, e.g.
//   scan.xyz:12: column 2 ('y'): expected a number, got '1,5'
//   scan.pts:1: count mismatch: 1000 points declared, the file ends after 998
#pragma once

#include <string>

#include "base/status.h"
#include "stages/geometry/io/scan_read.h"

namespace pb {

// Reads an XYZ/TXT/CSV/PTS file; `options.columns` overrides the default
// columns. `result.format` is the extension and the columns used, e.g.
// "pts (x y z i r g b)".
Expected<ScanReadResult> ReadXyz(const std::string& path, const ScanReadOptions& options);

}  // namespace pb
