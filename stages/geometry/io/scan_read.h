// The common shape of scan-file readers (PLY, PCD, PTS/XYZ, PTX, E57, LAS):
// each format's header declares
//   Expected<ScanReadResult> Read<Format>(const std::string& path,
//                                         const ScanReadOptions& options);
// and io.read_points picks one by extension or `format:`.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "stages/geometry/core/point_cloud.h"

namespace pb {

struct ScanReadOptions {
  // Drop points with NaN/Inf coordinates (counted) instead of failing on the
  // first one. Formats with a validity convention (PTX 0,0,0; PCD NaN in
  // organized clouds; E57 invalidState) drop those always and count them.
  bool drop_invalid_points = false;
  // Fraction done in [0, 1], called every few MB; may be empty.
  std::function<void(double)> progress;
  // XYZ/TXT/PTS only: column names in order, e.g. "x y z r g b" or
  // "x y z i r g b nx ny nz"; empty = the format's default / auto-detect.
  std::string columns;
};

struct ScanReadResult {
  PointCloud points;
  uint64_t dropped_points = 0;        // invalid points dropped
  std::vector<std::string> warnings;  // shown to the user, e.g. "3 scans merged"
  std::string format;                 // e.g. "pcd binary_compressed", "e57"
};

}  // namespace pb
