// Points another station saw through: transients of a multi-station laser
// scan. A person walking past one station, a bird, a vehicle, a door that
// moved, a clump of returns off dust: one station recorded them, and every
// other station that looked at the same place recorded what lies behind.
// They are as dense as the surface, so neither the stray clusters nor the
// points in the air (strays.h) take them, and every mesh keeps them as blobs
// (docs/real-scans.md, "Floaters").
//
// Definition: a point p of station t is seen through when some other
// station s looked at a ball of radius m around p and saw only beyond it:
// every sample of s in the directions of the ball (a cone from s) lies
// farther from s than |p - s| + m, and each of those directions holds at
// least one sample of s. m = max(`margin_spacings` x p's local spacing,
// `margin_range` x |p - s|): the stations' registration error, the noise and
// a silhouette seen a little sideways from another station stay inside the
// ball. A surface that s saw is never seen through (s's samples of it lie
// within the ball's cone at the ball's range or nearer), nor is a point that
// s could not see (something nearer hides it). A direction where s has no
// sample (sky, a dark surface that returned nothing, beyond its field of
// view) tells nothing, and a point whose cone holds one is not decided.
//
// Each station's samples go into a grid over its sphere of directions
// (longitude about the cloud's z axis, latitude), cells twice its median
// angular step, each keeping its nearest sample's range, and coarser grids
// of 2 x 2 cells each; a ball's cone is read as the cells around its
// direction's cell, as many either side as reach its half angle (at least
// one), on the finest grid where that is at most 3: the cells read cover the
// cone and at most one cell more either side. A cone within 5 degrees of a
// pole of the grid is not decided.
//
// Limits: a wire thinner than another station's sample step where that
// station looks at it may be missed by every one of its rays and so is seen
// through; a part that moved between two stations' scans (a door, a chair)
// is seen through in both places by the other, which is right for the place
// it left and drops the place it is in where only the one scan saw it.
// A cloud without stations, or with one, has no point seen through.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

struct SeenThroughOptions {
  double margin_spacings = 3.0;  // >= 0: the ball's radius, at least this many local spacings of the point
  double margin_range = 0.01;    // >= 0: ... and at least this fraction of its distance to the other station
  size_t min_station_points = 100;  // a station with fewer samples sees through nothing
  // A station reads only the points within its reach: nearer than its
  // farthest sample, and near the box of its samples (how near, the .cc
  // works out from how the cones are read). No other point can have every
  // sample of its cone beyond it, so the same points are found either way;
  // false reads every point's cone (bench/seen_through_bench compares the
  // two on a site of many rooms).
  bool within_reach_only = true;
  // Called from the calling thread after each station, with the fraction of
  // the stations done, in [0, 1].
  std::function<void(double fraction)> progress;
};

struct SeenThroughReport {
  size_t seen_through = 0;  // points seen through by another station
  size_t stations = 0;      // stations whose samples were looked through (with min_station_points)
  size_t decided = 0;       // points whose cone some other station's samples answered (every cell sampled;
                            // with within_reach_only, of the stations that reach past the point)
  size_t cones_read = 0;    // (point, station) pairs whose cone was read
};

// Per point of `cloud`, 1 when another station saw through it (above), else
// 0. `spacing`: one local spacing per point (spacing.h, LocalSpacing), in
// meters. Status::Invalid for options out of range, a `spacing` of another
// size, a station id past the stations or a non-finite coordinate.
// Parallel over the points (TBB: run inside a task_arena to limit threads);
// the result does not depend on the thread count.
Expected<std::vector<uint8_t>> SeenThroughPoints(const PointCloud& cloud, std::span<const float> spacing,
                                                 const SeenThroughOptions& options = {},
                                                 SeenThroughReport* report = nullptr);

}  // namespace pb
