// Chart segmentation and flattening for UV atlases (used by uv_atlas.cc;
// the public API is uv_atlas.h). Algorithm and references there.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "stages/geometry/core/mesh.h"

namespace pb {

// One chart, flattened: its faces, its vertices and their 2-D coordinates in
// meters after the minimal-rectangle rotation (min corner at the origin).
struct FlatChart {
  std::vector<uint32_t> faces;     // face ids, increasing
  std::vector<uint32_t> vertices;  // original vertex ids, increasing
  std::vector<uint32_t> corners;   // 3 per face of `faces`: index into `vertices`
  std::vector<double> uv_m;        // 2 per vertex
  double width_m = 0;              // extent along u (>= height_m)
  double height_m = 0;
  // A face too small to flatten at the atlas resolution: one face, extent 0,
  // laid out by the caller as a fixed 1-texel right triangle.
  bool isolated = false;
};

// Per face: area-weighted normal (length = 2 * area) and, per edge k (from
// corner k to k+1), the face across it, or kNoFace when the edge is a
// border, non-manifold or joins faces of opposite orientation.
constexpr uint32_t kNoFace = 0xffffffffu;
struct Topology {
  std::vector<std::array<double, 3>> area_normal;
  std::vector<uint32_t> neighbor;  // 3 per face
};
Topology BuildTopology(const Mesh& mesh);

// A chart of `faces` (increasing) with its vertices (increasing) and
// corners; uv_m unset. Shared by both chart makers.
FlatChart ChartSkeleton(const Mesh& mesh, std::vector<uint32_t> faces);

// An orthonormal basis (t1, t2) of the plane with unit normal `normal`,
// right-handed (t1 x t2 = normal), so front faces projected on it stay
// counter-clockwise.
void PlaneBasis(const std::array<double, 3>& normal, std::array<double, 3>* t1,
                std::array<double, 3>* t2);

// The signed area of a 2-D triangle {x0 y0 x1 y1 x2 y2},
// positive when counter-clockwise.
double SignedArea(const std::array<double, 6>& t);

// Rotates a flattened chart (uv_m, any placement) to its minimal-area
// bounding rectangle, landscape, min corner at the origin; sets width_m and
// height_m. Rotations only: no chart is mirrored.
void FitRectangle(FlatChart* chart);

struct ChartOptions {
  double max_angle_deg = 66;
  double max_stretch = 1.25;
  // Faces (by id, increasing) that become isolated one-face charts and that
  // no chart grows into.
  std::vector<uint32_t> isolated_faces;
};

// The charts of `mesh` (valid, see Validate), in the order their seed faces
// were reached (seeds in face order). Every face is in exactly one chart.
// After projection, faces beyond 1.2 x the stretch bound of the chart's
// final mean normal and faces of overlapping pairs are peeled off (the
// remainder and the peeled faces each split into connected components);
// a chart whose every face is involved is split in breadth-first halves.
// `seam_length_m` (may be null) receives the 3-D length of edges between
// faces of different charts. Threads through TBB; the result does not
// depend on the thread count.
std::vector<FlatChart> MakeFlatCharts(const Mesh& mesh, const ChartOptions& options,
                                      double* seam_length_m,
                                      const std::function<void(double)>& progress);

// Axis-aligned boxes {min_x, min_y, max_x, max_y}; calls visit(i, j), i < j,
// once for every pair whose boxes intersect (closed). A uniform grid sized to
// the boxes keeps the work near-linear for boxes of similar size. visit
// returns false to stop early. (A template: the visit is inlined, and it
// runs once per pair, a million times on a 10^5-face chart.)
using Box2 = std::array<double, 4>;
template <typename Visit>
void ForEachIntersectingBoxPair(const std::vector<Box2>& boxes, Visit&& visit);

// Whether the interiors of triangles a and b (3 points each, x y) overlap by
// more than `tolerance` along every separating axis (SAT): triangles that
// only touch along an edge or at a vertex do not overlap.
bool TrianglesOverlap(const std::array<double, 6>& a, const std::array<double, 6>& b,
                      double tolerance);
// Euclidean distance between two triangles (0 if they intersect).
double TriangleDistance(const std::array<double, 6>& a, const std::array<double, 6>& b);

// Whether two faces of a flattened chart overlap: TrianglesOverlap with
// `tolerance` on every pair of faces whose `boxes` (one per face, as
// ForEachIntersectingBoxPair takes them) intersect. Pairs of faces with
// positive signed area that share an edge in opposite directions, or share
// one corner and have disjoint angles there, are disjoint without the test
// (they lie on either side of a line through the shared corners); they are
// most pairs on a mesh.
bool ChartFacesOverlap(const FlatChart& chart, const std::vector<Box2>& boxes, double tolerance);

// Template definition.
template <typename Visit>
void ForEachIntersectingBoxPair(const std::vector<Box2>& boxes, Visit&& visit) {
  const size_t n = boxes.size();
  if (n < 2) return;
  double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300}, mean_size = 0;
  for (const Box2& b : boxes) {
    lo[0] = std::min(lo[0], b[0]);
    lo[1] = std::min(lo[1], b[1]);
    hi[0] = std::max(hi[0], b[2]);
    hi[1] = std::max(hi[1], b[3]);
    mean_size += std::max(b[2] - b[0], b[3] - b[1]);
  }
  mean_size /= double(n);
  const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], 1e-300});
  // Cells about the mean box size, at most ~4 n of them.
  double cell = std::max(mean_size, extent / std::sqrt(4.0 * double(n)));
  cell = std::max(cell, extent / 4096.0);
  const int64_t nx = std::max<int64_t>(1, int64_t((hi[0] - lo[0]) / cell) + 1);
  const int64_t ny = std::max<int64_t>(1, int64_t((hi[1] - lo[1]) / cell) + 1);
  auto cell_x = [&](double x) {
    return int32_t(std::clamp<int64_t>(int64_t((x - lo[0]) / cell), 0, nx - 1));
  };
  auto cell_y = [&](double y) {
    return int32_t(std::clamp<int64_t>(int64_t((y - lo[1]) / cell), 0, ny - 1));
  };
  // Each box's cell range, computed once.
  std::vector<std::array<int32_t, 4>> range(n);
  std::vector<uint32_t> offsets(size_t(nx * ny) + 1, 0);
  for (size_t i = 0; i < n; ++i) {
    const Box2& b = boxes[i];
    range[i] = {cell_x(b[0]), cell_y(b[1]), cell_x(b[2]), cell_y(b[3])};
    for (int64_t y = range[i][1]; y <= range[i][3]; ++y) {
      for (int64_t x = range[i][0]; x <= range[i][2]; ++x) ++offsets[size_t(y * nx + x) + 1];
    }
  }
  for (size_t i = 0; i + 1 < offsets.size(); ++i) offsets[i + 1] += offsets[i];
  // The cells' members with their boxes and min cells, in cell order (read
  // in sequence, not through the box index).
  struct Member {
    Box2 box;
    uint32_t id;
    int32_t cx, cy;
  };
  std::vector<Member> members(offsets.back());
  {
    std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (uint32_t i = 0; i < n; ++i) {
      const auto& r = range[i];
      for (int64_t y = r[1]; y <= r[3]; ++y) {
        for (int64_t x = r[0]; x <= r[2]; ++x) {
          members[fill[size_t(y * nx + x)]++] = {boxes[i], i, r[0], r[1]};
        }
      }
    }
  }
  for (int32_t cy = 0; cy < ny; ++cy) {
    for (int32_t cx = 0; cx < nx; ++cx) {
      const size_t c = size_t(cy * nx + cx);
      for (uint32_t p = offsets[c]; p < offsets[c + 1]; ++p) {
        const Member& mp = members[p];
        for (uint32_t q = p + 1; q < offsets[c + 1]; ++q) {
          const Member& mq = members[q];
          const Box2 &a = mp.box, &b = mq.box;
          if (a[0] > b[2] || b[0] > a[2] || a[1] > b[3] || b[1] > a[3]) continue;
          // Visit each pair once: in the cell of its intersection's min
          // corner (the cell of the larger min, the cells being monotone).
          if (std::max(mp.cx, mq.cx) != cx || std::max(mp.cy, mq.cy) != cy) continue;
          const uint32_t i = std::min(mp.id, mq.id), j = std::max(mp.id, mq.id);
          if (!visit(i, j)) return;
        }
      }
    }
  }
}

}  // namespace pb
