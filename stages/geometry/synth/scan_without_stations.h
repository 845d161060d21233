// A synthetic scan without its stations, for tests (test-only: no production
// code includes it; here and not in stages/geometry/testing/, which sits below
// synth/ in the layers).
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "stages/geometry/core/point_cloud.h"
#include "stages/geometry/synth/scanner.h"
#include "stages/geometry/synth/scene.h"

namespace pb::testing {

// A scan as it is often handed on: its points without the stations that
// recorded them (a PLY of x, y, z and colour), and those stations beside it.
struct ScanWithoutStations {
  PointCloud cloud;                              // no station_ids, no stations
  std::vector<std::array<double, 3>> stations;  // where the scanners stood, absolute meters
};

// synth.scan's facade preset (two brick walls on a paved yard, a pump, a
// bench, a column: an open scene) from `stations` stations, about `points`
// points in all, its stations taken away. Empty when the scan fails (the
// caller's ASSERT on the size says so).
inline ScanWithoutStations FacadeWithoutStations(int stations, uint64_t points) {
  ScanWithoutStations scan;
  Expected<SynthScene> scene = MakeSynthScene("facade", 1);
  if (!scene.ok()) return scan;
  SynthScanOptions options;
  options.target_points = points;
  options.stations = stations;
  Expected<SynthScanResult> result = SimulateScan(*scene, options);
  if (!result.ok()) return scan;
  scan.cloud = std::move(result->cloud);
  scan.stations = std::move(scan.cloud.stations);
  scan.cloud.stations.clear();
  scan.cloud.station_ids.clear();
  return scan;
}

}  // namespace pb::testing
