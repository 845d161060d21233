// PCD (Point Cloud Library "Point Cloud Data") reading.
//
// Format: https://pointclouds.org/documentation/tutorials/pcd_file_format.html
// (v0.7; v0.6 is the same without VIEWPOINT). A text header, one keyword per
// line ('#' starts a comment), DATA last:
//
//   VERSION 0.7
//   FIELDS x y z rgb normal_x normal_y normal_z curvature   <- field names
//   SIZE 4 4 4 4 4 4 4 4         <- bytes per value: 1, 2, 4 or 8
//   TYPE F F F F F F F F         <- I signed, U unsigned, F float (4 or 8 bytes)
//   COUNT 1 1 1 1 1 1 1 1        <- values per field (optional, default 1)
//   WIDTH 640                    <- points per row
//   HEIGHT 480                   <- rows; > 1 = an organized cloud (image grid)
//   VIEWPOINT tx ty tz qw qx qy qz   <- sensor pose (optional, v0.7)
//   POINTS 307200                <- WIDTH * HEIGHT (optional)
//   DATA binary_compressed       <- ascii | binary | binary_compressed
//
// Body layouts:
//   ascii:  one point per line, the fields' values in order, space separated.
//   binary: POINTS packed little-endian records, the fields in order.
//   binary_compressed: uint32 compressed size, uint32 uncompressed size, then
//           one LZF block (liblzf format) whose uncompressed bytes hold the
//           fields one after another (structure of arrays): all points' x,
//           then all y, ... Field k starts at POINTS * (bytes of fields < k).
//
// Fields read: x y z (F4 or F8, meters); normal_x normal_y normal_z; rgb or
// rgba (4 bytes, F or U: a uint32 0xAARRGGBB, r = (v >> 16) & 255); r g b as
// separate U1 fields; intensity (U1 / U2 scaled to [0,1]; float kept when it
// lies in [0,1], otherwise divided by the cloud's maximum, with a warning).
// Every other field (curvature, label, fpfh with COUNT 33, '_' padding, ...)
// is skipped. x, y, z and the other recognized fields must have COUNT 1.
//
// VIEWPOINT: the pose (rotation qw qx qy qz, then translation tx ty tz) is
// applied to the points and normals, and the translation becomes the cloud's
// only station (every point has station id 0). The identity pose (tx ty tz
// zero, qx qy qz zero) makes no station: PCL writes `VIEWPOINT 0 0 0 1 0 0 0`
// into every file by default, fused clouds included, and a station at the
// origin would orient normals wrongly. Without VIEWPOINT there is no
// station either. An organized cloud (HEIGHT > 1) without a VIEWPOINT pose
// (the identity, or none) is the exception when its image grid was swept
// from the origin (grid_station.h: a camera in its own frame, as a grabber
// writes it): its station is the origin, with a warning saying so (or why
// not).
// The origin stays (0, 0, 0) when x y z are F4 and tx ty tz are zero (the
// floats are kept bit for bit); otherwise points are re-centered on their
// bounding-box center rounded to 1 m, as the PLY reader does for doubles.
//
// Invalid points: in organized clouds (HEIGHT > 1) a NaN coordinate marks "no
// return"; such points are always left out and counted in no_return_points.
// Elsewhere a NaN/Inf coordinate is an error naming the point, unless
// drop_invalid_points (then counted in dropped_points).
//
// Memory: ascii and binary bodies stream through a 1 MiB buffer. A
// binary_compressed block is decompressed as a stream too (LZF references
// reach back at most 8 KiB), and each recognized field's values go straight
// into their output arrays as the stream yields them (x into positions[3i],
// y into positions[3i + 1], rgb into colors, ...); other fields' bytes are
// passed over unstored. Invalid points are then dropped by compacting the
// arrays in place, and the pose and re-centering applied. Peak ≈ the output
// cloud plus ~1.2 MiB in every case (measured 1.01× for 5·10^6 points with
// normals and colors). Allocation is bounded by what the file can hold (an
// LZF block expands at most 88×), so a corrupt header cannot exhaust memory.
//
// binary_compressed with F8 (or mixed-size) coordinates: each axis is stored
// as a float relative to its first finite value (+ the VIEWPOINT translation
// when there is no rotation) rounded to 1 m, which then serves as the
// provisional origin; for PCL files (a point is either fully valid or all
// NaN) that is the first valid point, as in the other bodies, and the output
// is the same bit for bit. With a non-identity VIEWPOINT rotation the points
// are rotated from those floats, so coordinates (and F8 normals) may differ
// by one float ulp from the other bodies' (7.6e-6 m at 64 m from the
// origin), and a non-finite-coordinate error prints the finite values with
// float precision. A finite F8 value too far from that origin to fit a float
// counts as non-finite.
//
// Errors name the file and the place: `scan.pcd:7: expected 'POINTS <count>'`
// (header line), `scan.pcd: truncated: point 1203 of 35947 at byte 48211`,
// `scan.pcd: corrupt LZF block: back reference of 4000 bytes at output byte
// 12 (compressed byte 9, file byte 251)`.
#pragma once

#include <string>

#include "base/status.h"
#include "stages/geometry/io/scan_read.h"

namespace pb {

// Reads a PCD file (ascii, binary or binary_compressed). `result.format` is
// "pcd ascii", "pcd binary" or "pcd binary_compressed"; `options.columns` is
// ignored.
Expected<ScanReadResult> ReadPcd(const std::string& path, const ScanReadOptions& options);

}  // namespace pb
