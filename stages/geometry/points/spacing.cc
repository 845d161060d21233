// Median nearest-neighbour spacing: exact 1-NN by kd-tree (knn.h) over a
// deterministic subsample; the median (not the mean) so that duplicates and
// sparse far-field points do not move it.
#include "stages/geometry/points/spacing.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "stages/geometry/points/knn.h"

namespace pb {
namespace {

Expected<double> SpacingInArena(const PointCloud& cloud, size_t sample) {
  const size_t n = cloud.size();
  PB_ASSIGN_OR_RETURN(const KnnIndex index, KnnIndex::Build(cloud.positions));
  const size_t count = sample == 0 || sample >= n ? n : sample;
  std::vector<double> distances(count);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1024), [&](const tbb::blocked_range<size_t>& range) {
    Neighbor nearest[1];
    for (size_t j = range.begin(); j < range.end(); ++j) {
      // floor(j * n / count); j * n < 2^64 because j < count <= n < 2^32.
      const size_t i = static_cast<size_t>(static_cast<uint64_t>(j) * n / count);
      index.QueryPoint(static_cast<uint32_t>(i), 1, nearest);
      distances[j] = std::sqrt(nearest[0].squared_distance_m2);
    }
  });
  const size_t middle = count / 2;
  std::nth_element(distances.begin(), distances.begin() + middle, distances.end());
  const double upper = distances[middle];
  if (count % 2 == 1) return upper;
  const double lower = *std::max_element(distances.begin(), distances.begin() + middle);
  return (lower + upper) / 2;
}

}  // namespace

Expected<double> MedianSpacing(const PointCloud& cloud, const SpacingOptions& options) {
  PB_RETURN_IF_ERROR(Validate(cloud));
  if (cloud.size() < 2) {
    return Status::Invalid("point spacing: needs at least 2 points, the cloud has " +
                           std::to_string(cloud.size()));
  }
  Expected<double> spacing = Status::Internal("not run");
  if (options.threads > 0) {
    tbb::task_arena arena(options.threads);
    spacing = arena.execute([&] { return SpacingInArena(cloud, options.sample); });
  } else {
    spacing = SpacingInArena(cloud, options.sample);
  }
  return spacing;
}

Expected<std::vector<float>> LocalSpacing(const PointCloud& cloud, int k) {
  PB_RETURN_IF_ERROR(Validate(cloud));
  if (k < 1) return Status::Invalid("local spacing: k must be >= 1, got " + std::to_string(k));
  PB_ASSIGN_OR_RETURN(const KnnIndex index, KnnIndex::Build(cloud.positions));
  return LocalSpacing(index, k);
}

Expected<std::vector<float>> LocalSpacing(const KnnIndex& index, int k) {
  if (k < 1) return Status::Invalid("local spacing: k must be >= 1, got " + std::to_string(k));
  if (index.size() <= size_t(k))
    return Status::Invalid("local spacing: needs more than k = " + std::to_string(k) +
                           " points, the cloud has " + std::to_string(index.size()));
  std::vector<float> spacing(index.size());
  // Walk the tree's slot order: neighbouring queries share cache lines.
  tbb::parallel_for(tbb::blocked_range<size_t>(0, index.size(), 1024), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<Neighbor> neighbors(static_cast<size_t>(k));
    for (size_t slot = range.begin(); slot < range.end(); ++slot) {
      const uint32_t i = index.PointAtSlot(slot);
      const int found = index.QueryPoint(i, k, neighbors);
      spacing[i] = SpacingOfKthNeighbour(neighbors[size_t(found - 1)].squared_distance_m2, k);
    }
  });
  return spacing;
}

double MedianLocalSpacing(std::span<const float> spacing) {
  if (spacing.empty()) return 0;
  std::vector<float> sorted(spacing.begin(), spacing.end());
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  return sorted[sorted.size() / 2];
}

}  // namespace pb
