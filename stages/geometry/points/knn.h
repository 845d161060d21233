// KnnIndex: exact k-nearest-neighbour queries over float32 point positions.
//
// A balanced kd-tree (Bentley 1975; Friedman, Bentley & Finkel 1977), chosen
// over a uniform grid because scan density varies by orders of magnitude with
// the distance to the scanner (a grid cell sized for the near field is empty
// in the far field and overfull close to a station); a kd-tree adapts to the
// density and needs no cell size. Each node splits its points at the median
// count along the widest axis of its bounding box, so the tree's shape depends
// only on the point count and it is stored implicitly (children of node i are
// 2i+1 and 2i+2): 5 bytes per node, a copy of the points in tree order as
// separate x, y, z float arrays plus the original index (16 bytes per point;
// a leaf's coordinates are contiguous, so its distance loop vectorizes), and
// the inverse permutation (4 bytes per point). Total memory ~21 bytes per
// point; 10^7 points build in about a second on 2 cores. Queries descend
// nearest-side first and prune with the incremental box distance of Arya &
// Mount (1993).
//
// Results are exact and deterministic: neighbours are ordered by (squared
// distance, point index), so ties (duplicate points, regular grids) resolve
// to the lower index and a query returns exactly what a brute-force search
// with the same ordering returns. Squared distances are computed in double
// from the float coordinates. Building is parallel (TBB) and its result does
// not depend on the thread count; queries are const and thread-safe.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "base/status.h"

namespace pb {

// Neighbours are ordered by (squared_distance_m2, index).
struct Neighbor {
  uint32_t index = 0;              // point index in the positions given to Build
  uint32_t slot = 0;               // where the point sits in the tree (KnnIndex::PositionAtSlot)
  double squared_distance_m2 = 0;  // squared Euclidean distance, square meters
};

class KnnIndex {
 public:
  // Indexes `xyz` (3 floats per point, meters; any frame). The index keeps
  // its own copy, so `xyz` may be freed afterwards. Status::Invalid if the
  // length is not a multiple of 3, a coordinate is NaN or infinite (naming
  // the point), or there are 2^32 points or more.
  static Expected<KnnIndex> Build(std::span<const float> xyz);

  KnnIndex() = default;
  size_t size() const { return index_.size(); }

  // The min(k, size()) points nearest to `position` (x, y, z meters, same
  // frame as Build), nearest first, written to `out[0..count)`; returns the
  // count. A point of the cloud queried at its own position finds itself
  // (distance 0). Requires k >= 0 and out.size() >= k.
  int Query(const float position[3], int k, std::span<Neighbor> out) const;
  // The min(k, size() - 1) points nearest to point `index` other than the
  // point itself (its duplicates at distance 0 are still found).
  int QueryPoint(uint32_t index, int k, std::span<Neighbor> out) const;

  // The point index stored at position `slot` (0..size()) of the tree. Points
  // close in slot order are close in space: batch queries that walk slots in
  // order reuse the cache.
  uint32_t PointAtSlot(size_t slot) const { return index_[slot]; }
  // Slot of point `index` (as given to Build).
  uint32_t SlotOf(uint32_t index) const { return slot_of_[index]; }
  // Position (x, y, z meters) of the point at `slot`.
  std::array<float, 3> PositionAtSlot(size_t slot) const { return {x_[slot], y_[slot], z_[slot]}; }

 private:
  int Search(const float position[3], int k, int64_t exclude_slot, std::span<Neighbor> out) const;

  // Points in tree order, one array per coordinate.
  std::vector<float> x_, y_, z_;
  std::vector<uint32_t> index_;    // slot -> point index
  std::vector<uint32_t> slot_of_;  // point index -> slot
  std::vector<float> split_;       // per implicit node: split coordinate
  std::vector<uint8_t> axis_;      // per implicit node: split axis 0..2
};

// ---- Neighbourhoods no smaller than a typical one -------------------------
// The plane fits (points.normals, render.splats' surfels) take a point's k
// nearest. Where a scanner's lines converge (the ceiling above a station)
// the lines lie a fraction of a millimetre apart and their samples a
// centimetre apart along them, so the k nearest lie on one short arc across
// the lines, the range noise along the ray is as deep as the arc is long,
// and the fitted plane stands on edge. No test on the k points tells (the
// noise makes the arc look like a plane); their radius does: it is far
// smaller than a typical point's. docs/points.md, "Where scan lines
// converge".

// A widened neighbourhood holds at most this many times k points.
inline constexpr int kWidenedNeighbors = 32;

// The median, over at most 65,536 points spread over the cloud, of the
// distance from a point to the k-th point of Query (the point itself
// counted): the radius of a typical k-neighbourhood. 0 for an empty index.
double MedianNeighborhoodRadius(const KnnIndex& index, int k);

// Widens a neighbourhood of `count` points found for k (out[0..count),
// nearest first) by `query(want, out)`, a Query or QueryPoint of the same
// point: when count == k and all of them lie within `radius_m`, queries
// enough points to fill that radius at their density, at most
// kWidenedNeighbors * k (out must hold that many), and keeps those within
// it (at least k). Returns the new count, or `count` when it did nothing.
template <typename QueryFn>
int WidenNeighborhood(const QueryFn& query, int k, int count, double radius_m, std::span<Neighbor> out) {
  const double radius_m2 = radius_m * radius_m;
  if (count != k || k < 1 || !(out[size_t(k - 1)].squared_distance_m2 < radius_m2)) return count;
  const int most = kWidenedNeighbors * k;
  // Points within a radius grow with its square at one density.
  const double fill = double(k) * radius_m2 / std::max(out[size_t(k - 1)].squared_distance_m2, 1e-300);
  const int want = int(std::min<double>(most, std::ceil(fill)));
  int widened = query(want, out);
  while (widened > k && out[size_t(widened - 1)].squared_distance_m2 > radius_m2) --widened;
  return widened;
}

}  // namespace pb
