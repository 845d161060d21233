// PTX reading: the ASCII export of Leica Cyclone / Leica scanners and FARO
// SCENE, one or more structured (gridded) terrestrial scans in one text file.
//
// Format (there is no formal spec; this follows Leica's "PTX format" note and
// the files PDAL and CloudCompare read). A file is a sequence of scans, each:
//
//   15                                 <- columns (positive integer)
//   71                                 <- rows (positive integer)
//   600000 800000 400                  <- scanner position, registered frame, m
//   1 0 0                              <- scanner X axis, registered frame
//   0 1 0                              <- scanner Y axis
//   0 0 1                              <- scanner Z axis
//   r00 r01 r02 0                      <- 4x4 transform M, row-major as
//   r10 r11 r12 0                         written; the 4th ROW holds the
//   r20 r21 r22 0                         translation and the 4th column is
//   tx  ty  tz  1                         0 0 0 1
//   x y z intensity [r g b]            <- columns*rows point lines, scanner
//   ...                                   frame, meters
//
// Points are row vectors: registered p' = p * M, i.e.
//   x' = x*r00 + y*r10 + z*r20 + tx   (and likewise for y', z').
// (PDAL's multiple-and-transform.ptx confirms it: its scale-2 matrix maps the
// scan-1 point z 15.83 to 431.66 = 2*15.83 + 400.) A 4th column other than
// 0 0 0 1 (within 1e-6) means a column-major writer and is rejected rather
// than guessed at.
//
// What the reader makes of it:
//   - positions: transformed by M in double precision, then stored as float32
//     relative to `origin` = the first kept point rounded to 1 m (the file is
//     streamed, so bounds are unknown until the end; one scan spans at most
//     the scanner's range, where float32 still resolves ~0.1 mm at 1 km).
//   - stations: one per scan, in file order, the header's line-3 position as
//     written. It is already in the registered frame (in PDAL's samples it
//     equals M's translation row), so it is not transformed again.
//     station_ids give each point's scan. At most 65536 scans.
//   - intensities: as written, clamped to [0, 1] (a warning counts clamped
//     values; some old exporters write -2048..2047).
//   - colors: when the scan's point lines have 7 values (r g b in 0..255).
//     If some scans have colors and others not, colors are dropped with a
//     warning.
//   - "no return": a point written exactly as 0 0 0 (before the transform) is
//     a grid cell without a measurement; it is always left out and counted in
//     `no_return_points`.
//   - NaN/Inf in any value of a point line: an error naming the line, or
//     dropped and counted when `options.drop_invalid_points`.
// Blank lines are ignored; "\r\n" line ends are accepted.
//
// Errors name the file and the 1-based line, e.g.
//   scan.ptx:2: expected the row count (a positive integer), found 'abc'
//   scan.ptx:1074: truncated: scan 1 ends after 1064 of 1065 points
//                  (15 columns x 71 rows)
//   scan.ptx:12: expected 4 values (x y z intensity) or 7 (x y z intensity
//                r g b), found 5
#pragma once

#include <string>

#include "stages/geometry/io/scan_read.h"

namespace pb {

// Reads every scan of a PTX file into one cloud (format "ptx"). Memory is the
// output cloud plus a 1 MiB read buffer.
Expected<ScanReadResult> ReadPtx(const std::string& path, const ScanReadOptions& options = {});

}  // namespace pb
