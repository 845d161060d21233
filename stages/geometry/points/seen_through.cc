// Points another station saw through (seen_through.h): per station a pyramid
// of nearest-range grids over its sphere of directions, read by every other
// station's points.
#include "stages/geometry/points/seen_through.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "stages/geometry/core/vec3.h"

namespace pb {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr float kEmpty = std::numeric_limits<float>::infinity();
// At most this many cells in a station's finest grid (64 MB of floats): a
// denser station gets larger cells, which only decides fewer cones.
constexpr size_t kMaxCells = size_t(1) << 24;
// A cone wider than this (half angle) is not read: it would say little.
constexpr double kMaxHalfAngle = 20.0 * kPi / 180.0;
// A cone is read on the finest grid where it spans at most this many cells
// either side of its direction's cell.
constexpr int kMaxWindow = 3;
// Nor a cone this close to a pole of the grid.
constexpr double kPoleMargin = 5.0 * kPi / 180.0;

// The direction of `v` (not zero): longitude in [0, 2 pi), latitude in
// [-pi/2, pi/2].
struct Direction {
  double longitude;
  double latitude;
};

Direction DirectionOf(const std::array<double, 3>& v, double length) {
  double longitude = std::atan2(v[1], v[0]);
  if (longitude < 0) longitude += 2 * kPi;
  if (!(longitude < 2 * kPi)) longitude = 0;
  return {longitude, std::asin(std::clamp(v[2] / length, -1.0, 1.0))};
}

// One station's grids: level 0 has cells of `cell` radians; level L + 1 has
// cells of 2 x 2 level-L cells, each the nearest range of its children
// (kEmpty where none of them holds a sample).
class RangePyramid {
 public:
  RangePyramid(double cell, std::span<const Direction> directions, std::span<const float> ranges) : cell_(cell) {
    int columns = int(std::ceil(2 * kPi / cell)), rows = int(std::ceil(kPi / cell));
    levels_.push_back({columns, rows, std::vector<float>(size_t(columns) * size_t(rows), kEmpty)});
    Level& base = levels_.back();
    for (size_t i = 0; i < directions.size(); ++i) {
      const int column = std::min(columns - 1, int(directions[i].longitude / cell));
      const int row = std::clamp(int((directions[i].latitude + kPi / 2) / cell), 0, rows - 1);
      float& nearest = base.nearest[size_t(row) * size_t(columns) + size_t(column)];
      nearest = std::min(nearest, ranges[i]);
    }
    while (columns > 3 && rows > 3 && cell * double(1 << (levels_.size() - 1)) < kMaxHalfAngle) {
      const Level& fine = levels_.back();
      Level coarse{(fine.columns + 1) / 2, (fine.rows + 1) / 2, {}};
      coarse.nearest.assign(size_t(coarse.columns) * size_t(coarse.rows), kEmpty);
      for (int row = 0; row < fine.rows; ++row)
        for (int column = 0; column < fine.columns; ++column) {
          float& nearest = coarse.nearest[size_t(row / 2) * size_t(coarse.columns) + size_t(column / 2)];
          nearest = std::min(nearest, fine.nearest[size_t(row) * size_t(fine.columns) + size_t(column)]);
        }
      columns = coarse.columns;
      rows = coarse.rows;
      levels_.push_back(std::move(coarse));
    }
  }

  // True when every cell of the window around `direction` on the finest
  // level where the window is at most kMaxWindow cells either side of the
  // direction's cell and reaches `half_angle` from it (in latitude, and in
  // longitude at the cone's widest) holds a sample and the nearest is
  // farther than `beyond`. False when some cell is empty, the cone is too
  // wide or near a pole (undecided) or a sample lies within `beyond`.
  // `decided` is set when every cell held a sample.
  bool SawBeyond(const Direction& direction, double half_angle, double beyond, bool* decided) const {
    *decided = false;
    const double widest = std::abs(direction.latitude) + half_angle;
    if (half_angle > kMaxHalfAngle || widest > kPi / 2 - kPoleMargin) return false;
    const double across = half_angle / std::cos(widest);  // in longitude
    for (size_t level = 0; level < levels_.size(); ++level) {
      const double cell = cell_ * double(size_t(1) << level);
      const int rows_out = std::max(1, int(std::ceil(half_angle / cell)));
      const int columns_out = std::max(1, int(std::ceil(across / cell)));
      if (rows_out > kMaxWindow || columns_out > kMaxWindow) continue;
      const Level& grid = levels_[level];
      const int column = std::min(grid.columns - 1, int(direction.longitude / cell));
      const int row = int((direction.latitude + kPi / 2) / cell);
      if (row < rows_out || row + rows_out >= grid.rows || 2 * columns_out + 1 > grid.columns) return false;
      float nearest = kEmpty;
      for (int dr = -rows_out; dr <= rows_out; ++dr)
        for (int dc = -columns_out; dc <= columns_out; ++dc) {
          const int c = (column + dc + grid.columns) % grid.columns;
          const float range = grid.nearest[size_t(row + dr) * size_t(grid.columns) + size_t(c)];
          if (range == kEmpty) return false;
          nearest = std::min(nearest, range);
        }
      *decided = true;
      return double(nearest) > beyond;
    }
    return false;
  }

 private:
  struct Level {
    int columns;
    int rows;
    std::vector<float> nearest;
  };
  double cell_;
  std::vector<Level> levels_;
};

// False when no cone of station s around `v` (a point's offset from s, at
// `distance`, with its ball's `margin`) can be seen beyond, so that
// RangePyramid::SawBeyond would say false without reading it:
//  - no sample of s is farther than the ball (`reach`: the farthest one's
//    range);
//  - or the point lies farther from the box of s and its samples
//    [box_lo, box_hi] than any point SawBeyond accepts can. For one it
//    accepts, the cell of its direction u on the level read holds a sample q
//    beyond the ball; the point at `distance` along q's direction lies on
//    the segment from s to q, so in the box, and within `distance` times the
//    angle between u and q's direction of the point. That angle is at most
//    2 c for a cell of c radians (latitude and longitude each span c, and a
//    radian of longitude is at most one of arc). The level read has c =
//    `cell` (level 0), or else the level below spanned more than 3 cells of
//    the cone's width in longitude, `across` = half / cos(widest latitude)
//    <= 11.5 half (SawBeyond reads no cone reaching past 85 degrees), so
//    c < 2 across / 3 <= 7.7 half; half = asin(margin / distance) <=
//    1.021 margin / distance (SawBeyond reads no cone wider than 20 degrees).
//    So the point lies within max(2 cell distance, 15.7 margin) of the box.
bool WithinReach(const std::array<double, 3>& v, double distance, double margin, double reach,
                 const std::array<double, 3>& box_lo, const std::array<double, 3>& box_hi, double cell) {
  if (!(distance + margin < reach)) return false;
  const double slack = std::max(2 * cell * distance, 16 * margin) + 1e-6 * (distance + 1);
  for (size_t a = 0; a < 3; ++a)
    if (v[a] < box_lo[a] - slack || v[a] > box_hi[a] + slack) return false;
  return true;
}

}  // namespace

Expected<std::vector<uint8_t>> SeenThroughPoints(const PointCloud& cloud, std::span<const float> spacing,
                                                 const SeenThroughOptions& options, SeenThroughReport* report) {
  if (!(options.margin_spacings >= 0) || !std::isfinite(options.margin_spacings))
    return Status::Invalid("points seen through: margin_spacings must be >= 0");
  if (!(options.margin_range >= 0) || !std::isfinite(options.margin_range))
    return Status::Invalid("points seen through: margin_range must be >= 0");
  PB_RETURN_IF_ERROR(Validate(cloud));
  PB_RETURN_IF_ERROR(CheckFinitePositions(cloud, "points seen through"));
  const size_t n = cloud.size();
  if (spacing.size() != n)
    return Status::Invalid("points seen through: " + std::to_string(spacing.size()) + " spacings for " +
                           std::to_string(n) + " points");
  SeenThroughReport local;
  std::vector<uint8_t> seen(n, 0);
  if (!cloud.has_stations() || cloud.stations.size() < 2) {
    if (report) *report = local;
    return seen;
  }
  const size_t station_count = cloud.stations.size();
  std::vector<std::vector<uint32_t>> members(station_count);
  for (size_t i = 0; i < n; ++i) {
    members[cloud.station_ids[i]].push_back(uint32_t(i));  // < station_count: Validate
  }
  auto offset = [&](size_t i, const vec3::V3& from) {
    return vec3::Sub({cloud.positions[i * 3], cloud.positions[i * 3 + 1], cloud.positions[i * 3 + 2]}, from);
  };
  std::vector<uint8_t> votes(n, 0);
  for (size_t s = 0; s < station_count; ++s) {
    if (options.progress && s > 0) options.progress(double(s) / double(station_count));
    if (members[s].size() < std::max<size_t>(options.min_station_points, 1)) continue;
    const std::array<double, 3> at = {cloud.stations[s][0] - cloud.origin[0], cloud.stations[s][1] - cloud.origin[1],
                                      cloud.stations[s][2] - cloud.origin[2]};
    // The station's own samples: direction, range, angular step.
    std::vector<Direction> directions;
    std::vector<float> ranges;
    std::vector<float> steps;
    directions.reserve(members[s].size());
    // Its reach: the farthest sample's range (as stored, a float), and the
    // box of the station and its samples, relative to the station.
    double reach = 0;
    std::array<double, 3> box_lo = {0, 0, 0}, box_hi = {0, 0, 0};
    for (uint32_t i : members[s]) {
      const std::array<double, 3> v = offset(i, at);
      const double range = vec3::Norm(v);
      if (!(range > 0)) continue;
      directions.push_back(DirectionOf(v, range));
      ranges.push_back(float(range));
      steps.push_back(float(double(spacing[i]) / range));
      reach = std::max(reach, double(ranges.back()));
      for (int a = 0; a < 3; ++a) {
        box_lo[size_t(a)] = std::min(box_lo[size_t(a)], v[size_t(a)]);
        box_hi[size_t(a)] = std::max(box_hi[size_t(a)], v[size_t(a)]);
      }
    }
    if (steps.size() < std::max<size_t>(options.min_station_points, 1)) continue;
    std::nth_element(steps.begin(), steps.begin() + ptrdiff_t(steps.size() / 2), steps.end());
    double cell = 2.0 * double(steps[steps.size() / 2]);
    if (!(cell > 0)) continue;
    while ((2 * kPi / cell) * (kPi / cell) > double(kMaxCells)) cell *= 1.25;
    const RangePyramid pyramid(cell, directions, ranges);
    ++local.stations;
    std::atomic<size_t> cones_read{0};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& range) {
      size_t read_here = 0;
      for (size_t i = range.begin(); i < range.end(); ++i) {
        if (cloud.station_ids[i] == s) continue;
        const std::array<double, 3> v = offset(i, at);
        const double distance = vec3::Norm(v);
        const double margin = std::max(options.margin_spacings * double(spacing[i]), options.margin_range * distance);
        if (!(distance > 2 * margin)) continue;  // the ball nearly holds the station
        if (options.within_reach_only && !WithinReach(v, distance, margin, reach, box_lo, box_hi, cell)) continue;
        ++read_here;
        bool decided = false;
        // Bit 0: seen through; bit 1: some station read its cone.
        if (pyramid.SawBeyond(DirectionOf(v, distance), std::asin(margin / distance), distance + margin, &decided))
          votes[i] |= 1;
        if (decided) votes[i] |= 2;
      }
      cones_read += read_here;
    });
    local.cones_read += cones_read;
  }
  if (options.progress) options.progress(1.0);
  for (size_t i = 0; i < n; ++i) {
    seen[i] = votes[i] & 1;
    local.seen_through += seen[i];
    local.decided += (votes[i] >> 1) & 1;
  }
  if (report) *report = local;
  return seen;
}

}  // namespace pb
