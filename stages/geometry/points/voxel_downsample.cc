#include "stages/geometry/points/voxel_downsample.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace pb {
namespace {

constexpr int kBitsPerAxis = 21;
constexpr int64_t kCellsPerAxis = int64_t{1} << kBitsPerAxis;

}  // namespace

Expected<PointCloud> VoxelDownsample(const PointCloud& cloud, const VoxelDownsampleOptions& options) {
  const double voxel_m = options.voxel_m;
  if (!(voxel_m > 0) || !std::isfinite(voxel_m)) {
    return Status::Invalid("voxel downsampling: voxel size must be a positive number of meters, got " +
                           std::to_string(voxel_m));
  }
  PB_RETURN_IF_ERROR(Validate(cloud));
  PointCloud out;
  out.origin = cloud.origin;
  out.stations = cloud.stations;
  const size_t n = cloud.size();
  if (n == 0) return out;

  // Integer cell of every point, relative to the smallest cell so that the
  // three axes pack into one 63-bit key.
  const Bounds bounds = AbsoluteBounds(cloud);
  std::array<int64_t, 3> min_cell{};
  for (int axis = 0; axis < 3; ++axis) {
    min_cell[axis] = static_cast<int64_t>(std::floor(bounds.min_m[axis] / voxel_m));
    const int64_t max_cell = static_cast<int64_t>(std::floor(bounds.max_m[axis] / voxel_m));
    if (max_cell - min_cell[axis] >= kCellsPerAxis) {
      return Status::Invalid("voxel downsampling: the cloud spans " +
                             std::to_string(max_cell - min_cell[axis] + 1) + " voxels of " +
                             std::to_string(voxel_m) + " m along " + "xyz"[axis] +
                             ", more than the supported 2^21; use a larger voxel");
    }
  }
  std::vector<std::pair<uint64_t, uint64_t>> keyed(n);  // (cell key, point index)
  for (size_t i = 0; i < n; ++i) {
    uint64_t key = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const double absolute = cloud.origin[axis] + static_cast<double>(cloud.positions[3 * i + axis]);
      int64_t cell = static_cast<int64_t>(std::floor(absolute / voxel_m)) - min_cell[axis];
      // Rounding at the bounds can step one cell outside; clamp.
      cell = std::clamp<int64_t>(cell, 0, kCellsPerAxis - 1);
      key = (key << kBitsPerAxis) | static_cast<uint64_t>(cell);
    }
    keyed[i] = {key, i};
  }
  // Ties sort by index, so sums run in input order: deterministic.
  std::sort(keyed.begin(), keyed.end());

  for (size_t begin = 0; begin < n;) {
    size_t end = begin + 1;
    while (end < n && keyed[end].first == keyed[begin].first) ++end;
    const double count = static_cast<double>(end - begin);
    double position[3] = {0, 0, 0};
    double normal[3] = {0, 0, 0};
    uint64_t color[3] = {0, 0, 0};
    double intensity = 0;
    for (size_t k = begin; k < end; ++k) {
      const size_t i = keyed[k].second;
      if (cloud.has_intensities()) intensity += cloud.intensities[i];
      for (int axis = 0; axis < 3; ++axis) {
        position[axis] += cloud.positions[3 * i + axis];
        if (cloud.has_normals()) normal[axis] += cloud.normals[3 * i + axis];
        if (cloud.has_colors()) color[axis] += cloud.colors[3 * i + axis];
      }
    }
    for (int axis = 0; axis < 3; ++axis) {
      out.positions.push_back(static_cast<float>(position[axis] / count));
    }
    if (cloud.has_colors()) {
      const uint64_t points = end - begin;
      for (int c = 0; c < 3; ++c) {
        out.colors.push_back(static_cast<uint8_t>((2 * color[c] + points) / (2 * points)));
      }
    }
    if (cloud.has_normals()) {
      const double length = std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
      const size_t first = keyed[begin].second;
      for (int axis = 0; axis < 3; ++axis) {
        out.normals.push_back(length < 1e-12 ? cloud.normals[3 * first + axis]
                                             : static_cast<float>(normal[axis] / length));
      }
    }
    if (cloud.has_intensities()) out.intensities.push_back(static_cast<float>(intensity / count));
    // A station cannot be averaged: the voxel keeps the one that saw its first
    // point (in input order), which still faces the surface it sampled.
    if (cloud.has_stations()) out.station_ids.push_back(cloud.station_ids[keyed[begin].second]);
    begin = end;
  }
  return out;
}

}  // namespace pb
