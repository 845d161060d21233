// Normal estimation for point clouds: k-nearest-neighbour PCA plus a sign
// (orientation) step.
//
// The unoriented normal of point i is the eigenvector of the smallest
// eigenvalue of the 3x3 covariance of its k nearest points (the point itself
// included, as PCL's NormalEstimation does), a unit vector in the cloud's
// frame. Coincident neighbourhoods (zero covariance) get an arbitrary but
// deterministic unit axis.
//
// Orientation picks each normal's sign:
//   kStations:  toward the scanner that saw the point, dot(station - p, n) > 0
//               (stations are absolute; p = origin + position). Needs
//               station_ids and stations.
//   kPropagate: Hoppe et al. 1992: a minimum spanning tree over the kNN graph
//               (edge weight 1 - |n_i . n_j| quantized to 1/256, Prim's
//               algorithm; each point's 8 nearest as edges) grown from a
//               seed whose normal points away from the cloud's centroid; each
//               point takes its tree parent's side. Disconnected parts are
//               seeded the same way. Right for closed objects (a sphere gets
//               outward normals). An interior scanned from inside and
//               merged without its stations (a room as one PLY) would come
//               out inside-out, so `interior` decides the sides: kAuto
//               looks for the free space the scan encloses
//               (enclosure.h: a room's, not an object's inside); every point
//               with one side in it and the other not (probes 1.5 voxels
//               ahead and behind: a wall's, a floor's, a table's in the
//               room) faces it, and the propagation grows from those points
//               to the rest (propagation alone is unreliable across the
//               sharp creases where furniture meets a floor). Without an
//               enclosed space and no lost station found (find_station),
//               the space the scan nearly encloses (enclosure.h's
//               FindOpen: a corridor open at its ends, a room with a wide
//               doorway, a cell) is faced the same way. Without either
//               enclosed space (an object), rays over a voxel grid decide
//               first the points open on one side and closed on the other
//               (of 48 directions, those within 60 degrees of either
//               side: a share at least 0.75 larger escapes on one), at
//               most 100,000, each kept when 3 of its 8 nearest probed
//               points agree; a plinth on its ground otherwise faced in
//               through it. kNo keeps the
//               outward seeds (version 2's rule); kYes seeds inward, toward
//               the centroid, for an interior the enclosure test misses (a
//               room open on a side wider than 1.5 m).
//   kInput:     the side of the normal the cloud came with (a file's own
//               normals: a scanner's or a fusion's software knew the sensor;
//               PCL and Open3D write oriented ones), dot(n_in, n) >= 0. Needs
//               every point to have a finite, non-zero input normal.
//   kAuto:      kStations when the cloud has stations, else kInput when every
//               point has a usable input normal whose sides agree between
//               neighbours (NormalReport::input_sides_disagree at most 5 %),
//               else kPropagate.
//   kNone:      the sign the eigen solver happens to produce.
//
// Output is identical whatever the thread count. Cost: one kNN query per
// point (see knn.h, ~21 bytes per point for the index) plus, for
// propagation, 32 bytes per point of neighbour graph and a sequential pass.
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <string>

#include "base/status.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

enum class NormalOrientation { kAuto, kStations, kInput, kPropagate, kNone };

// Whether kPropagate treats the scan as an interior seen from inside.
enum class NormalInterior { kAuto, kYes, kNo };

// Whose code finds the unoriented normals (the orientation step is always
// ours, so the three differ only in the PCA): ours (above), PCL 1.13's
// NormalEstimationOMP (pointbake-pcl.so) or Open3D 0.16's
// PointCloud::EstimateNormals with a k-NN search (pointbake-poisson-open3d.so),
// each loaded on first use. Both libraries take the same k nearest points,
// the point included; a normal they cannot fit becomes +z. Their output is
// float-rounding close to ours, not bit-identical.
enum class NormalImplementation { kOwn, kPcl, kOpen3d };

struct NormalOptions {
  NormalImplementation implementation = NormalImplementation::kOwn;
  int k = 16;  // points in each PCA neighbourhood, the point included; 3..100
  // kOwn only. A point whose k nearest lie closer together than a typical
  // point's (the cloud's median distance to the k-th nearest) takes its
  // nearest points out to that distance instead: as many as the density of
  // its k nearest puts within it, at most 32k (knn.h, WidenNeighborhood), so
  // that no neighbourhood is smaller than a typical one. Where a scanner's
  // lines converge (the ceiling above a station: lines a fraction of a
  // millimetre apart, their points a centimetre apart along them) the k
  // nearest lie on one short arc across the lines, the range noise along
  // the ray is as large as the arc, and the fitted plane stands on edge; the
  // typical neighbourhood spans several lines. false: every neighbourhood is the k
  // nearest (points.normals version 4).
  bool widen_dense = true;
  NormalOrientation orientation = NormalOrientation::kAuto;
  NormalInterior interior = NormalInterior::kAuto;  // kPropagate only
  // kAuto resolved to kPropagate with interior kAuto and no enclosed space
  // found (at least kLeastPointsForStation points): look for where one
  // scanner would have stood (lost_station.h, its axis the cloud's x, y or
  // z); found, every normal faces it, as with a station the file gave. One
  // scan exported without its position (a PLY of x, y, z and colour) is
  // otherwise oriented by propagation, which picks a side per part: half
  // the pump's normals faced away from its scanner.
  bool find_station = true;
  int threads = 0;  // worker threads; 0 = TBB's default (all cores)
  // Called from the calling thread with the fraction done, in [0, 1].
  std::function<void(double fraction)> progress;
};

struct NormalReport {
  size_t points = 0;
  size_t flipped = 0;  // normals whose sign orientation reversed
  // widen_dense: the radius neighbourhoods were widened to (0: none), and
  // the points that gained neighbours by it.
  double widen_to_m = 0.0;
  size_t widened = 0;
  NormalOrientation orientation_used = NormalOrientation::kNone;  // kAuto resolved
  // kPropagate with interior kAuto: the enclosed space found (0: none), and
  // the points oriented to face it (the rest by propagation).
  // enclosure_open: found by EnclosedSpace::FindOpen (no room closed in,
  // no station found), a room open on a side or small.
  double enclosed_volume_m3 = 0.0;
  bool enclosure_open = false;
  size_t facing_enclosure = 0;
  // kPropagate without enclosed space (an object): the points whose side
  // rays decided (the rest by propagation from them).
  size_t facing_rays = 0;
  // kAuto with the file's normals, every one usable (input_sides_checked):
  // the share of neighbouring pairs on one smooth surface whose file sides
  // disagree; over kMaxInputSidesDisagree the file's sides were not
  // oriented (a tool's "preferred orientation", random signs) and
  // propagation orients instead (orientation_used says so).
  bool input_sides_checked = false;
  double input_sides_disagree = 0.0;
  // find_station: whether the search ran, what it found (station_found, the
  // place, absolute, the cloud's units) and its verdict and figures.
  bool station_searched = false;
  bool station_found = false;
  std::array<double, 3> station{};
  std::string station_verdict;
};

inline constexpr size_t kLeastPointsForStation = 1000;

inline constexpr double kMaxInputSidesDisagree = 0.05;

// Replaces cloud.normals with estimated, oriented unit normals (3 floats per
// point). Status::Invalid if k is outside 3..100, the cloud has fewer than 3
// points or a non-finite coordinate, kStations is asked for a cloud without
// stations, or (from Validate) a station id is out of range;
// Status::Unsupported if the implementation's module is not in this build.
Status EstimateNormals(PointCloud& cloud, const NormalOptions& options, NormalReport* report = nullptr);

// Eigen-decomposition of the symmetric 3x3 matrix `a` (row-major, only
// symmetric input is meaningful) by cyclic Jacobi rotations: returns the unit
// eigenvector of the smallest eigenvalue in `vector`, and that eigenvalue.
double SmallestEigenvector(const double a[9], double vector[3]);

// The same unit eigenvector for a symmetric positive semi-definite `a` (a
// covariance), 4x faster: closed-form eigenvalues and a cross product, the
// same direction as SmallestEigenvector to well below float resolution when
// the two smallest eigenvalues differ by at least 1/1000 of the spread;
// otherwise (and for a zero matrix) it is SmallestEigenvector. The sign is
// arbitrary.
void PlaneNormal(const double a[9], double vector[3]);

}  // namespace pb
