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
// A room open on a side wider than 2 * gap_m (a corridor open at both
// ends, a chapel whose doorway or windows the scan left open), or smaller
// than 2 * gap_m plus about 1 m across (a cell, a sacristy), encloses
// nothing so. FindOpen looks for such a space by what a person standing in
// it sees: occupancy is grown by open_gap_m only (half the gap: openings
// are not closed, so they need not be), and a free voxel counts when at least
// min_surrounded of the 26 lattice directions from it (to its neighbours and
// on across the grid) meet an occupied voxel before the grid's border; each
// 6-connected part of such voxels holding at least min_open_volume_m3
// counts, unless it is a cup, and reaches back to the scan as above (the
// outside being the free voxels from which more lines of sight leave). In
// the middle of a corridor 1.8 m wide only the two along it leave (24 of
// 26); beside an object, or in the corner of two walls on a yard open to the
// sky, at least 7 do (the sky's octant). The inside of an object resting on
// the ground is surrounded too (only the few directions through its
// unscanned footprint leave: a 3 m cube on paving keeps 7 m3), but it is a
// cup: along one axis the line straight out leaves from at least half of
// the part's voxels, and the other way from at most a tenth. A room's door
// lets that line out from few voxels; a corridor's ends let it out both
// ways; a passage open at one end only (a dead end, an apse) is a cup too
// and is not found. An object closed all round, its underside too, is
// found only when more than about 2.3 m across.
//
// Cost: at most 256^3 voxels (16 MiB per byte of them; about 6 bytes each),
// a few passes over them; FindOpen about 9 bytes each and 26 more passes
// (its voxels are half the size, so its grid reaches the 256 a side past
// 24 m instead of 48 m).
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
  // FindOpen:
  double open_gap_m = 0.375;        // occupancy grown by this only
  double min_surrounded = 0.85;     // share of the 26 directions meeting the scan
  double min_open_volume_m3 = 1.5;  // of a part, after the growth by open_gap_m
};

class EnclosedSpace {
 public:
  // Finds the enclosed space of `cloud` (meters; positions relative to its
  // origin, as all queries below). Status::Invalid when the cloud is empty,
  // has a non-finite coordinate or an option is not positive.
  static Expected<EnclosedSpace> Find(const PointCloud& cloud, const EnclosureOptions& options = {});
  // Finds the space a scan nearly encloses, open on a side or small (see
  // above); for a scan Find finds nothing in. The same errors.
  static Expected<EnclosedSpace> FindOpen(const PointCloud& cloud, const EnclosureOptions& options = {});

  bool empty() const { return volume_m3_ == 0.0; }
  // Found by FindOpen: surrounded by the scan, not closed in.
  bool open() const { return open_; }
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
  void Finish(std::vector<uint8_t>& cells, const std::vector<uint8_t>& scanned, int outside_radius);

  bool open_ = false;
  std::array<double, 3> min_{};  // the grid's corner, relative to the origin
  std::array<int, 3> dims_{};
  double voxel_m_ = 0.0;
  double volume_m3_ = 0.0;
  std::array<double, 3> deepest_{};
  std::vector<uint8_t> inside_;  // dims_ voxels, x fastest: 1 = in the space
};

}  // namespace pb
