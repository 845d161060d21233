// Chart segmentation and flattening for UV atlases (used by uv_atlas.cc;
// the public API is uv_atlas.h). Algorithm and references there.
#pragma once

#include <array>
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
// returns false to stop early.
using Box2 = std::array<double, 4>;
void ForEachIntersectingBoxPair(const std::vector<Box2>& boxes,
                                const std::function<bool(uint32_t, uint32_t)>& visit);

// Whether the interiors of triangles a and b (3 points each, x y) overlap by
// more than `tolerance` along every separating axis (SAT): triangles that
// only touch along an edge or at a vertex do not overlap.
bool TrianglesOverlap(const std::array<double, 6>& a, const std::array<double, 6>& b,
                      double tolerance);
// Euclidean distance between two triangles (0 if they intersect).
double TriangleDistance(const std::array<double, 6>& a, const std::array<double, 6>& b);

}  // namespace pb
