// A lost station: where the scanner stood, found in the points of one scan
// exported without its position (a PLY, XYZ or LAS of x, y, z and colour).
// Without it nothing says which side of an open surface was scanned: the
// normals' sides come out half wrong (the pump as such a file: 50.4 % face
// the scanner, 57 % of every view a face's back; docs/real-scans.md).
//
// One terrestrial scan has two properties no other cloud has, and the search
// asks for both:
//   * Its sampling follows from one place. A scanner sends a ray every
//     angular step in azimuth and in elevation, so a surface r away, at
//     incidence i, at elevation e (whose azimuth steps close up toward the
//     zenith), is sampled every  step * r * sqrt(cos e / cos i). The misfit
//     of a place is the median absolute deviation, over `sample` points
//     spread over the cloud, of  log(spacing) - log(r) + log(cos i) / 2 -
//     log(cos e) / 2  (spacing: LocalSpacing's formula at k = 16, its
//     distances taken in the tangent plane of the same neighbours' PCA,
//     which gives i too; e against `up`): about 0.03 for the synthetic
//     stations, 0.05 for the pump, 0.08-0.23 for clouds merged from several
//     stations, fused from a camera's trajectory or resampled.
//   * From there every point is seen, with nothing in front of it (the
//     scanner recorded the first surface along each ray). A line of sight
//     is walked over an occupancy grid of the points (at most `grid_side`
//     voxels along the box's longest side, none finer than the median
//     spacing; a lone occupied voxel, a return in the air, is left empty)
//     from the place to short of its point by max(3 voxels, 10 % of the
//     distance), as a grazing ray meets the voxels of its own floor only
//     that close to it. Below a floor the sampling fits as well as above
//     it, but the floor blocks every line of sight. Edges cost a few per
//     cent even at the right place (a ray passing a voxel of the pump's
//     pipes: 5 % at its station), so the bound is loose.
// The search: a lattice of `lattice`^3 places over the points' robust box
// padded by half its longest side each way (none in or beside an occupied
// voxel: no place to stand); of those whose lines of sight (512 of them) are
// blocked at most `max_blocked`, the best few by misfit start a pattern
// search on the misfit through places of the box still blocked at most
// that, halving its step down to a voxel.
//
// The place is declared only when all of these hold (else `found` is false
// and `verdict` says which failed):
//   * its misfit is at most `max_misfit`;
//   * it is unique: the pattern searches start from places farther apart
//     than `max_spread` of the extent, and every place they end at whose
//     misfit is within 1.25x of its and whose lines of sight are blocked at
//     most 3 points more lies within that of it (a lone wall's mirror image
//     does not);
//   * it stands in free space: its 8th nearest point at least
//     `min_clearance_m` away (a scanner records nothing within its minimum
//     range). The inside of a closed object also sees every point
//     unblocked;
//   * it explains at least `min_explained` of the spacing's own variation
//     (1 - misfit / the median absolute deviation of log(spacing)): a cloud
//     of nearly even spacing fits a far place about as well as any.
// Measured (docs/real-scans.md, "A lost station"): each synthetic station's
// scan alone found within 0.02-0.20 m of its station; the pump within 0.24 m
// (E57 read without its pose, and as a millimetre PLY); nothing found for
// the merged synthetic room, vault, tower, sculpture or facade, the bunny,
// the statue stand-in, the Kinect office or the living-room fusion.
// Cost: a k-NN index of the points (knn.h), a byte per voxel, and about
// lattice^3 * 512 + a few hundred * `sample` lines of sight: 1-3 s for
// 155,000 points on 2 cores, 4.3 s and 330 MB for 5 * 10^6 with the axis
// unknown (three searches, one grid).
#pragma once

#include <array>
#include <cstddef>
#include <string>

#include "base/status.h"
#include "stages/geometry/core/point_cloud.h"
#include "stages/geometry/points/knn.h"

namespace pb {

struct LostStationOptions {
  // The scanner's axis (need not be unit length); zero when not known: the
  // search then tries the cloud's z, y and x axes and keeps the best fit.
  std::array<double, 3> up = {0.0, 0.0, 1.0};
  size_t sample = 4096;       // points whose lines of sight are walked
  int grid_side = 200;        // voxels along the padded box's longest side, at most
  int lattice = 16;           // places per side of the first search
  double max_blocked = 0.15;  // share of lines of sight that may cross surface
  double max_misfit = 0.065;  // of the sampling against one scanner's
  double max_spread = 0.15;   // of the box's longest side: places nearly as good
  double min_clearance_m = 0.3;
  double min_explained = 0.7;  // of the spacing's variation, by the place
};

struct LostStation {
  bool found = false;
  std::array<double, 3> position{};  // absolute (the cloud's origin added), the cloud's units
  std::array<double, 3> up{};        // the scanner's axis taken (unit length)
  double misfit = 0.0;               // of the sampling against one scanner's there
  double blocked_share = 1.0;        // of the lines of sight from it that cross surface
  double spread = 0.0;               // farthest nearly-as-good place, over the box's longest side
  double clearance_m = 0.0;          // to its 8th nearest point
  double explained = 0.0;            // 1 - misfit / the spacing's own variation
  std::string verdict;   // what was found, or why nothing was: "the sampling is not one scanner's"
  std::string figures;   // the figures it rests on, for a log or a comment
};

// Searches `cloud` (meters; positions relative to its origin) for the one
// place a single scan would have been taken from. Status::Invalid when it
// has fewer than 100 points, a non-finite coordinate or an option out of
// range; a cloud that is not one station's gives found = false, not an error.
// `points_index`, when given, is KnnIndex::Build over cloud.positions (a
// caller that has one: points.normals), and is not built again.
Expected<LostStation> FindLostStation(const PointCloud& cloud, const LostStationOptions& options = {},
                                      const KnnIndex* points_index = nullptr);

}  // namespace pb
