#include "stages/geometry/core/point_cloud.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace pb {

std::array<double, 3> Bounds::center_m() const {
  if (empty()) return {0, 0, 0};
  return {0.5 * (min_m[0] + max_m[0]), 0.5 * (min_m[1] + max_m[1]), 0.5 * (min_m[2] + max_m[2])};
}

std::array<double, 3> Bounds::extent_m() const {
  if (empty()) return {0, 0, 0};
  return {max_m[0] - min_m[0], max_m[1] - min_m[1], max_m[2] - min_m[2]};
}

Bounds BoundsOf(std::span<const float> positions_xyz) {
  assert(positions_xyz.size() % 3 == 0);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Bounds bounds{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}};
  for (size_t i = 0; i + 2 < positions_xyz.size(); i += 3) {
    for (int axis = 0; axis < 3; ++axis) {
      const double value = positions_xyz[i + axis];
      bounds.min_m[axis] = std::min(bounds.min_m[axis], value);
      bounds.max_m[axis] = std::max(bounds.max_m[axis], value);
    }
  }
  return bounds;
}

Bounds LocalBounds(const PointCloud& cloud) { return BoundsOf(cloud.positions); }

Bounds AbsoluteBounds(const PointCloud& cloud) {
  Bounds bounds = LocalBounds(cloud);
  if (bounds.empty()) return bounds;
  for (int axis = 0; axis < 3; ++axis) {
    bounds.min_m[axis] += cloud.origin[axis];
    bounds.max_m[axis] += cloud.origin[axis];
  }
  return bounds;
}

Bounds RobustLocalBounds(const PointCloud& cloud, double fraction) {
  Bounds bounds;
  bounds.min_m.fill(std::numeric_limits<double>::infinity());
  bounds.max_m.fill(-std::numeric_limits<double>::infinity());
  const size_t n = cloud.size();
  if (n == 0) return bounds;
  const size_t step = std::max<size_t>(1, n / 1000000);
  std::vector<float> values;
  values.reserve(n / step + 1);
  auto quantile = [&values](double q) {
    const size_t k = std::min(values.size() - 1, size_t(q * double(values.size() - 1) + 0.5));
    std::nth_element(values.begin(), values.begin() + k, values.end());
    return double(values[k]);
  };
  for (int axis = 0; axis < 3; ++axis) {
    values.clear();
    for (size_t i = 0; i < n; i += step) values.push_back(cloud.positions[3 * i + axis]);
    bounds.min_m[axis] = quantile(fraction);
    bounds.max_m[axis] = quantile(1.0 - fraction);
  }
  return bounds;
}

void ConvertToMeters(double meters_per_unit, PointCloud* cloud) {
  if (meters_per_unit == 1.0) return;
  for (double& c : cloud->origin) c *= meters_per_unit;
  for (float& c : cloud->positions) c = static_cast<float>(c * meters_per_unit);
  for (std::array<double, 3>& station : cloud->stations)
    for (double& c : station) c *= meters_per_unit;
}

Status CheckFinitePositions(const PointCloud& cloud, std::string_view what) {
  for (size_t i = 0; i < cloud.positions.size(); ++i) {
    if (!std::isfinite(cloud.positions[i])) {
      return Status::Invalid(std::string(what) + ": point " + std::to_string(i / 3) +
                             " has a non-finite coordinate");
    }
  }
  return Status::Ok();
}

Status Validate(const PointCloud& cloud) {
  if (cloud.positions.size() % 3 != 0) {
    return Status::Invalid("point cloud: positions hold " + std::to_string(cloud.positions.size()) +
                           " floats, not a multiple of 3");
  }
  const size_t n = cloud.size();
  if (cloud.has_normals() && cloud.normals.size() != 3 * n) {
    return Status::Invalid("point cloud: " + std::to_string(cloud.normals.size()) +
                           " normal floats for " + std::to_string(n) + " points (expected 3 per point)");
  }
  if (cloud.has_colors() && cloud.colors.size() != 3 * n) {
    return Status::Invalid("point cloud: " + std::to_string(cloud.colors.size()) +
                           " color bytes for " + std::to_string(n) + " points (expected 3 per point)");
  }
  if (cloud.has_intensities() && cloud.intensities.size() != n) {
    return Status::Invalid("point cloud: " + std::to_string(cloud.intensities.size()) +
                           " intensities for " + std::to_string(n) + " points");
  }
  if (cloud.has_stations()) {
    if (cloud.station_ids.size() != n)
      return Status::Invalid("point cloud: " + std::to_string(cloud.station_ids.size()) +
                             " station ids for " + std::to_string(n) + " points");
    for (size_t i = 0; i < n; ++i)
      if (cloud.station_ids[i] >= cloud.stations.size())
        return Status::Invalid("point cloud: point " + std::to_string(i) + " names station " +
                               std::to_string(cloud.station_ids[i]) + " of " +
                               std::to_string(cloud.stations.size()));
  }
  return Status::Ok();
}

PointCloud SelectPoints(const PointCloud& cloud, std::span<const uint32_t> indices) {
  PointCloud out;
  out.origin = cloud.origin;
  out.stations = cloud.stations;
  const size_t m = indices.size();
  out.positions.resize(3 * m);
  if (cloud.has_normals()) out.normals.resize(3 * m);
  if (cloud.has_colors()) out.colors.resize(3 * m);
  if (cloud.has_intensities()) out.intensities.resize(m);
  if (cloud.has_stations()) out.station_ids.resize(m);
  for (size_t j = 0; j < m; ++j) {
    const size_t i = indices[j];
    assert(i < cloud.size());
    std::copy_n(&cloud.positions[3 * i], 3, &out.positions[3 * j]);
    if (cloud.has_normals()) std::copy_n(&cloud.normals[3 * i], 3, &out.normals[3 * j]);
    if (cloud.has_colors()) std::copy_n(&cloud.colors[3 * i], 3, &out.colors[3 * j]);
    if (cloud.has_intensities()) out.intensities[j] = cloud.intensities[i];
    if (cloud.has_stations()) out.station_ids[j] = cloud.station_ids[i];
  }
  return out;
}

}  // namespace pb
