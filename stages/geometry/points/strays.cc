// Stray points (strays.h): clusters of the k-NN graph restricted to pairs
// closer than a multiple of their local spacings, found with union-find
// (core/union_find.h).
#include "stages/geometry/points/strays.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "stages/geometry/core/union_find.h"

namespace pb {

Expected<SpacingAndStrays> LocalSpacingAndStrays(const KnnIndex& index, const StrayOptions& options) {
  if (options.k < 1 || options.k > 64)
    return Status::Invalid("stray points: k must be in 1..64, got " + std::to_string(options.k));
  if (!(options.link_spacings > 0) || !std::isfinite(options.link_spacings))
    return Status::Invalid("stray points: link_spacings must be > 0");
  if (!(options.max_spacing_ratio >= 1) || !std::isfinite(options.max_spacing_ratio))
    return Status::Invalid("stray points: max_spacing_ratio must be >= 1");
  const size_t n = index.size(), k = size_t(options.k);
  if (n <= k)
    return Status::Invalid("local spacing: needs more than k = " + std::to_string(k) + " points, the cloud has " +
                           std::to_string(n));
  SpacingAndStrays result;
  result.spacing.resize(n);
  result.stray.assign(n, 0);
  // links[i * k + j]: first the j-th nearest neighbour of point i, then (below)
  // that neighbour if it links to i, else i itself.
  std::vector<uint32_t> links(n * k);
  // Walk the tree's slot order: neighbouring queries share cache lines.
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<Neighbor> neighbors(k);
    for (size_t slot = range.begin(); slot < range.end(); ++slot) {
      const uint32_t i = index.PointAtSlot(slot);
      const int found = index.QueryPoint(i, int(k), neighbors);  // found == k: n > k
      result.spacing[i] = SpacingOfKthNeighbour(neighbors[size_t(found - 1)].squared_distance_m2, int(k));
      for (size_t j = 0; j < k; ++j) links[size_t(i) * k + j] = neighbors[j].index;
    }
  });
  if (options.min_cluster_points <= 1) return result;
  const std::vector<float>& spacing = result.spacing;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t slot = range.begin(); slot < range.end(); ++slot) {
      const uint32_t i = index.PointAtSlot(slot);
      const std::array<float, 3> p = index.PositionAtSlot(slot);
      for (size_t j = 0; j < k; ++j) {
        uint32_t& link = links[size_t(i) * k + j];
        const std::array<float, 3> q = index.PositionAtSlot(index.SlotOf(link));
        // The squared distance as KnnIndex computes it (double from float).
        const double dx = double(q[0]) - double(p[0]), dy = double(q[1]) - double(p[1]),
                     dz = double(q[2]) - double(p[2]);
        const double lo = std::min(spacing[i], spacing[link]);
        const double hi = std::max(spacing[i], spacing[link]);
        const double reach = options.link_spacings * (hi <= options.max_spacing_ratio * lo ? hi : lo);
        if (!(dx * dx + dy * dy + dz * dz <= reach * reach)) link = i;
      }
    }
  });
  UnionFind clusters(n);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < k; ++j) clusters.Union(uint32_t(i), links[i * k + j]);
  for (size_t i = 0; i < n; ++i) result.stray[i] = clusters.SizeOf(uint32_t(i)) < options.min_cluster_points;
  return result;
}

}  // namespace pb
