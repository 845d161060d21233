// E57 (ASTM E2807, "3D Imaging Data Exchange") point-cloud reading.
//
// An E57 file is paged (1024-byte pages: 1020 data bytes + CRC-32C, see
// e57_binary.h) and holds, in logical order:
//   48-byte header (page 0), little-endian:
//     char[8] "ASTM-E57", uint32 versionMajor (1), uint32 versionMinor,
//     uint64 filePhysicalLength, uint64 xmlPhysicalOffset,
//     uint64 xmlLogicalLength, uint64 pageSize (1024)
//   binary sections (CompressedVector point data, blobs such as JPEG images)
//   an XML section (parsed by e57_xml.h) describing the data:
//     /e57Root/data3D/vectorChild          one per scan
//       pose/rotation {w,x,y,z}            unit quaternion (default identity)
//       pose/translation {x,y,z}           meters (default 0)
//       colorLimits, intensityLimits       value ranges for normalization
//       points type="CompressedVector" fileOffset=<physical> recordCount=<n>
//         prototype                        one child (bytestream) per field:
//           Float (precision single|double), Integer (minimum, maximum),
//           ScaledInteger (minimum, maximum, scale, offset)
//         codecs                           empty, or bitPackCodec only
//
// ReadE57 reads every scan of data3D and merges them into one PointCloud:
//   - coordinates: cartesianX/Y/Z, else sphericalRange/Azimuth/Elevation
//     (radians) converted with x = r cos(el) cos(az), y = r cos(el) sin(az),
//     z = r sin(el); then the scan pose is applied (rotate, then translate);
//   - cartesianInvalidState / sphericalInvalidState != 0 (1 = direction only,
//     2 = no return): the point is left out and counted in no_return_points;
//   - NaN/Inf coordinates: an error naming the scan and record, or dropped and
//     counted with options.drop_invalid_points;
//   - colorRed/Green/Blue -> 0..255 using colorLimits (else the prototype
//     field's minimum/maximum, else [0, 1] for Float fields); intensity ->
//     [0, 1] using intensityLimits the same way. Colors / intensities are
//     kept only if every scan has them (a warning says when they are not);
//     points whose isColorInvalid / isIntensityInvalid is set are listed in
//     colorless_points / intensityless_points (io.read_points gives them
//     their nearest valid neighbour's value);
//   - stations: one per scan, station_ids per point, when every scan's
//     scanner is known: at its pose's translation (absolute meters); a scan
//     without a pose (the identity) has its scanner at its frame's origin
//     when spherical coordinates are measured from there, or when its
//     rowIndex/columnIndex grid was swept from there (grid_station.h: the
//     angle between grid neighbours seen from the origin is constant; the
//     pump sample passes, a scan whose registration was baked into its
//     coordinates fails). Otherwise no stations, and a warning says which
//     scan and why, unless no scan had a pose or a grid to go by;
//   - origin: the bounding-box center of all points rounded to 1 m, positions
//     are float32 relative to it;
//   - rowIndex, columnIndex: only for the station test above; timeStamp,
//     returnIndex, extension fields (prefixed names) and other unknown
//     fields are decoded and ignored;
//     images2D and pointGroupingSchemes are ignored.
// Memory: the output arrays, the XML text, and one packet per stream.
//
// Errors name the file and the place: a page (`scan.e57: CRC-32C mismatch in
// page 3 (byte 3072)`), an XML line (`scan.e57: XML line 12: ...`), a section
// or packet byte offset and record index for binary data.
#pragma once

#include <string>

#include "base/status.h"
#include "stages/geometry/io/scan_read.h"

namespace pb {

// Reads all scans of an E57 file into one cloud (format "e57").
Expected<ScanReadResult> ReadE57(const std::string& path, const ScanReadOptions& options = {});

}  // namespace pb
