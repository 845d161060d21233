// Lines of sight of a scan (see sight.h).
#include "stages/geometry/mesh/sight.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "stages/geometry/core/vec3.h"

namespace pb {
namespace {

using vec3::V3;
using vec3::Cross;
using vec3::Dot;
using vec3::Norm;
using vec3::Sub;

constexpr double kPi = std::numbers::pi;

// Azimuth in [-pi, pi] and elevation in [-pi/2, pi/2] of a direction.
std::array<double, 2> Angles(const V3& d) {
  const double horizontal = std::hypot(d[0], d[1]);
  return {std::atan2(d[1], d[0]), std::atan2(d[2], horizontal)};
}

// Moller-Trumbore: where the line station + t d meets the triangle
// corner0 + u e1 + v e2 (`to_station` = station - corner0), the t > 0 of
// the crossing, or 0 when it misses.
double CrossingAt(const V3& d, const V3& e1, const V3& e2, const V3& to_station) {
  const V3 p = Cross(d, e2);
  const double det = Dot(e1, p);
  if (std::abs(det) < 1e-300) return 0;
  const double inv = 1 / det;
  const double u = Dot(to_station, p) * inv;
  if (u < 0 || u > 1) return 0;
  const V3 q = Cross(to_station, e1);
  const double v = Dot(d, q) * inv;
  if (v < 0 || u + v > 1) return 0;
  return std::max(0.0, Dot(e2, q) * inv);
}

}  // namespace

Expected<LinesOfSight> LinesOfSight::Build(const PointCloud& points,
                                           const std::array<double, 3>& frame_origin,
                                           double cell_rad) {
  if (!points.has_stations() || points.stations.empty()) {
    return Status::Invalid("lines of sight: the cloud has no scanner stations");
  }
  if (!(cell_rad > 0 && cell_rad < 1)) {
    return Status::Invalid("lines of sight: cell_rad must be in (0, 1)");
  }
  LinesOfSight sight;
  sight.cell_ = cell_rad;
  sight.rows_ = static_cast<int64_t>(std::ceil(kPi / cell_rad)) + 1;
  sight.cols_ = static_cast<int64_t>(std::ceil(2 * kPi / cell_rad)) + 1;
  sight.count_ = points.size();
  sight.stations_.resize(points.stations.size());
  for (size_t s = 0; s < points.stations.size(); ++s) {
    for (int c = 0; c < 3; ++c) {
      sight.stations_[s].origin[c] = points.stations[s][c] - frame_origin[c];
      if (!std::isfinite(points.stations[s][c])) {
        return Status::Invalid("lines of sight: station " + std::to_string(s) +
                               " has a non-finite coordinate");
      }
    }
  }
  // Per station, (key, point) pairs sorted by key then point index.
  std::vector<std::vector<std::pair<uint64_t, uint32_t>>> binned(sight.stations_.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const uint16_t s = points.station_ids[i];
    if (s >= sight.stations_.size()) {
      return Status::Invalid("lines of sight: point " + std::to_string(i) + " names station " +
                             std::to_string(s) + " of " +
                             std::to_string(sight.stations_.size()));
    }
    V3 d;
    for (int c = 0; c < 3; ++c) {
      d[c] = points.positions[3 * i + c] + (points.origin[c] - frame_origin[c]) -
             sight.stations_[s].origin[c];
    }
    if (!std::isfinite(d[0] + d[1] + d[2])) {
      return Status::Invalid("lines of sight: point " + std::to_string(i) +
                             " has a non-finite coordinate");
    }
    if (Norm(d) == 0) continue;
    const auto angles = Angles(d);
    const int64_t row = std::clamp<int64_t>(
        static_cast<int64_t>((angles[1] + kPi / 2) / cell_rad), 0, sight.rows_ - 1);
    const int64_t col = std::clamp<int64_t>(
        static_cast<int64_t>((angles[0] + kPi) / cell_rad), 0, sight.cols_ - 1);
    binned[s].emplace_back(static_cast<uint64_t>(row * sight.cols_ + col),
                           static_cast<uint32_t>(i));
  }
  for (size_t s = 0; s < binned.size(); ++s) {
    std::sort(binned[s].begin(), binned[s].end());
    Station& station = sight.stations_[s];
    station.keys.reserve(binned[s].size());
    station.offsets.reserve(binned[s].size());
    for (const auto& [key, i] : binned[s]) {
      station.keys.push_back(key);
      std::array<float, 3> o;
      for (int c = 0; c < 3; ++c) {
        o[c] = static_cast<float>(points.positions[3 * size_t{i} + c] +
                                  (points.origin[c] - frame_origin[c]) - station.origin[c]);
      }
      station.offsets.push_back(o);
    }
  }
  return sight;
}

LinesOfSight::Counts LinesOfSight::Through(const std::array<double, 3>& a,
                                           const std::array<double, 3>& b,
                                           const std::array<double, 3>& c, double clearance_m,
                                           double min_angle_rad) const {
  Counts counts;
  const V3 normal = Cross(Sub(b, a), Sub(c, a));
  const double normal_length = Norm(normal);
  if (!(normal_length > 0)) return counts;
  const double min_sin = std::sin(min_angle_rad);
  for (const Station& station : stations_) {
    // The triangle's corners seen from the station.
    const V3 corners[3] = {Sub(a, station.origin), Sub(b, station.origin),
                           Sub(c, station.origin)};
    const V3 e1 = Sub(corners[1], corners[0]), e2 = Sub(corners[2], corners[0]);
    const V3 to_station = {-corners[0][0], -corners[0][1], -corners[0][2]};
    double el_lo = kPi, el_hi = -kPi;
    double az[3];
    for (int k = 0; k < 3; ++k) {
      const auto angles = Angles(corners[k]);
      az[k] = angles[0];
      el_lo = std::min(el_lo, angles[1]);
      el_hi = std::max(el_hi, angles[1]);
    }
    // Azimuth ranges: one, or two across the -pi / pi seam.
    std::vector<std::array<double, 2>> az_ranges;
    const double lo = std::min({az[0], az[1], az[2]}), hi = std::max({az[0], az[1], az[2]});
    if (hi - lo <= kPi) {
      az_ranges.push_back({lo, hi});
    } else {
      // Shift the negative ones by 2 pi: the span across the seam.
      double shifted_lo = kPi, shifted_hi = -kPi;
      for (double x : az) {
        const double y = x < 0 ? x + 2 * kPi : x;
        shifted_lo = std::min(shifted_lo, y);
        shifted_hi = std::max(shifted_hi, y);
      }
      az_ranges.push_back({shifted_lo, kPi});
      az_ranges.push_back({-kPi, shifted_hi - 2 * kPi});
    }
    // A cell of margin covers edges bulging between corners; a triangle
    // around the straight up or down direction reaches the pole between its
    // corners, and then spans every azimuth.
    if (CrossingAt({0, 0, 1}, e1, e2, to_station) > 0) el_hi = kPi / 2;
    if (CrossingAt({0, 0, -1}, e1, e2, to_station) > 0) el_lo = -kPi / 2;
    const int64_t row_lo = std::clamp<int64_t>(
        static_cast<int64_t>((el_lo + kPi / 2) / cell_) - 1, 0, rows_ - 1);
    const int64_t row_hi = std::clamp<int64_t>(
        static_cast<int64_t>((el_hi + kPi / 2) / cell_) + 1, 0, rows_ - 1);
    const bool polar = row_lo == 0 || row_hi == rows_ - 1;
    if (polar) az_ranges = {{-kPi, kPi}};  // every column, once
    for (const auto& range : az_ranges) {
      const int64_t col_lo = std::clamp<int64_t>(
          static_cast<int64_t>((range[0] + kPi) / cell_) - 1, 0, cols_ - 1);
      const int64_t col_hi = std::clamp<int64_t>(
          static_cast<int64_t>((range[1] + kPi) / cell_) + 1, 0, cols_ - 1);
      for (int64_t row = row_lo; row <= row_hi; ++row) {
        const uint64_t key_lo = static_cast<uint64_t>(row * cols_ + col_lo);
        const uint64_t key_hi = static_cast<uint64_t>(row * cols_ + col_hi);
        auto it = std::lower_bound(station.keys.begin(), station.keys.end(), key_lo);
        for (; it != station.keys.end() && *it <= key_hi; ++it) {
          const auto& o = station.offsets[static_cast<size_t>(it - station.keys.begin())];
          const V3 d = {o[0], o[1], o[2]};  // station -> point
          const double length = Norm(d);
          // The angle between the line and the plane: |d . n| / (|d| |n|).
          if (std::abs(Dot(d, normal)) < min_sin * length * normal_length) continue;
          // The crossing at t of the way from the station to the point.
          const double t = CrossingAt(d, e1, e2, to_station);
          if (t <= 0) continue;
          const double before_point = (1 - t) * length;  // < 0: the point lies before it
          if (before_point >= clearance_m) {
            ++counts.behind;
          } else if (before_point > -clearance_m) {
            ++counts.near;
          }
        }
      }
    }
  }
  return counts;
}

}  // namespace pb
