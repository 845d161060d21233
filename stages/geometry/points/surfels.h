// Surfels of a scanned surface: per point, the plane the surface is in
// (normal) and, where the point lies on the border of what was scanned, the
// direction in that plane in which the scanned surface ends.
//
// Normal: the unit eigenvector of the smallest eigenvalue of the covariance
// of the point and its k nearest other points (normals.h's PlaneNormal; the
// sign is arbitrary: a surfel is two-sided).
//
// Surface variation (Pauly, Gross and Kobbelt 2002, "Efficient simplification
// of point-sampled surfaces", IEEE Visualization): the smallest eigenvalue
// over the sum of the three, 0 for a plane, 1/3 for points spread evenly in
// space; large where the neighbourhood is no plane (a corner, a thin part,
// or, in a one-station scan, a foreground edge whose neighbours include the
// surface behind it), where the fitted plane and the border test mean little.
//
// Border: the half-disc criterion of Bendels, Schnabel and Klein 2006
// ("Detecting holes in point set surfaces", WSCG): inside a sampled surface
// the k nearest neighbours surround the point and their centroid lies close
// to it; on the border they lie on one side, and the centroid shifts away
// from the border, by 4 r / (3 pi) = 0.42 r for a half disc of radius r. A
// point is on the border when the centroid of its k nearest other points,
// projected into its tangent plane, lies more than `border_shift` x r_k from
// it (r_k: the distance to the k-th neighbour); `outward` is then the unit
// vector opposite the shift, else 0. The default 0.25 sits between a half
// disc (0.42) and the centroid's scatter on a randomly sampled full disc
// (standard deviation 0.125 r per axis for k = 16), and a laser scan's
// near-regular grid scatters far less.
//
// On the surface (with `project`): the point moved onto the quadric height
// field z = a x^2 + b xy + c y^2 + d x + e y + f fitted by least squares to
// it and its k neighbours in the frame of their plane (origin at their
// centroid, z along the normal, coordinates scaled by r_k), at its own
// tangent coordinates: one step of the moving-least-squares projection
// (Alexa et al. 2003, "Computing and rendering point set surfaces", with the
// polynomial of Levin's MLS). It removes the range noise across the
// surface, about sqrt(6 / (k + 1)) of it is left, and, the quadric holding
// the curvature, moves a noise-free point by third-order terms only (a plane
// would pull a point on a curved part inward by r_k^2 / 4R). Where the
// normal equations are singular (points on a line) the point goes onto the
// plane; where the quadric would move it more than r_k it stays.
//
// Deterministic for any thread count (run inside a tbb::task_arena to limit
// threads).
#pragma once

#include <cstddef>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/point_cloud.h"
#include "stages/geometry/points/knn.h"

namespace pb {

struct SurfelOptions {
  int k = 16;                 // neighbours of the plane fit and the border test, 3..64
  double border_shift = 0.25;  // in r_k, > 0
  bool project = false;        // also compute `on_surface`
  // A point whose k nearest others lie closer than a typical point's (the
  // cloud's median distance to the k-th other) takes its nearest points out
  // to that distance instead (knn.h, WidenNeighborhood): where a scanner's
  // lines converge the k nearest lie on one arc and the fitted plane stands
  // on edge. r_k below is then the widened radius. false: always the k
  // nearest.
  bool widen_dense = false;
};

struct Surfels {
  std::vector<float> normal;   // 3 per point, unit, the cloud's frame
  std::vector<float> outward;  // 3 per point: unit, in the tangent plane, on the border; else 0
  std::vector<float> variation;  // 1 per point, surface variation in [0, 1/3]
  std::vector<float> on_surface;  // with `project`: 3 per point, the cloud's frame; else empty
  size_t border_points = 0;
  double widen_to_m = 0;  // with widen_dense: the typical radius
  size_t widened = 0;     // points that gained neighbours by widening
};

// Status::Invalid if an option is out of range, the cloud has at most k
// points or a non-finite coordinate. `index`, when given, must have been
// built from exactly `cloud.positions` (a caller that already has it, as
// render.splats does, saves building it again: the same surfels); null
// builds one; Status::Invalid when it holds another number of points.
Expected<Surfels> EstimateSurfels(const PointCloud& cloud, const SurfelOptions& options = {},
                                  const KnnIndex* index = nullptr);

}  // namespace pb
