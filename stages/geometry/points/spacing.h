// Point spacing: the median distance from a point to its nearest other point,
// in meters. Later stages express thresholds in spacings, so it is measured
// once per cloud.
//
// Exact nearest neighbours (kd-tree over all points, see knn.h); duplicates
// count as distance 0. For speed the median is taken over a deterministic
// subsample of `sample` points, indices floor(j * n / sample) for j in
// 0..sample-1, or over every point when sample is 0 or >= n. With an even
// count the median is the mean of the two middle values.
#pragma once

#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/point_cloud.h"
#include "stages/geometry/points/knn.h"

namespace pb {

struct SpacingOptions {
  size_t sample = 100000;  // points measured; 0 = all
  int threads = 0;         // worker threads; 0 = TBB's default (all cores)
};

// Median nearest-neighbour distance in meters. Status::Invalid if the cloud
// has fewer than 2 points or a non-finite coordinate (naming the point).
Expected<double> MedianSpacing(const PointCloud& cloud, const SpacingOptions& options = {});

// Local spacing: for every point, an estimate in meters of the distance
// between neighbouring samples around it, s = r_k * sqrt(pi / k), with r_k
// the distance to its k-th nearest other point (exact k-NN, knn.h;
// duplicates count at distance 0): k samples in a disc of radius r_k on a
// surface sampled every s (pi r_k^2 = k s^2). Where the scan is denser or
// sparser the value follows it, unlike the median: what a splat radius or a
// "near the scan" threshold needs. The one definition of the project:
// mesh.trim, metrics.geometry and render.splats all count in it. On a square
// grid of step h, k = 8 reaches the diagonal neighbours, r_8 = h sqrt(2),
// and s = 0.886 h; on a grid's border r_k and s are larger (the neighbours
// lie on one side). Deterministic for any thread count (run inside a
// tbb::task_arena to limit threads). Status::Invalid if k < 1, the cloud has
// at most k points or a non-finite coordinate.
Expected<std::vector<float>> LocalSpacing(const PointCloud& cloud, int k);
// The same for the points of `index` (KnnIndex::Build over the cloud's
// positions), for a caller that keeps the index for its own queries.
Expected<std::vector<float>> LocalSpacing(const KnnIndex& index, int k);
// One point's local spacing from the squared distance to its k-th nearest
// other point: the formula of LocalSpacing, for a caller that makes the k-NN
// queries itself (strays.h).
inline float SpacingOfKthNeighbour(double squared_distance_m2, int k) {
  return float(std::sqrt(squared_distance_m2) * std::sqrt(M_PI / k));
}

// The median of local spacings (the upper middle value of an even count; 0
// for none): the one figure the stages that count in local spacings report.
double MedianLocalSpacing(std::span<const float> spacing);

}  // namespace pb
