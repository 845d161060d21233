// Lines of sight of a scan: the segment from each point's station (the
// scanner that measured it) to the point. The scanner saw through every
// place such a segment crosses: free space, or a surface it saw behind.
// A patch that would put a surface there (a hole filled by mesh.decimate)
// hides what the scanner saw, and is invented surface however small.
//
// Queries count, for a triangle, the lines crossing it farther than a
// clearance before their point (seen through it) and those ending within
// the clearance of it (its own surface: a point a hair behind a patch over
// its own hole's rim is that surface, not seen through it). Per station, the points are
// binned by direction (azimuth x elevation cells of `cell_rad`, sorted), so
// a query tests only the points in the directions its triangle covers seen
// from that station.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

class LinesOfSight {
 public:
  // Needs a cloud with stations (PointCloud::has_stations); `frame_origin`
  // is the origin of the coordinates the queries give (a mesh's origin).
  // Status::Invalid without stations or with a non-finite coordinate.
  static Expected<LinesOfSight> Build(const PointCloud& points,
                                      const std::array<double, 3>& frame_origin,
                                      double cell_rad = 0.002);

  // The lines of sight through a triangle (corners a, b, c in the query
  // frame): `behind` crossing it at least `clearance_m` before their point
  // (the scanner saw past it), `near` ending within `clearance_m` of it
  // (its own surface). Lines whose point lies farther before the triangle
  // (the scanner saw something in front of it) are neither, and so is a
  // line at less than `min_angle_rad` to the triangle's plane: at a grazing
  // angle, noise of the point along the ray moves the crossing far.
  struct Counts {
    size_t behind = 0;
    size_t near = 0;
  };
  Counts Through(const std::array<double, 3>& a, const std::array<double, 3>& b,
                 const std::array<double, 3>& c, double clearance_m,
                 double min_angle_rad = 0.2) const;

  size_t size() const { return count_; }

 private:
  struct Station {
    std::array<double, 3> origin;  // in the query frame
    // Sorted cell keys (row * cols + col) and, aligned, each point's offset
    // from the station.
    std::vector<uint64_t> keys;
    std::vector<std::array<float, 3>> offsets;
  };
  double cell_ = 0.002;
  int64_t rows_ = 0, cols_ = 0;
  size_t count_ = 0;
  std::vector<Station> stations_;
};

}  // namespace pb
