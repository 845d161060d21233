// Moving-least-squares smoothing of a scan: every point moves onto a
// polynomial surface fitted to its neighbours, which removes range noise
// before meshing and before normal estimation.
//
// Reference: M. Alexa, J. Behr, D. Cohen-Or, S. Fleishman, D. Levin,
// C. T. Silva, "Computing and rendering point set surfaces", IEEE TVCG 9(1),
// 2003 (the MLS projection); the implementation is PCL 1.13's
// pcl::MovingLeastSquares (Rusu's formulation: a local plane from the
// weighted neighbourhood, a bivariate polynomial of the given order over it,
// the point projected along the plane's normal, projection method SIMPLE,
// no upsampling, Gaussian weight exp(-d^2 / radius^2)). It runs in
// pointbake-pcl.so, loaded on first use (stages/geometry/core/module.h).
//
// Units: meters in the cloud's frame. Output: the same points in the same
// order, moved; colors, intensities and station ids kept; normals removed
// (they described the unsmoothed surface: estimate them afterwards). A point
// with fewer neighbours inside the radius than the polynomial has
// coefficients is projected onto the neighbourhood's plane only (PCL's rule);
// one whose projection is not finite keeps its position.
// Deterministic whatever the thread count. Cost on 10^6 points of a room
// scan, radius 4 spacings: ~7 s of CPU, ~380 MiB peak for the whole stage
// process (PCL's copy of the cloud, its kd-tree and the fits' buffers;
// docs/implementations.md).
#pragma once

#include <cstddef>

#include "base/status.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

struct SmoothOptions {
  double radius_m = 0;       // neighbourhood radius, > 0; ~3-5 point spacings
  int polynomial_order = 2;  // 0 or 1: plane only; 2, 3: a polynomial keeps curvature
  int threads = 0;           // worker threads; 0 = all cores
};

struct SmoothReport {
  size_t points = 0;
  double mean_shift_m = 0;  // mean distance a point moved
  double max_shift_m = 0;
};

// Status::Invalid for radius_m not > 0, polynomial_order outside 0..3, fewer
// than 3 points or a non-finite coordinate (naming the point);
// Status::Unsupported when this build has no pointbake-pcl.so.
Expected<PointCloud> SmoothMovingLeastSquares(const PointCloud& cloud, const SmoothOptions& options,
                                              SmoothReport* report = nullptr);

}  // namespace pb
