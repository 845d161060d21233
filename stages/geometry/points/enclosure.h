// Enclosed space: the free space a scan closes around, as a room's walls,
// floor and ceiling do, found on a voxel grid. It tells an interior scanned
// from inside (a room exported as one merged cloud, with no scanner
// stations) from an object scanned from outside, which normal orientation
// and the scene survey cannot otherwise tell apart.
//
// The grid covers the points' robust box (per axis the 0.5th to 99.5th
// percentile, padded); its voxel is gap_m / 4, or coarser so that the
// longest side has at most 256 voxels. Every voxel holding a point is
// occupied; occupancy is grown by gap_m (a cube of ceil(gap_m / voxel)
// voxels each way), which closes openings up to 2 * gap_m wide (a door, a
// window, a scan's gaps). The free voxels the grid's border cannot reach
// through 6-connected free voxels are enclosed; each 6-connected part of
// them holding at least min_volume_m3 counts. So the interior of a room at
// least about 2 * gap_m plus 1 m across in every direction is found, while
// an object's inside, which its own surface, grown by gap_m, fills, is not
// (a statue would need a hollow more than 1.5 m across everywhere). The space
// reported reaches back to the scan: every voxel without a point that the
// enclosed parts reach without crossing a voxel with a point or entering the
// outside grown back by the gap and a voxel. So it fills the room up to its
// walls and furniture, also where they stand closer than 2 * gap_m, but not
// a closed object's inside (a table's, if its surface has no gap of a
// voxel) nor the outside through a door.
//
// Cost: at most 256^3 voxels (16 MiB per byte of them; about 6 bytes each),
// a few passes over them.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

struct EnclosureOptions {
  double gap_m = 0.75;         // openings up to twice this wide are closed
  double min_volume_m3 = 1.0;  // of an enclosed part, after the growth by gap_m
  int max_voxels_per_side = 256;
};

class EnclosedSpace {
 public:
  // Finds the enclosed space of `cloud` (meters; positions relative to its
  // origin, as all queries below). Status::Invalid when the cloud is empty,
  // has a non-finite coordinate or an option is not positive.
  static Expected<EnclosedSpace> Find(const PointCloud& cloud, const EnclosureOptions& options = {});

  bool empty() const { return volume_m3_ == 0.0; }
  // Volume of the enclosed parts found, before growing them back to the scan.
  double volume_m3() const { return volume_m3_; }
  double voxel_m() const { return voxel_m_; }
  // Whether a point (relative to the cloud's origin) lies in the space (to a
  // voxel: the space can reach a voxel past the scan).
  bool Contains(const float p[3]) const;
  // The center of the enclosed voxel farthest (city-block) from everything
  // else, of several the one nearest their centroid, relative to the cloud's
  // origin: a place to stand in the room. Only when !empty().
  std::array<double, 3> Deepest() const { return deepest_; }

 private:
  std::array<double, 3> min_{};  // the grid's corner, relative to the origin
  std::array<int, 3> dims_{};
  double voxel_m_ = 0.0;
  double volume_m3_ = 0.0;
  std::array<double, 3> deepest_{};
  std::vector<uint8_t> inside_;  // dims_ voxels, x fastest: 1 = in the space
};

}  // namespace pb
