// LAS reading: the ASPRS LASer exchange format, versions 1.0 to 1.4,
// uncompressed. Spec: ASPRS "LAS Specification 1.4 - R15" (2019), sections
// 2.4 (public header block) and 2.6 (point data record formats 0-10);
// LAS 1.2 (2008) for the older header sizes.
//
// Layout used (all little-endian; byte offsets into the public header block):
//     0  char[4]  "LASF"
//    24  uint8    version major (must be 1), 25: version minor (0..4)
//    94  uint16   header size (>= 227; 235 in 1.3, 375 in 1.4)
//    96  uint32   offset to point data (>= header size; VLRs lie between)
//   104  uint8    point data record format; bit 7 (0x80) or bit 6 (0x40) set
//                 = LAZ-compressed
//   105  uint16   point data record length (>= the format's size below;
//                 extra bytes per record are skipped)
//   107  uint32   legacy number of point records
//   131  double[3] x y z scale factors; 155: double[3] x y z offsets
//   179  double   max x, min x, max y, min y, max z, min z (meters)
//   247  uint64   number of point records (1.4, header size >= 375): used
//                 when non-zero, else the legacy count
//
// Point records (formats 0-10), the fields read:
//   format  size  X Y Z (int32 x3)  intensity (uint16)  red green blue (uint16 x3)
//   0       20    0                 12                  -
//   1       28    0                 12                  -
//   2       26    0                 12                  20
//   3       34    0                 12                  28
//   4 / 5   57/63 as 1 / 3 plus a waveform packet (ignored)
//   6       30    0                 12                  -
//   7       36    0                 12                  30
//   8       38    0                 12                  30   (+ NIR, ignored)
//   9 / 10  59/67 as 6 / 8 plus a waveform packet (ignored)
//
// What the reader makes of it:
//   - positions: X * scale + offset in double, stored as float32 relative to
//     `origin` = the center of the header's bounding box rounded to 1 m. If
//     that box is not finite or does not hold the first point (within 1 m),
//     the first point rounded to 1 m is used instead, with a warning.
//   - intensities: intensity / 65535.
//   - colors (formats 2, 3, 5, 7, 8, 10): if no channel of any point exceeds
//     255 the file is taken as 8-bit (many writers do that), else each
//     channel is shifted right by 8.
//   - no stations (LAS does not record scanner positions).
// Points are streamed through a 1 MiB buffer; memory is the output cloud.
//
// Not supported, with a message saying what to do: LAZ (a `.laz` name or a
// compressed point format), versions other than 1.x, unknown point formats.
// Errors name the file and the place, e.g.
//   scan.las: not a LAS file (expected signature 'LASF' at byte 0)
//   scan.las: truncated: point 1203 of 5000 at byte 24287 (file has 24300 bytes)
#pragma once

#include <string>

#include "stages/geometry/io/scan_read.h"

namespace pb {

// Reads the points of an uncompressed LAS file; `format` is e.g. "las 1.4
// format 7".
Expected<ScanReadResult> ReadLas(const std::string& path, const ScanReadOptions& options = {});

}  // namespace pb
