// kd-tree k-nearest-neighbour search. References: J. L. Bentley, "Multidimensional
// binary search trees used for associative searching", CACM 18(9), 1975;
// J. H. Friedman, J. L. Bentley, R. A. Finkel, "An algorithm for finding best
// matches in logarithmic expected time", ACM TOMS 3(3), 1977; the incremental
// distance to the far cell is from S. Arya & D. Mount, "Algorithms for fast
// vector quantization", DCC 1993 (as in nanoflann). Departure: splits are at
// the median *count* (not the median of the spread), which keeps the tree
// balanced and implicit, so no node pointers are stored.
#include "stages/geometry/knn.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <string>

namespace pb {
namespace {

// Points per leaf at most. Small leaves cost nodes; large ones cost distance
// evaluations; 16 measured best for k = 16 on scan-like clouds (8 and 32
// were 10-15% slower).
constexpr size_t kLeafSize = 16;
// Subtrees with more points than this build their children in parallel.
constexpr size_t kParallelBuildMin = size_t{1} << 15;

size_t TreeDepth(size_t n) {
  size_t depth = 0;
  for (size_t count = n; count > kLeafSize; count -= count / 2) ++depth;
  return depth;
}

// Orders neighbours by (squared distance, index): the deterministic tie rule.
bool Closer(double d2_a, uint32_t index_a, const Neighbor& b) {
  return d2_a < b.squared_distance_m2 || (d2_a == b.squared_distance_m2 && index_a < b.index);
}

}  // namespace

Expected<KnnIndex> KnnIndex::Build(std::span<const float> xyz) {
  if (xyz.size() % 3 != 0) {
    return Status::Invalid("kNN index: expected 3 floats per point, got " + std::to_string(xyz.size()) +
                           " floats");
  }
  const size_t n = xyz.size() / 3;
  if (n > std::numeric_limits<uint32_t>::max() - 1) {
    return Status::Invalid("kNN index: " + std::to_string(n) +
                           " points is more than the supported 2^32 - 1; split the cloud");
  }
  KnnIndex index;
  index.entries_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const float x = xyz[3 * i], y = xyz[3 * i + 1], z = xyz[3 * i + 2];
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
      return Status::Invalid("kNN index: point " + std::to_string(i) + " has a non-finite coordinate");
    }
    index.entries_[i] = {x, y, z, static_cast<uint32_t>(i)};
  }
  const size_t nodes = (size_t{2} << TreeDepth(n)) - 1;
  index.split_.assign(nodes, 0.0f);
  index.axis_.assign(nodes, 0);

  // Each call owns entries [begin, end) and node `node`: disjoint ranges, so
  // the result is the same whatever the thread count.
  auto build = [&index](auto&& self, size_t node, size_t begin, size_t end) -> void {
    if (end - begin <= kLeafSize) return;
    Entry* entries = index.entries_.data();
    float lo[3] = {entries[begin].x, entries[begin].y, entries[begin].z};
    float hi[3] = {lo[0], lo[1], lo[2]};
    for (size_t i = begin + 1; i < end; ++i) {
      const float* p = &entries[i].x;
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], p[a]);
        hi[a] = std::max(hi[a], p[a]);
      }
    }
    int axis = 0;
    for (int a = 1; a < 3; ++a) {
      if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
    }
    const size_t mid = begin + (end - begin) / 2;
    std::nth_element(entries + begin, entries + mid, entries + end,
                     [axis](const Entry& a, const Entry& b) { return (&a.x)[axis] < (&b.x)[axis]; });
    // Left holds coordinates <= split, right >= split.
    index.split_[node] = (&entries[mid].x)[axis];
    index.axis_[node] = static_cast<uint8_t>(axis);
    if (end - begin >= kParallelBuildMin) {
      tbb::parallel_invoke([&] { self(self, 2 * node + 1, begin, mid); },
                           [&] { self(self, 2 * node + 2, mid, end); });
    } else {
      self(self, 2 * node + 1, begin, mid);
      self(self, 2 * node + 2, mid, end);
    }
  };
  build(build, 0, 0, n);

  index.slot_of_.resize(n);
  for (size_t slot = 0; slot < n; ++slot) index.slot_of_[index.entries_[slot].index] = static_cast<uint32_t>(slot);
  return index;
}

int KnnIndex::Query(const float position[3], int k, std::span<Neighbor> out) const {
  return Search(position, k, -1, out);
}

int KnnIndex::QueryPoint(uint32_t index, int k, std::span<Neighbor> out) const {
  assert(index < size());
  return Search(PositionOf(index), k, index, out);
}

int KnnIndex::Search(const float position[3], int k, int64_t exclude, std::span<Neighbor> out) const {
  assert(k >= 0 && out.size() >= static_cast<size_t>(k));
  const int64_t available = static_cast<int64_t>(size()) - (exclude >= 0 ? 1 : 0);
  const int want = static_cast<int>(std::min<int64_t>(k, std::max<int64_t>(available, 0)));
  if (want == 0) return 0;
  const double q[3] = {position[0], position[1], position[2]};
  int count = 0;

  auto visit_leaf = [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      const Entry& e = entries_[i];
      if (static_cast<int64_t>(e.index) == exclude) continue;
      const double dx = static_cast<double>(e.x) - q[0];
      const double dy = static_cast<double>(e.y) - q[1];
      const double dz = static_cast<double>(e.z) - q[2];
      const double d2 = dx * dx + dy * dy + dz * dz;
      if (count == want && !Closer(d2, e.index, out[want - 1])) continue;
      // Insertion into the sorted prefix: k is small (<= ~100).
      int at = count < want ? count++ : want - 1;
      while (at > 0 && Closer(d2, e.index, out[at - 1])) {
        out[at] = out[at - 1];
        --at;
      }
      out[at] = {e.index, d2};
    }
  };

  // off[a]: signed distance from q to the current cell along axis a (0 when
  // inside); cell_d2 = sum of off^2, a lower bound for every point in it.
  double off[3] = {0, 0, 0};
  auto descend = [&](auto&& self, size_t node, size_t begin, size_t end, double cell_d2) -> void {
    if (end - begin <= kLeafSize) {
      visit_leaf(begin, end);
      return;
    }
    const size_t mid = begin + (end - begin) / 2;
    const int axis = axis_[node];
    const double diff = q[axis] - static_cast<double>(split_[node]);
    const bool left_first = diff < 0;
    if (left_first) {
      self(self, 2 * node + 1, begin, mid, cell_d2);
    } else {
      self(self, 2 * node + 2, mid, end, cell_d2);
    }
    const double old = off[axis];
    const double far_d2 = cell_d2 - old * old + diff * diff;
    // Equal distance is not pruned (the far side may hold a tie with a lower
    // index), and the slack absorbs rounding in the incremental bound.
    if (count == want && far_d2 > out[want - 1].squared_distance_m2 * (1.0 + 1e-9)) return;
    off[axis] = diff;
    if (left_first) {
      self(self, 2 * node + 2, mid, end, far_d2);
    } else {
      self(self, 2 * node + 1, begin, mid, far_d2);
    }
    off[axis] = old;
  };
  descend(descend, 0, 0, size(), 0.0);
  return count;
}

}  // namespace pb
