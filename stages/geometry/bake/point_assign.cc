// Point-to-face assignment of the paper's point-based detail transfer
// (paper, "Detail Transfer Algorithm", pseudo-code lines 5-10 and 20-28).
//
// Departures from the paper and the authors' code, and why:
//   - The authors took, per triangle, the nearby points, projected them on
//     the triangle's plane and kept those with all barycentric coordinates
//     >= 0, so a point could land on several triangles or on none (points
//     just past an edge). Here every point goes to exactly one face, the
//     nearest acceptable one, at the closest point of the triangle: no point
//     is counted twice and none falls between neighbours.
//   - Their distance threshold (4.0, compared with a squared distance) and
//     angle threshold (45 degrees against vertex normals in the code, 120 in
//     the paper) are parameters here, in meters and degrees against the face
//     normal (DESIGN.md).
//
// Structure: a uniform grid over the faces (dense, or hashed when a dense one
// would be large), each face registered in the cells that its bounding box
// expanded by max_distance overlaps and whose centre lies within
// max_distance + half the cell diagonal of the triangle; a point tests only
// the faces of its own cell, the previous point's face first, each through a
// cheap lower bound (plane and edge lines) before the exact closest point.
// The results overwrite the cloud's positions in place as (s, t, face); an
// in-place two-level bucket sort (American flag: 256 face ranges, then faces)
// groups the points by face across positions, colors and normals; a per-face
// sort orders each face's points; st is compacted from 3 floats to 2.
#include "stages/geometry/bake/point_assign.h"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

namespace pb {
namespace {

constexpr uint32_t kDropped = 0xffffffffu;
// Grid cell edge relative to the mean triangle edge (see FaceGrid::Build).
constexpr double kCellPerMeanEdge = 0.5;

// A face as the inner loop reads it: corners relative to the mesh's origin
// (as the mesh stores them) and the unit face normal.
struct FaceGeom {
  float a[3], b[3], c[3];
  float n[3];
};

// The per-point test's view of a face: its plane and the three in-plane
// lines through its edges, unit normals (in-plane ones pointing out). For a
// point at height h over the plane and `out` past the farthest edge line,
// h^2 + out^2 is a lower bound of its squared distance to the triangle, and
// exact (h^2) when the point projects inside.
struct FaceBound {
  float plane[4];    // n, n . a
  float edge[3][4];  // m_k, m_k . (a point of edge k)
};

FaceBound MakeBound(const FaceGeom& g) {
  FaceBound b;
  const double n[3] = {g.n[0], g.n[1], g.n[2]};
  b.plane[0] = g.n[0], b.plane[1] = g.n[1], b.plane[2] = g.n[2];
  b.plane[3] = float(n[0] * g.a[0] + n[1] * g.a[1] + n[2] * g.a[2]);
  const float* v[3] = {g.a, g.b, g.c};
  for (int k = 0; k < 3; ++k) {
    const float* p = v[k];
    const float* q = v[(k + 1) % 3];
    const double e[3] = {double(q[0]) - p[0], double(q[1]) - p[1], double(q[2]) - p[2]};
    // m = e x n points out of a counter-clockwise triangle.
    double m[3] = {e[1] * n[2] - e[2] * n[1], e[2] * n[0] - e[0] * n[2], e[0] * n[1] - e[1] * n[0]};
    const double len = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    for (int j = 0; j < 3; ++j) m[j] /= len;
    for (int j = 0; j < 3; ++j) b.edge[k][j] = float(m[j]);
    b.edge[k][3] = float(double(b.edge[k][0]) * p[0] + double(b.edge[k][1]) * p[1] + double(b.edge[k][2]) * p[2]);
  }
  return b;
}

// Squared distance from p to triangle f and the barycentric coordinates of
// the closest point (Ericson, Real-Time Collision Detection, 5.1.5). The
// triangle must have nonzero area.
double ClosestOnTriangle(const double p[3], const float* a, const float* b, const float* c, double bary[3]) {
  double ab[3], ac[3], ap[3], bp[3], cp[3];
  for (int k = 0; k < 3; ++k) {
    ab[k] = double(b[k]) - a[k];
    ac[k] = double(c[k]) - a[k];
    ap[k] = p[k] - a[k];
    bp[k] = p[k] - b[k];
    cp[k] = p[k] - c[k];
  }
  auto dot = [](const double* x, const double* y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; };
  double v = 0, w = 0;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  const double vc = d1 * d4 - d3 * d2;
  const double vb = d5 * d2 - d1 * d6;
  const double va = d3 * d6 - d5 * d4;
  if (d1 <= 0 && d2 <= 0) {
    v = 0, w = 0;
  } else if (d3 >= 0 && d4 <= d3) {
    v = 1, w = 0;
  } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    v = d1 / (d1 - d3), w = 0;
  } else if (d6 >= 0 && d5 <= d6) {
    v = 0, w = 1;
  } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    v = 0, w = d2 / (d2 - d6);
  } else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    v = 1 - w;
  } else {
    const double denom = 1 / (va + vb + vc);
    v = vb * denom;
    w = vc * denom;
  }
  bary[0] = 1 - v - w;
  bary[1] = v;
  bary[2] = w;
  double d2sum = 0;
  for (int k = 0; k < 3; ++k) {
    const double e = ap[k] - ab[k] * v - ac[k] * w;
    d2sum += e * e;
  }
  return d2sum;
}

// Faces by grid cell. Cell (i, j, k) covers min + [i, i+1) * cell_m etc.
// Dense (an offset per cell of the bounding box) when that costs no more
// than the face lists themselves; otherwise the occupied cells in an
// open-addressing hash table, as a surface fills few cells of its box.
class FaceGrid {
 public:
  // The last cell looked up, for points that come in spatial runs.
  struct Cache {
    uint64_t idx[3] = {~uint64_t(0), 0, 0};
    std::pair<uint32_t, uint32_t> range;
  };
  // [begin, end) of the cell's faces in faces(); empty outside the grid.
  std::pair<uint32_t, uint32_t> CellOf(const double q[3], Cache* cache) const {
    uint64_t idx[3];
    for (int k = 0; k < 3; ++k) {
      // Truncation is floor here (f >= 0), and no libm call.
      const double f = (q[k] - min_[k]) * inv_cell_;
      if (!(f >= 0 && f < double(n_[k]))) return {0, 0};
      idx[k] = uint64_t(f);
    }
    if (idx[0] == cache->idx[0] && idx[1] == cache->idx[1] && idx[2] == cache->idx[2]) return cache->range;
    std::copy(idx, idx + 3, cache->idx);
    cache->range = Lookup(idx);
    return cache->range;
  }

 private:
  std::pair<uint32_t, uint32_t> Lookup(const uint64_t idx[3]) const {
    uint64_t c;
    if (dense_) {
      c = (idx[2] * n_[1] + idx[1]) * n_[0] + idx[0];
    } else {
      c = Find(Key(idx[0], idx[1], idx[2]));
      if (c == kNone) return {0, 0};
    }
    return {cell_begin_[c], cell_begin_[c + 1]};
  }

 public:
  const std::vector<uint32_t>& faces() const { return faces_; }
  double cell_m() const { return cell_m_; }
  bool dense() const { return dense_; }
  size_t cells() const { return cell_begin_.size() - 1; }
  size_t memory_bytes() const {
    return faces_.capacity() * 4 + cell_begin_.capacity() * 4 + slots_.capacity() * sizeof(Slot);
  }

  static Expected<FaceGrid> Build(const std::vector<FaceGeom>& geom, const std::vector<uint32_t>& usable,
                                  double max_distance_m);

 private:
  static constexpr uint64_t kEmptyKey = ~uint64_t(0);
  static constexpr uint32_t kNone = ~uint32_t(0);
  static constexpr int kAxisBits = 21;
  struct Slot {
    uint64_t key = kEmptyKey;
    uint32_t cell = kNone;  // ordinal of the occupied cell
  };
  static uint64_t Key(uint64_t i, uint64_t j, uint64_t k) { return i | (j << kAxisBits) | (k << (2 * kAxisBits)); }
  uint64_t Hash(uint64_t key) const { return (key * 0x9E3779B97F4A7C15ull) >> shift_; }
  uint32_t Find(uint64_t key) const {
    for (uint64_t slot = Hash(key);; slot = (slot + 1) & mask_) {
      const Slot& s = slots_[slot];
      if (s.key == key) return s.cell;
      if (s.key == kEmptyKey) return kNone;
    }
  }
  // The ordinal of key's cell, adding it (ordinal = cells so far) if new.
  uint32_t FindOrAdd(uint64_t key, uint32_t* cells);
  void Rehash(int bits);

  // Calls visit(i, j, k) for every cell face `f` is registered in.
  template <typename Visit>
  void ForEachCell(const FaceGeom& f, double max_distance_m, Visit&& visit) const;

  double min_[3] = {0, 0, 0};
  double cell_m_ = 1, inv_cell_ = 1;
  uint64_t n_[3] = {0, 0, 0};
  bool dense_ = true;
  std::vector<uint32_t> cell_begin_;  // cells + 1 offsets into faces_
  std::vector<Slot> slots_;           // hashed: open addressing, linear probing
  uint64_t mask_ = 0;
  int shift_ = 64;
  std::vector<uint32_t> faces_;  // per cell, ascending face index
};

void FaceGrid::Rehash(int bits) {
  std::vector<Slot> old = std::move(slots_);
  slots_.assign(size_t(1) << bits, Slot{});
  mask_ = (uint64_t(1) << bits) - 1;
  shift_ = 64 - bits;
  for (const Slot& s : old) {
    if (s.key == kEmptyKey) continue;
    uint64_t slot = Hash(s.key);
    while (slots_[slot].key != kEmptyKey) slot = (slot + 1) & mask_;
    slots_[slot] = s;
  }
}

uint32_t FaceGrid::FindOrAdd(uint64_t key, uint32_t* cells) {
  if (2 * (uint64_t(*cells) + 1) > slots_.size()) Rehash(std::countr_zero(slots_.size()) + 1);
  uint64_t slot = Hash(key);
  for (;; slot = (slot + 1) & mask_) {
    if (slots_[slot].key == key) return slots_[slot].cell;
    if (slots_[slot].key == kEmptyKey) break;
  }
  slots_[slot] = Slot{key, (*cells)++};
  return slots_[slot].cell;
}

template <typename Visit>
void FaceGrid::ForEachCell(const FaceGeom& f, double d, Visit&& visit) const {
  int64_t lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    const double mn = std::min({double(f.a[k]), double(f.b[k]), double(f.c[k])}) - d;
    const double mx = std::max({double(f.a[k]), double(f.b[k]), double(f.c[k])}) + d;
    lo[k] = std::clamp<int64_t>(int64_t(std::floor((mn - min_[k]) * inv_cell_)), 0, int64_t(n_[k]) - 1);
    hi[k] = std::clamp<int64_t>(int64_t(std::floor((mx - min_[k]) * inv_cell_)), 0, int64_t(n_[k]) - 1);
  }
  // A point of the cell within d of the triangle is within half the cell's
  // diagonal of its centre, so the centre is within d + that of the triangle
  // (and of its plane: the cheap test first).
  const double n[3] = {f.n[0], f.n[1], f.n[2]};
  const double slack = 1e-6 * cell_m_;
  const double slab = d + 0.5 * cell_m_ * (std::abs(n[0]) + std::abs(n[1]) + std::abs(n[2])) + slack;
  const double reach = d + 0.5 * std::sqrt(3.0) * cell_m_ + slack;
  const double offset = n[0] * f.a[0] + n[1] * f.a[1] + n[2] * f.a[2];
  for (int64_t k = lo[2]; k <= hi[2]; ++k) {
    const double cz = min_[2] + (k + 0.5) * cell_m_;
    for (int64_t j = lo[1]; j <= hi[1]; ++j) {
      const double cy = min_[1] + (j + 0.5) * cell_m_;
      for (int64_t i = lo[0]; i <= hi[0]; ++i) {
        const double cx = min_[0] + (i + 0.5) * cell_m_;
        if (std::abs(n[0] * cx + n[1] * cy + n[2] * cz - offset) > slab) continue;
        const double centre[3] = {cx, cy, cz};
        double bary[3];
        if (ClosestOnTriangle(centre, f.a, f.b, f.c, bary) > reach * reach) continue;
        visit(uint64_t(i), uint64_t(j), uint64_t(k));
      }
    }
  }
}

Expected<FaceGrid> FaceGrid::Build(const std::vector<FaceGeom>& geom, const std::vector<uint32_t>& usable,
                                   double d) {
  FaceGrid grid;
  grid.cell_begin_.assign(1, 0);
  if (usable.empty()) return grid;  // n_ = 0: every point is outside
  double mn[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
  double mx[3] = {-mn[0], -mn[1], -mn[2]};
  double edge_sum = 0;
  for (uint32_t f : usable) {
    const FaceGeom& g = geom[f];
    const float* v[3] = {g.a, g.b, g.c};
    for (int c = 0; c < 3; ++c) {
      for (int k = 0; k < 3; ++k) {
        mn[k] = std::min(mn[k], double(v[c][k]));
        mx[k] = std::max(mx[k], double(v[c][k]));
      }
      const float* w = v[(c + 1) % 3];
      edge_sum += std::sqrt(double(v[c][0] - w[0]) * (v[c][0] - w[0]) + double(v[c][1] - w[1]) * (v[c][1] - w[1]) +
                            double(v[c][2] - w[2]) * (v[c][2] - w[2]));
    }
  }
  const double mean_edge_m = edge_sum / (3.0 * usable.size());
  double extent = 0;
  for (int k = 0; k < 3; ++k) {
    grid.min_[k] = mn[k] - d;
    extent = std::max(extent, mx[k] - mn[k] + 2 * d);
  }
  // Cells of about half a mean edge keep a handful of candidate faces per
  // point on a regular surface; never below max_distance (a face then spans
  // few cells per axis) and never more than 2^21 cells per axis (the hash
  // key). Grown if the registrations get out of hand (large faces).
  double cell = std::max({d, kCellPerMeanEdge * mean_edge_m, extent / double((1 << kAxisBits) - 2)});
  const size_t max_registrations = 32 * usable.size() + (size_t(1) << 20);
  size_t registrations = 0;
  for (;;) {
    grid.cell_m_ = cell;
    grid.inv_cell_ = 1 / cell;
    for (int k = 0; k < 3; ++k)
      grid.n_[k] = uint64_t(std::floor((mx[k] + d - grid.min_[k]) * grid.inv_cell_)) + 1;
    registrations = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, usable.size(), 1024), size_t(0),
        [&](const tbb::blocked_range<size_t>& r, size_t sum) {
          for (size_t u = r.begin(); u != r.end(); ++u)
            grid.ForEachCell(geom[usable[u]], d, [&](uint64_t, uint64_t, uint64_t) { ++sum; });
          return sum;
        },
        std::plus<size_t>());
    if (registrations <= max_registrations) break;
    cell *= 1.5;
  }
  if (registrations >= kDropped) return Status::Invalid("point assignment: the face grid is too large");

  // Cell of every registration, in face order; then a counting sort, which
  // keeps the faces of each cell ascending.
  const double box_cells = double(grid.n_[0]) * double(grid.n_[1]) * double(grid.n_[2]);
  grid.dense_ = box_cells <= std::max(double(registrations), double(1 << 16));
  std::vector<uint32_t> cell_of_registration;
  cell_of_registration.reserve(registrations);
  uint32_t cells = 0;
  if (grid.dense_) {
    cells = uint32_t(box_cells);
  } else {
    grid.Rehash(10);
  }
  std::vector<uint32_t> first_registration(usable.size() + 1);
  for (size_t u = 0; u < usable.size(); ++u) {
    first_registration[u] = uint32_t(cell_of_registration.size());
    grid.ForEachCell(geom[usable[u]], d, [&](uint64_t i, uint64_t j, uint64_t k) {
      cell_of_registration.push_back(grid.dense_ ? uint32_t((k * grid.n_[1] + j) * grid.n_[0] + i)
                                                 : grid.FindOrAdd(Key(i, j, k), &cells));
    });
  }
  first_registration[usable.size()] = uint32_t(cell_of_registration.size());
  grid.cell_begin_.assign(size_t(cells) + 1, 0);
  for (uint32_t c : cell_of_registration) ++grid.cell_begin_[c + 1];
  for (size_t c = 1; c < grid.cell_begin_.size(); ++c) grid.cell_begin_[c] += grid.cell_begin_[c - 1];
  grid.faces_.resize(registrations);
  std::vector<uint32_t> cursor(grid.cell_begin_.begin(), grid.cell_begin_.end() - 1);
  for (size_t u = 0; u < usable.size(); ++u)
    for (uint32_t r = first_registration[u]; r < first_registration[u + 1]; ++r)
      grid.faces_[cursor[cell_of_registration[r]]++] = usable[u];
  return grid;
}

// Per-thread tallies of the assignment pass; integers only, so the sums do
// not depend on how the points were split between threads.
struct Tally {
  std::vector<uint32_t> face_counts;  // < 2^32: the point count is checked
  size_t too_far = 0, wrong_angle = 0, non_finite = 0;
  uint64_t distance_nm = 0;
};

// The three point arrays seen as one array of points, for the in-place sorts.
template <bool kNormals, bool kColors>
struct PointArrays {
  float* st;        // 3 per point: s, t, face bits
  float* normals;   // 3 per point
  uint8_t* colors;  // 3 per point

  struct Point {
    float st[3];
    float n[3];
    uint8_t c[3];
  };
  Point Load(size_t i) const {
    Point p;
    std::memcpy(p.st, st + 3 * i, 12);
    if constexpr (kNormals) std::memcpy(p.n, normals + 3 * i, 12);
    if constexpr (kColors) std::memcpy(p.c, colors + 3 * i, 3);
    return p;
  }
  void Store(size_t i, const Point& p) const {
    std::memcpy(st + 3 * i, p.st, 12);
    if constexpr (kNormals) std::memcpy(normals + 3 * i, p.n, 12);
    if constexpr (kColors) std::memcpy(colors + 3 * i, p.c, 3);
  }
  uint32_t Face(size_t i) const { return std::bit_cast<uint32_t>(st[3 * i + 2]); }
  static uint32_t Face(const Point& p) { return std::bit_cast<uint32_t>(p.st[2]); }

  // In-place American flag sort of [begin, end) into buckets of
  // bucket_of(face); bucket b starts at starts[b] - the caller's counts.
  // Buckets are completed in order: once done(b) is called, bucket b holds
  // its points and the sort never touches it again.
  template <typename BucketOf, typename Done>
  void FlagSort(std::vector<size_t> next, const std::vector<size_t>& ends, BucketOf&& bucket_of,
                Done&& done) const {
    for (size_t b = 0; b < ends.size(); ++b) {
      while (next[b] < ends[b]) {
        Point p = Load(next[b]);
        size_t k = bucket_of(Face(p));
        while (k != b) {
          const size_t at = next[k]++;
          Point q = Load(at);
          Store(at, p);
          p = q;
          k = bucket_of(Face(p));
        }
        Store(next[b]++, p);
      }
      done(b);
    }
  }

  // The order within a face: (s, t, color, normal); floats by a monotonic
  // map of their bits, so -0 and +0 (and anything else) order totally.
  static uint32_t Monotonic(float x) {
    const uint32_t b = std::bit_cast<uint32_t>(x);
    return (b & 0x80000000u) ? ~b : (b | 0x80000000u);
  }
  struct SortKey {
    uint32_t s, t;
    uint8_t c[3];
    uint32_t n[3];
    bool operator<(const SortKey& o) const {
      if (s != o.s) return s < o.s;
      if (t != o.t) return t < o.t;
      if (int r = std::memcmp(c, o.c, 3)) return r < 0;
      if (n[0] != o.n[0]) return n[0] < o.n[0];
      if (n[1] != o.n[1]) return n[1] < o.n[1];
      return n[2] < o.n[2];
    }
  };
  static SortKey KeyOf(const Point& p) {
    SortKey k{Monotonic(p.st[0]), Monotonic(p.st[1]), {0, 0, 0}, {0, 0, 0}};
    if constexpr (kColors) std::memcpy(k.c, p.c, 3);
    if constexpr (kNormals)
      for (int j = 0; j < 3; ++j) k.n[j] = std::bit_cast<uint32_t>(p.n[j]);
    return k;
  }

  // Sorts the points [begin, end) of one face. Small faces through a
  // thread-local buffer (bounded: at most kGatherLimit points); larger ones
  // by an in-place heapsort, so no face needs memory proportional to its
  // point count.
  static constexpr size_t kGatherLimit = 1 << 14;
  struct SortBuffer {
    std::vector<Point> points;
    std::vector<std::pair<uint64_t, uint32_t>> order;  // (s, t) packed, index
  };
  void SortFace(size_t begin, size_t end, SortBuffer& buffer) const {
    const size_t count = end - begin;
    if (count < 2) return;
    if (count <= kGatherLimit) {
      buffer.points.resize(count);
      buffer.order.resize(count);
      for (size_t i = 0; i < count; ++i) {
        const Point& p = buffer.points[i] = Load(begin + i);
        buffer.order[i] = {uint64_t(Monotonic(p.st[0])) << 32 | Monotonic(p.st[1]), uint32_t(i)};
      }
      // (s, t) decides almost always; the full key only for equal ones.
      std::sort(buffer.order.begin(), buffer.order.end(), [&](const auto& x, const auto& y) {
        if (x.first != y.first) return x.first < y.first;
        return KeyOf(buffer.points[x.second]) < KeyOf(buffer.points[y.second]);
      });
      for (size_t i = 0; i < count; ++i) Store(begin + i, buffer.points[buffer.order[i].second]);
      return;
    }
    auto less = [&](size_t i, size_t j) { return KeyOf(Load(begin + i)) < KeyOf(Load(begin + j)); };
    auto swap = [&](size_t i, size_t j) {
      const Point p = Load(begin + i);
      Store(begin + i, Load(begin + j));
      Store(begin + j, p);
    };
    auto sift = [&](size_t root, size_t n) {
      for (;;) {
        size_t child = 2 * root + 1;
        if (child >= n) return;
        if (child + 1 < n && less(child, child + 1)) ++child;
        if (!less(root, child)) return;
        swap(root, child);
        root = child;
      }
    };
    for (size_t i = count / 2; i-- > 0;) sift(i, count);
    for (size_t n = count; n-- > 1;) {
      swap(0, n);
      sift(0, n);
    }
  }
};

// Gives the pages of v past size() back to the system without reallocating
// (shrink_to_fit would copy and briefly hold both buffers). The vector keeps
// its capacity; the released pages read as zero if it ever grows into them.
template <typename T>
void ReleaseTail(std::vector<T>& v) {
  const size_t page = size_t(sysconf(_SC_PAGESIZE));
  const uintptr_t base = reinterpret_cast<uintptr_t>(v.data());
  const uintptr_t from = (base + v.size() * sizeof(T) + page - 1) / page * page;
  const uintptr_t to = (base + v.capacity() * sizeof(T)) / page * page;
  if (to > from && to - from >= (size_t(1) << 20)) madvise(reinterpret_cast<void*>(from), to - from, MADV_DONTNEED);
}

template <typename T>
bool AllFinite(const std::vector<T>& values, size_t* bad) {
  for (size_t i = 0; i < values.size(); ++i)
    if (!std::isfinite(values[i])) {
      *bad = i;
      return false;
    }
  return true;
}

template <bool kNormals, bool kColors>
void GroupByFace(PointCloud& cloud, const std::vector<uint64_t>& face_begin, size_t face_count,
                 size_t assigned) {
  const PointArrays<kNormals, kColors> arrays{cloud.positions.data(), cloud.normals.data(), cloud.colors.data()};
  // Level 1: ranges of faces, the dropped points in a last bucket.
  const size_t ranges = std::min<size_t>(256, std::max<size_t>(face_count, 1));
  const size_t faces_per_range = (face_count + ranges - 1) / ranges;
  std::vector<size_t> starts(ranges + 1), ends(ranges + 1);
  for (size_t b = 0; b < ranges; ++b) {
    starts[b] = face_begin[std::min(face_count, b * faces_per_range)];
    ends[b] = face_begin[std::min(face_count, (b + 1) * faces_per_range)];
  }
  starts[ranges] = assigned;
  ends[ranges] = cloud.size();
  // Level 2 and the per-face order of each range as a task as soon as level
  // 1 has filled the range: level 1 is sequential, and ranges complete in
  // order, so the other threads sort while this one still distributes.
  using Arrays = PointArrays<kNormals, kColors>;
  tbb::enumerable_thread_specific<typename Arrays::SortBuffer> buffers;
  auto sort_range = [&](size_t b) {
    auto& buffer = buffers.local();
    const size_t first_face = std::min(face_count, b * faces_per_range);
    const size_t last_face = std::min(face_count, (b + 1) * faces_per_range);
    if (first_face == last_face) return;
    std::vector<size_t> next(last_face - first_face), face_end(last_face - first_face);
    for (size_t f = first_face; f < last_face; ++f) {
      next[f - first_face] = face_begin[f];
      face_end[f - first_face] = face_begin[f + 1];
    }
    arrays.FlagSort(next, face_end, [&](uint32_t face) { return size_t(face) - first_face; },
                    [](size_t) {});
    for (size_t f = first_face; f < last_face; ++f) arrays.SortFace(face_begin[f], face_begin[f + 1], buffer);
  };
  tbb::task_group sorts;
  arrays.FlagSort(
      starts, ends, [&](uint32_t face) { return face == kDropped ? ranges : size_t(face) / faces_per_range; },
      [&](size_t b) {
        if (b < ranges) sorts.run([&sort_range, b] { sort_range(b); });
      });
  sorts.wait();
}

}  // namespace

Expected<MappedPoints> AssignPointsToFaces(const Mesh& mesh, PointCloud&& cloud, const AssignOptions& options,
                                           AssignReport* report) {
  if (!(options.max_distance_m > 0) || !std::isfinite(options.max_distance_m))
    return Status::Invalid("point assignment: max_distance_m must be a finite number > 0, got " +
                           std::to_string(options.max_distance_m));
  if (!(options.max_angle_deg >= 0 && options.max_angle_deg <= 180))
    return Status::Invalid("point assignment: max_angle_deg must be in [0, 180], got " +
                           std::to_string(options.max_angle_deg));
  if (options.size < 1)
    return Status::Invalid("point assignment: size must be >= 1, got " + std::to_string(options.size));
  if (!mesh.has_uvs()) return Status::Invalid("point assignment: the mesh has no uvs (unwrap it first)");
  PB_RETURN_IF_ERROR(Validate(mesh).WithContext("point assignment: mesh"));
  PB_RETURN_IF_ERROR(Validate(cloud).WithContext("point assignment: points"));
  size_t bad = 0;
  if (!AllFinite(mesh.positions, &bad))
    return Status::Invalid("point assignment: mesh vertex " + std::to_string(bad / 3) + " has a non-finite position");
  if (!AllFinite(mesh.uvs, &bad))
    return Status::Invalid("point assignment: mesh vertex " + std::to_string(bad / 2) + " has a non-finite uv");
  const size_t face_count = mesh.face_count();
  if (face_count >= kDropped) return Status::Invalid("point assignment: too many faces");
  if (cloud.size() >= kDropped)
    return Status::Invalid("point assignment: more than 2^32 - 2 points; split the cloud");

  // What the sort does not carry is released first.
  cloud.intensities = {};
  cloud.station_ids = {};
  const bool normals = cloud.has_normals();
  const bool colors = cloud.has_colors();
  const size_t n = cloud.size();

  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  auto progress = [&](double f) {
    if (options.progress) options.progress(f);
  };

  // Faces: geometry, and which of them can be chosen (nonzero area).
  std::vector<FaceGeom> geom(face_count);
  std::vector<uint32_t> usable;
  usable.reserve(face_count);
  for (size_t f = 0; f < face_count; ++f) {
    FaceGeom& g = geom[f];
    const uint32_t* v = &mesh.indices[3 * f];
    std::memcpy(g.a, &mesh.positions[3 * size_t(v[0])], 12);
    std::memcpy(g.b, &mesh.positions[3 * size_t(v[1])], 12);
    std::memcpy(g.c, &mesh.positions[3 * size_t(v[2])], 12);
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
      e1[k] = double(g.b[k]) - g.a[k];
      e2[k] = double(g.c[k]) - g.a[k];
    }
    const double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const double len = std::sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
    const double scale = std::max(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2], e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]);
    // Zero area, also to rounding: sin(angle) below 1e-9.
    if (!(len > 1e-9 * scale) || !std::isfinite(len)) {
      g.n[0] = g.n[1] = g.n[2] = 0;
      continue;
    }
    for (int k = 0; k < 3; ++k) g.n[k] = float(cr[k] / len);
    usable.push_back(uint32_t(f));
  }

  const double d = options.max_distance_m;
  Expected<FaceGrid> grid_or = arena.execute([&] { return FaceGrid::Build(geom, usable, d); });
  PB_RETURN_IF_ERROR(grid_or.status());
  const FaceGrid& grid = *grid_or;
  usable = {};
  std::vector<FaceBound> bounds(face_count);
  for (size_t f = 0; f < face_count; ++f) {
    if (geom[f].n[0] == 0 && geom[f].n[1] == 0 && geom[f].n[2] == 0) {
      // Zero area: never in the grid; a bound no distance passes anyway.
      bounds[f] = FaceBound{{0, 0, 0, -std::numeric_limits<float>::infinity()}, {}};
    } else {
      bounds[f] = MakeBound(geom[f]);
    }
  }
  geom = {};
  progress(0.05);

  const double offset[3] = {cloud.origin[0] - mesh.origin[0], cloud.origin[1] - mesh.origin[1],
                            cloud.origin[2] - mesh.origin[2]};
  const double max_d2 = d * d;
  const bool angle_test = normals && options.max_angle_deg < 180;
  const double cos_max = std::cos(options.max_angle_deg * std::numbers::pi / 180);
  const double size = options.size;
  float* positions = cloud.positions.data();
  const float* point_normals = cloud.normals.data();
  const std::vector<uint32_t>& cell_faces = grid.faces();

  tbb::enumerable_thread_specific<Tally> tallies([&] {
    Tally t;
    t.face_counts.assign(face_count, 0);
    return t;
  });
  auto assign_range = [&](size_t begin, size_t end) {
    Tally& tally = tallies.local();
    uint32_t hint = kDropped;
    FaceGrid::Cache cell_cache;
    for (size_t i = begin; i < end; ++i) {
      float* out = positions + 3 * i;
      const double q[3] = {offset[0] + out[0], offset[1] + out[1], offset[2] + out[2]};
      out[0] = out[1] = 0;
      out[2] = std::bit_cast<float>(kDropped);
      if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2])) {
        ++tally.non_finite;
        continue;
      }
      double pn[3] = {0, 0, 0};
      bool test_angle = angle_test;
      double min_dot = 0;
      if (test_angle) {
        for (int k = 0; k < 3; ++k) pn[k] = point_normals[3 * i + k];
        const double len = std::sqrt(pn[0] * pn[0] + pn[1] * pn[1] + pn[2] * pn[2]);
        test_angle = len > 0 && std::isfinite(len);
        min_dot = cos_max * len;
      }
      const auto [cb, ce] = grid.CellOf(q, &cell_cache);
      uint32_t best = kDropped;
      double best_d2 = max_d2;
      bool in_reach = false;
      // The bound comes from float planes and lines, so it can exceed the
      // distance ClosestOnTriangle gives by rounding (~1e-7 of the
      // coordinates); a face is skipped only when its bound is beyond the
      // best distance plus a margin several times that. Skipping on the bound
      // alone made the winner of near-ties depend on the order the faces
      // were considered in, which depends on the previous point, i.e. on
      // how the points were split between threads.
      const double slack_m = 2.5e-7 * (1 + std::abs(q[0]) + std::abs(q[1]) + std::abs(q[2]));
      double skip_d2 = (d + 2 * slack_m) * (d + 2 * slack_m);
      // Candidates in any order: the winner is the least (distance, face),
      // so a tie goes to the lower index. The previous point's face first:
      // scan order is spatially coherent, and a near first answer lets the
      // bound reject most of the others.
      auto consider = [&](uint32_t f) {
        const FaceBound& b = bounds[f];
        const double h = b.plane[0] * q[0] + b.plane[1] * q[1] + b.plane[2] * q[2] - b.plane[3];
        double out = 0;
        for (int k = 0; k < 3; ++k)
          out = std::max(out, b.edge[k][0] * q[0] + b.edge[k][1] * q[1] + b.edge[k][2] * q[2] - b.edge[k][3]);
        const double lb = h * h + out * out;
        if (lb > skip_d2) return;
        const bool angle_ok = !test_angle || pn[0] * b.plane[0] + pn[1] * b.plane[1] + pn[2] * b.plane[2] >= min_dot;
        if (!angle_ok && (in_reach || best != kDropped)) return;
        double d2 = lb;
        if (out > 0) {
          const uint32_t* v = &mesh.indices[3 * size_t(f)];
          double bary[3];
          d2 = ClosestOnTriangle(q, &mesh.positions[3 * size_t(v[0])], &mesh.positions[3 * size_t(v[1])],
                                 &mesh.positions[3 * size_t(v[2])], bary);
        }
        if (d2 > max_d2) return;
        if (!angle_ok) {
          in_reach = true;
          return;
        }
        if (best == kDropped || d2 < best_d2 || (d2 == best_d2 && f < best)) {
          best = f;
          best_d2 = d2;
          const double reach = std::sqrt(d2) + 2 * slack_m;
          skip_d2 = reach * reach;
        }
      };
      const bool hint_here = hint != kDropped && cb < ce;
      if (hint_here) consider(hint);
      for (uint32_t c = cb; c < ce; ++c)
        if (cell_faces[c] != hint || !hint_here) consider(cell_faces[c]);
      hint = best != kDropped ? best : hint;
      if (best == kDropped) {
        ++(in_reach ? tally.wrong_angle : tally.too_far);
        continue;
      }
      const uint32_t* v = &mesh.indices[3 * size_t(best)];
      double best_bary[3];
      ClosestOnTriangle(q, &mesh.positions[3 * size_t(v[0])], &mesh.positions[3 * size_t(v[1])],
                        &mesh.positions[3 * size_t(v[2])], best_bary);
      double u = 0, w = 0;
      for (int k = 0; k < 3; ++k) {
        u += best_bary[k] * mesh.uvs[2 * size_t(v[k])];
        w += best_bary[k] * mesh.uvs[2 * size_t(v[k]) + 1];
      }
      out[0] = float(u * size);
      out[1] = float((1 - w) * size);
      out[2] = std::bit_cast<float>(best);
      ++tally.face_counts[best];
      tally.distance_nm += uint64_t(std::llround(std::sqrt(best_d2) * 1e9));
    }
  };
  // Batches so that progress is reported from the calling thread.
  const size_t batches = 16;
  for (size_t b = 0; b < batches; ++b) {
    const size_t begin = n * b / batches, end = n * (b + 1) / batches;
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, 2048),
                        [&](const tbb::blocked_range<size_t>& r) { assign_range(r.begin(), r.end()); });
    });
    progress(0.05 + 0.75 * double(b + 1) / batches);
  }

  AssignReport tally_report;
  tally_report.points = n;
  MappedPoints mapped;
  mapped.face_begin.assign(face_count + 1, 0);
  uint64_t distance_nm = 0;
  for (const Tally& t : tallies) {
    tally_report.too_far += t.too_far;
    tally_report.wrong_angle += t.wrong_angle;
    tally_report.non_finite += t.non_finite;
    distance_nm += t.distance_nm;
    for (size_t f = 0; f < face_count; ++f) mapped.face_begin[f + 1] += t.face_counts[f];
  }
  tallies.clear();
  for (size_t f = 0; f < face_count; ++f) {
    tally_report.faces_with_points += mapped.face_begin[f + 1] > 0;
    mapped.face_begin[f + 1] += mapped.face_begin[f];
  }
  const size_t assigned = mapped.face_begin[face_count];
  tally_report.assigned = assigned;
  tally_report.mean_distance_m = assigned ? double(distance_nm) * 1e-9 / double(assigned) : 0;

  arena.execute([&] {
    if (normals && colors) GroupByFace<true, true>(cloud, mapped.face_begin, face_count, assigned);
    else if (normals) GroupByFace<true, false>(cloud, mapped.face_begin, face_count, assigned);
    else if (colors) GroupByFace<false, true>(cloud, mapped.face_begin, face_count, assigned);
    else GroupByFace<false, false>(cloud, mapped.face_begin, face_count, assigned);
  });
  progress(0.95);

  // st from 3 floats to 2, in place (index 2i never passes 3i).
  for (size_t i = 0; i < assigned; ++i) {
    positions[2 * i] = positions[3 * i];
    positions[2 * i + 1] = positions[3 * i + 1];
  }
  mapped.st = std::move(cloud.positions);
  mapped.st.resize(2 * assigned);
  ReleaseTail(mapped.st);
  if (colors) {
    mapped.colors = std::move(cloud.colors);
    mapped.colors.resize(3 * assigned);
    ReleaseTail(mapped.colors);
  }
  if (normals) {
    mapped.normals = std::move(cloud.normals);
    mapped.normals.resize(3 * assigned);
    ReleaseTail(mapped.normals);
  }
  cloud = PointCloud{};
  progress(1);
  if (report) *report = tally_report;
  return mapped;
}

}  // namespace pb
