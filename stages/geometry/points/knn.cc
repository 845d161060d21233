// kd-tree k-nearest-neighbour search. References: J. L. Bentley, "Multidimensional
// binary search trees used for associative searching", CACM 18(9), 1975;
// J. H. Friedman, J. L. Bentley, R. A. Finkel, "An algorithm for finding best
// matches in logarithmic expected time", ACM TOMS 3(3), 1977; the incremental
// distance to the far cell is from S. Arya & D. Mount, "Algorithms for fast
// vector quantization", DCC 1993 (as in nanoflann). Departure: splits are at
// the median *count* (not the median of the spread), which keeps the tree
// balanced and implicit, so no node pointers are stored.
#include "stages/geometry/points/knn.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace pb {
namespace {

// Points per leaf at most (leaves hold between half that and that). Small
// leaves cost nodes; large ones cost distance evaluations. 16 measured best
// for k = 16 on scan-like clouds, also with the vectorized leaf loop (8 and
// 32 were 8-20% slower).
constexpr size_t kLeafSize = 16;
static_assert(kLeafSize <= 64, "leaf masks are 64-bit");
// Subtrees with more points than this build their children in parallel.
constexpr size_t kParallelBuildMin = size_t{1} << 15;
// Relative slack on the pruning bound: absorbs rounding in the incremental
// cell distance, so no cell holding a true neighbour is skipped.
constexpr double kSlack = 1e-9;

// Orders neighbours by (squared distance, index): the deterministic tie rule.
bool Closer(double d2_a, uint32_t index_a, const Neighbor& b) {
  return d2_a < b.squared_distance_m2 || (d2_a == b.squared_distance_m2 && index_a < b.index);
}

size_t TreeDepth(size_t n) {
  size_t depth = 0;
  for (size_t count = n; count > kLeafSize; count -= count / 2) ++depth;
  return depth;
}

// A point during the build: nth_element moves whole entries.
struct Entry {
  float x, y, z;
  uint32_t index;
};

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
  std::vector<Entry> entries(n);
  for (size_t i = 0; i < n; ++i) {
    const float x = xyz[3 * i], y = xyz[3 * i + 1], z = xyz[3 * i + 2];
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
      return Status::Invalid("kNN index: point " + std::to_string(i) + " has a non-finite coordinate");
    }
    entries[i] = {x, y, z, static_cast<uint32_t>(i)};
  }
  KnnIndex index;
  const size_t nodes = (size_t{2} << TreeDepth(n)) - 1;
  index.split_.assign(nodes, 0.0f);
  index.axis_.assign(nodes, 0);

  // Each call owns entries [begin, end) and node `node`: disjoint ranges, so
  // the result is the same whatever the thread count.
  auto build = [&index, &entries](auto&& self, size_t node, size_t begin, size_t end) -> void {
    if (end - begin <= kLeafSize) return;
    Entry* e = entries.data();
    float lo[3] = {e[begin].x, e[begin].y, e[begin].z};
    float hi[3] = {lo[0], lo[1], lo[2]};
    for (size_t i = begin + 1; i < end; ++i) {
      const float* p = &e[i].x;
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
    std::nth_element(e + begin, e + mid, e + end, [axis](const Entry& a, const Entry& b) {
      return (&a.x)[axis] < (&b.x)[axis];
    });
    // Left holds coordinates <= split, right >= split.
    index.split_[node] = (&e[mid].x)[axis];
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

  index.x_.resize(n);
  index.y_.resize(n);
  index.z_.resize(n);
  index.index_.resize(n);
  index.slot_of_.resize(n);
  for (size_t slot = 0; slot < n; ++slot) {
    const Entry& e = entries[slot];
    index.x_[slot] = e.x;
    index.y_[slot] = e.y;
    index.z_[slot] = e.z;
    index.index_[slot] = e.index;
    index.slot_of_[e.index] = static_cast<uint32_t>(slot);
  }
  return index;
}

int KnnIndex::Query(const float position[3], int k, std::span<Neighbor> out) const {
  return Search(position, k, -1, out);
}

int KnnIndex::QueryPoint(uint32_t index, int k, std::span<Neighbor> out) const {
  assert(index < size());
  const uint32_t slot = slot_of_[index];
  const float position[3] = {x_[slot], y_[slot], z_[slot]};
  return Search(position, k, slot, out);
}

int KnnIndex::Search(const float position[3], int k, int64_t exclude_slot,
                     std::span<Neighbor> out) const {
  assert(k >= 0 && out.size() >= static_cast<size_t>(k));
  const int64_t available = static_cast<int64_t>(size()) - (exclude_slot >= 0 ? 1 : 0);
  const int want = static_cast<int>(std::min<int64_t>(k, std::max<int64_t>(available, 0)));
  if (want == 0) return 0;
  const double q[3] = {position[0], position[1], position[2]};
  int count = 0;
  // Squared radius beyond which nothing can enter the result: infinite
  // until `want` neighbours are found, then the current k-th distance.
  double worst = std::numeric_limits<double>::infinity();
  const float* xs = x_.data();
  const float* ys = y_.data();
  const float* zs = z_.data();
  const uint32_t* points = index_.data();

  auto insert = [&](double d, uint32_t point, uint32_t slot) {
    if (count == want && !Closer(d, point, out[want - 1])) return;
    // Insertion into the sorted prefix: k is small (<= ~100).
    int at = count < want ? count++ : want - 1;
    while (at > 0 && Closer(d, point, out[at - 1])) {
      out[at] = out[at - 1];
      --at;
    }
    out[at] = {point, slot, d};
    if (count == want) worst = out[want - 1].squared_distance_m2;
  };

  auto visit_leaf = [&](size_t begin, size_t end) {
    // Two passes: the distance loop has no branches and vectorizes; the
    // second walks only the points within the current radius.
    double d2[kLeafSize];
    const size_t m = end - begin;
    for (size_t j = 0; j < m; ++j) {
      const double dx = static_cast<double>(xs[begin + j]) - q[0];
      const double dy = static_cast<double>(ys[begin + j]) - q[1];
      const double dz = static_cast<double>(zs[begin + j]) - q[2];
      d2[j] = dx * dx + dy * dy + dz * dz;
    }
    uint64_t inside = 0;
    for (size_t j = 0; j < m; ++j) inside |= static_cast<uint64_t>(d2[j] <= worst) << j;
    if (exclude_slot >= static_cast<int64_t>(begin) && exclude_slot < static_cast<int64_t>(end)) {
      inside &= ~(uint64_t{1} << (exclude_slot - static_cast<int64_t>(begin)));
    }
    while (inside != 0) {
      const int j = std::countr_zero(inside);
      inside &= inside - 1;
      if (d2[j] > worst) continue;  // worst shrank since the mask
      insert(d2[j], points[begin + j], static_cast<uint32_t>(begin + j));
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
    if (far_d2 > worst * (1.0 + kSlack)) return;
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

double MedianNeighborhoodRadius(const KnnIndex& index, int k) {
  constexpr size_t kSamples = size_t{1} << 16;
  const size_t n = index.size();
  if (n == 0 || k < 1) return 0.0;
  const size_t step = std::max<size_t>(1, n / kSamples);
  std::vector<double> squared((n + step - 1) / step, 0.0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, squared.size(), 256),
                    [&](const tbb::blocked_range<size_t>& range) {
                      std::vector<Neighbor> neighbors(static_cast<size_t>(k));
                      for (size_t s = range.begin(); s < range.end(); ++s) {
                        const std::array<float, 3> p = index.PositionAtSlot(s * step);
                        const int count = index.Query(p.data(), k, neighbors);
                        squared[s] = count > 0 ? neighbors[size_t(count - 1)].squared_distance_m2 : 0.0;
                      }
                    });
  std::nth_element(squared.begin(), squared.begin() + ptrdiff_t(squared.size() / 2), squared.end());
  return std::sqrt(squared[squared.size() / 2]);
}

}  // namespace pb
