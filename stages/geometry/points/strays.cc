// Stray points (strays.h): clusters of the k-NN graph restricted to pairs
// closer than a multiple of their local spacings, found with union-find
// (Tarjan 1975, path halving and union by size).
#include "stages/geometry/points/strays.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace pb {
namespace {

class UnionFind {
 public:
  explicit UnionFind(size_t n) : parent_(n), size_(n, 1) { std::iota(parent_.begin(), parent_.end(), 0u); }
  uint32_t Find(uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void Union(uint32_t a, uint32_t b) {
    a = Find(a);
    b = Find(b);
    if (a == b) return;
    if (size_[a] < size_[b]) std::swap(a, b);
    parent_[b] = a;
    size_[a] += size_[b];
  }
  uint32_t SizeOf(uint32_t x) { return size_[Find(x)]; }

 private:
  std::vector<uint32_t> parent_, size_;
};

}  // namespace

Expected<std::vector<uint8_t>> StrayPoints(const KnnIndex& index, std::span<const float> spacing,
                                           const StrayOptions& options) {
  if (options.k < 1 || options.k > 64)
    return Status::Invalid("stray points: k must be in 1..64, got " + std::to_string(options.k));
  if (!(options.link_spacings > 0) || !std::isfinite(options.link_spacings))
    return Status::Invalid("stray points: link_spacings must be > 0");
  if (!(options.max_spacing_ratio >= 1) || !std::isfinite(options.max_spacing_ratio))
    return Status::Invalid("stray points: max_spacing_ratio must be >= 1");
  if (spacing.size() != index.size())
    return Status::Invalid("stray points: " + std::to_string(spacing.size()) + " spacings for " +
                           std::to_string(index.size()) + " points");
  const size_t n = index.size();
  std::vector<uint8_t> stray(n, 0);
  if (options.min_cluster_points <= 1 || n == 0) return stray;
  // links[i * k + j]: the j-th linked neighbour of point i, or i itself.
  const size_t k = size_t(options.k);
  std::vector<uint32_t> links(n * k);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<Neighbor> neighbors(k);
    for (size_t slot = range.begin(); slot < range.end(); ++slot) {
      const uint32_t i = index.PointAtSlot(slot);
      const int found = index.QueryPoint(i, int(k), neighbors);
      for (size_t j = 0; j < k; ++j) {
        uint32_t linked = i;
        if (int(j) < found) {
          const Neighbor& nb = neighbors[j];
          const double lo = std::min(spacing[i], spacing[nb.index]);
          const double hi = std::max(spacing[i], spacing[nb.index]);
          const double reach = options.link_spacings * (hi <= options.max_spacing_ratio * lo ? hi : lo);
          if (nb.squared_distance_m2 <= reach * reach) linked = nb.index;
        }
        links[size_t(i) * k + j] = linked;
      }
    }
  });
  UnionFind clusters(n);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < k; ++j) clusters.Union(uint32_t(i), links[i * k + j]);
  for (size_t i = 0; i < n; ++i) stray[i] = clusters.SizeOf(uint32_t(i)) < options.min_cluster_points;
  return stray;
}

}  // namespace pb
