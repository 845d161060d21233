// Fitting a mesh to its scan (see fit.h). The data term is the point-to-plane
// distance of ICP (Chen & Medioni 1992) with the vertices moving along their
// normals, as in normal-displacement fitting of a coarse surface to samples
// (Krishnamurthy & Levoy 1996, "Fitting smooth surfaces to dense polygon
// meshes", section 4); the smoothness term is the membrane energy of the
// displacement field, solved by Jacobi sweeps.
#include "stages/geometry/mesh/fit.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "stages/geometry/core/vec3.h"
#include "stages/geometry/mesh/distance.h"
#include "stages/geometry/mesh/holes.h"  // BorderSides
#include "stages/geometry/mesh/trim.h"  // MeanEdgeLength
#include "stages/geometry/points/knn.h"
#include "stages/geometry/points/spacing.h"

namespace pb {
namespace {

using vec3::V3;
using vec3::Sub;
using vec3::Dot;
using vec3::Cross;
using vec3::Norm;

template <typename Body>
void ParallelRanges(size_t n, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024),
                    [&](const tbb::blocked_range<size_t>& r) { body(r.begin(), r.end()); });
}

V3 Position(const std::vector<float>& positions, uint32_t v) {
  return {positions[3 * size_t{v}], positions[3 * size_t{v} + 1], positions[3 * size_t{v} + 2]};
}

// Non-normalized face normals (twice the area), one per face.
std::vector<V3> FaceCrosses(const Mesh& mesh, const std::vector<float>& positions) {
  std::vector<V3> crosses(mesh.face_count());
  for (size_t f = 0; f < crosses.size(); ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    const V3 a = Position(positions, t[0]);
    crosses[f] = Cross(Sub(Position(positions, t[1]), a), Sub(Position(positions, t[2]), a));
  }
  return crosses;
}

V3 Unit(const V3& a) {
  const double n = Norm(a);
  return n > 0 ? V3{a[0] / n, a[1] / n, a[2] / n} : V3{0, 0, 0};
}

// Area-weighted vertex normals (unit; zero for a vertex of no face or of
// faces without area).
std::vector<V3> VertexNormals(const Mesh& mesh, const std::vector<V3>& crosses) {
  std::vector<V3> normals(mesh.vertex_count(), V3{0, 0, 0});
  for (size_t f = 0; f < crosses.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      V3& n = normals[mesh.indices[3 * f + k]];
      for (int c = 0; c < 3; ++c) n[c] += crosses[f][c];
    }
  }
  for (V3& n : normals) n = Unit(n);
  return normals;
}

// The solution of a x = b for a symmetric positive definite 3 x 3 `a`
// (row-major), by Cramer's rule; zero when a is (nearly) singular.
V3 SolveSymmetric3(const std::array<double, 9>& a, const V3& b) {
  const double c00 = a[4] * a[8] - a[5] * a[7], c01 = a[5] * a[6] - a[3] * a[8],
               c02 = a[3] * a[7] - a[4] * a[6];
  const double det = a[0] * c00 + a[1] * c01 + a[2] * c02;
  const double scale = std::abs(a[0]) + std::abs(a[4]) + std::abs(a[8]);
  if (!(std::abs(det) > 1e-12 * scale * scale * scale)) return {0, 0, 0};
  const double c11 = a[0] * a[8] - a[2] * a[6], c12 = a[1] * a[6] - a[0] * a[7],
               c22 = a[0] * a[4] - a[1] * a[3];
  // a is symmetric, so its cofactor matrix is too.
  return {(c00 * b[0] + c01 * b[1] + c02 * b[2]) / det, (c01 * b[0] + c11 * b[1] + c12 * b[2]) / det,
          (c02 * b[0] + c12 * b[1] + c22 * b[2]) / det};
}

// Barycentric coordinates of q (on the triangle) in (a, b, c); thirds for a
// triangle without area.
std::array<double, 3> Barycentric(const V3& q, const V3& a, const V3& b, const V3& c) {
  const V3 v0 = Sub(b, a), v1 = Sub(c, a), v2 = Sub(q, a);
  const double d00 = Dot(v0, v0), d01 = Dot(v0, v1), d11 = Dot(v1, v1);
  const double d20 = Dot(v2, v0), d21 = Dot(v2, v1);
  const double den = d00 * d11 - d01 * d01;
  if (!(den > 1e-30)) return {1.0 / 3, 1.0 / 3, 1.0 / 3};
  double v = (d11 * d20 - d01 * d21) / den;
  double w = (d00 * d21 - d01 * d20) / den;
  v = std::clamp(v, 0.0, 1.0);
  w = std::clamp(w, 0.0, 1.0 - v);
  return {1 - v - w, v, w};
}

// One point's assignment to its nearest face.
struct Assignment {
  uint32_t face = UINT32_MAX;  // UINT32_MAX: not supported
  float b[3] = {0, 0, 0};
  double d = 0;  // signed distance along the face normal, meters
};

// Assigns every point (mesh frame, `local`) to its nearest face of the mesh
// with `positions` (whose face cross products are `crosses`); unsupported
// points get face UINT32_MAX. With `nearest_signed_m`, also every point's
// signed distance along the nearest face's normal, supported or not. Writes
// `out` (one per point), reusing its memory from the round before: a fresh
// vector each round spent 6 % of the fit in page faults at 3e6 points.
void Assign(const Mesh& mesh, const std::vector<float>& positions, const std::vector<V3>& crosses,
            const std::vector<V3>& local, const std::vector<float>& spacing,
            const PointCloud& points, const FitOptions& options, double edge_floor_m,
            std::vector<uint32_t>& nearest_face, std::vector<Assignment>& out,
            std::vector<double>* nearest_signed_m = nullptr) {
  Mesh work;
  work.positions = positions;
  work.indices = mesh.indices;
  const TriangleBvh bvh(work);
  out.assign(local.size(), Assignment{});
  if (nearest_signed_m) nearest_signed_m->assign(local.size(), 0.0);
  ParallelRanges(local.size(), [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      // Last round's nearest face as the hint: the mesh moved by a fraction
      // of an edge, so it is at or next to this round's (same answer, found
      // with less search: TriangleBvh::Nearest).
      const TriangleBvh::Hit hit = bvh.Nearest(local[i], nearest_face[i]);
      if (hit.face == UINT32_MAX) continue;
      nearest_face[i] = hit.face;
      if (nearest_signed_m) {
        (*nearest_signed_m)[i] = Dot(Sub(local[i], hit.closest), Unit(crosses[hit.face]));
      }
      const double support =
          std::max(options.support_spacings * spacing[i], edge_floor_m);
      if (hit.squared_distance_m2 > support * support) continue;
      const V3 n = Unit(crosses[hit.face]);
      if (n == V3{0, 0, 0}) continue;
      if (points.has_normals()) {
        const V3 pn = {points.normals[3 * i], points.normals[3 * i + 1], points.normals[3 * i + 2]};
        if (Dot(pn, n) < options.min_normal_cosine * Norm(pn)) continue;
      }
      const uint32_t* t = &mesh.indices[3 * size_t{hit.face}];
      const auto b = Barycentric(hit.closest, Position(positions, t[0]),
                                 Position(positions, t[1]), Position(positions, t[2]));
      Assignment& a = out[i];
      a.face = hit.face;
      for (int k = 0; k < 3; ++k) a.b[k] = static_cast<float>(b[k]);
      a.d = Dot(Sub(local[i], hit.closest), n);
    }
  });
}

// The face-turn guard of a move. `place()` writes `moved` from the current
// `scale` of each vertex's move (1 to start); while a face with a moving
// corner turns further than acos(cos_turn) from its normal before the move
// (`before`) or in the input (`input`), or loses its area, the scales of its
// moving corners halve, six times, then drop to 0. `halved` counts the cuts.
template <typename Place>
void GuardFaceTurns(const Mesh& mesh, const std::vector<V3>& before,
                    const std::vector<V3>& input, double cos_turn,
                    const std::vector<uint8_t>& moving, std::vector<double>& scale,
                    const std::vector<float>& moved, const Place& place, uint64_t& halved) {
  const size_t nv = mesh.vertex_count(), nf = mesh.face_count();
  const auto still = [&](uint32_t v) { return !moving[v] || scale[v] == 0; };
  place();
  for (int pass = 0;; ++pass) {
    const std::vector<V3> now = FaceCrosses(mesh, moved);
    std::vector<uint8_t> mark(nv, 0);
    bool bad = false;
    for (size_t f = 0; f < nf; ++f) {
      const uint32_t* t = &mesh.indices[3 * f];
      if (still(t[0]) && still(t[1]) && still(t[2])) continue;
      const double len = Norm(now[f]);
      const double len_before = Norm(before[f]), len_input = Norm(input[f]);
      bool ok = len > 0;
      if (ok && len_before > 0) ok = Dot(now[f], before[f]) >= cos_turn * len * len_before;
      if (ok && len_input > 0) ok = Dot(now[f], input[f]) >= cos_turn * len * len_input;
      if (!ok) {
        bad = true;
        for (int k = 0; k < 3; ++k) mark[t[k]] = 1;
      }
    }
    if (!bad) return;
    for (size_t v = 0; v < nv; ++v) {
      if (!mark[v] || still(static_cast<uint32_t>(v))) continue;
      scale[v] = pass < 6 ? 0.5 * scale[v] : 0.0;
      ++halved;
    }
    place();
  }
}

// The border pass (fit.h, "Borders"): moves border vertices outward in
// their faces' planes so that every border edge passes border_margin_spacings
// of a local spacing beyond the supported points whose closest point lies on
// it. Returns the vertices moved.
uint64_t ExtendBorders(const Mesh& mesh, const std::vector<uint8_t>& border_corner,
                       std::vector<float>& positions, const std::vector<V3>& local, const std::vector<float>& spacing,
                       const PointCloud& points, const FitOptions& options, double edge_floor_m,
                       std::vector<uint32_t>& nearest_face, const std::vector<double>& input_edge,
                       double cos_turn, const std::vector<V3>& input_crosses,
                       std::vector<Assignment>& assigned, FitReport& report) {
  const size_t nv = mesh.vertex_count(), nf = mesh.face_count();
  // Each vertex's number of border sides (`border_corner`: corner k of face
  // f to k + 1, alone on their edge), up to 3.
  std::vector<uint8_t> border_count(nv, 0);
  for (size_t e = 0; e < border_corner.size(); ++e) {
    if (!border_corner[e]) continue;
    const size_t f = e / 3, k = e % 3;
    for (size_t c : {k, (k + 1) % 3}) {
      uint8_t& n = border_count[mesh.indices[3 * f + c]];
      n = static_cast<uint8_t>(std::min(n + 1, 3));
    }
  }
  uint64_t total_moved = 0;
  std::vector<uint8_t> ever_moved(nv, 0);
  const std::vector<float> start = positions;
  for (int pass = 0; pass < 2; ++pass) {
    const std::vector<V3> crosses = FaceCrosses(mesh, positions);
    Assign(mesh, positions, crosses, local, spacing, points, options, edge_floor_m, nearest_face,
           assigned);
    // Outward unit direction of each border edge in its face's plane.
    std::vector<V3> outward(3 * nf, V3{0, 0, 0});
    for (size_t e = 0; e < 3 * nf; ++e) {
      if (!border_corner[e]) continue;
      const size_t f = e / 3;
      const int k = static_cast<int>(e % 3);
      const V3 a = Position(positions, mesh.indices[3 * f + k]);
      const V3 b = Position(positions, mesh.indices[3 * f + (k + 1) % 3]);
      const V3 c = Position(positions, mesh.indices[3 * f + (k + 2) % 3]);
      const V3 ab = Unit(Sub(b, a));
      const V3 ac = Sub(c, a);
      const double along = Dot(ac, ab);
      outward[e] = Unit(V3{along * ab[0] - ac[0], along * ab[1] - ac[1], along * ab[2] - ac[2]});
    }
    // The points beyond each border edge: (edge, s, goal), s the place of
    // the point's closest point along the edge (0 at corner k, 1 at k + 1),
    // goal how far the edge's line must move outward there.
    struct Beyond {
      uint32_t edge;
      double s, goal;
    };
    std::vector<Beyond> beyond_points;
    for (size_t i = 0; i < assigned.size(); ++i) {
      const Assignment& as = assigned[i];
      if (as.face == UINT32_MAX) continue;
      const size_t f = as.face;
      const uint32_t* t = &mesh.indices[3 * f];
      V3 q = {0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        const V3 p = Position(positions, t[k]);
        for (int c = 0; c < 3; ++c) q[c] += as.b[k] * p[c];
      }
      const V3 n = Unit(crosses[f]);
      const V3 pq = Sub(local[i], q);
      const double height = std::abs(Dot(pq, n));
      for (int k = 0; k < 3; ++k) {
        // The edge from corner k to k + 1, opposite corner k + 2.
        const size_t e = 3 * f + k;
        if (!border_corner[e] || as.b[(k + 2) % 3] > 1e-6f) continue;
        // On the edge or past it (>= 0 but for rounding: the closest point
        // is on the edge).
        const double beyond = std::max(0.0, Dot(pq, outward[e]));
        // The surface continuing past the border lies within 45 degrees of
        // the face's plane, give or take the scan's noise (two spacings); a
        // point farther off it is another surface's (a wall behind the
        // border, a mixed return along the ray at a depth step). The spacing
        // is the point's local one but at most the cloud's median: a sparse
        // point (a flying pixel at a depth step, whose spacing is inflated)
        // earns no wider tolerance nor margin.
        const double s_i = std::min<double>(spacing[i], report.median_spacing_m);
        if (height > beyond + 2 * s_i) continue;
        const double goal = beyond + options.border_margin_spacings * s_i;
        const double sa = as.b[k], sb = as.b[(k + 1) % 3];
        beyond_points.push_back(
            {static_cast<uint32_t>(e), sa + sb > 0 ? sb / (sa + sb) : 0.5, goal});
      }
    }
    // Per edge, the offsets (m_a, m_b) of its two ends whose line
    // (1 - s) m_a + s m_b passes over every goal with the least m_a + m_b
    // (the least area added), both >= 0: the upper convex hull of the goals
    // and of (0, 0) and (1, 0), read at s = 1/2 and extended to both ends.
    std::sort(beyond_points.begin(), beyond_points.end(), [](const Beyond& x, const Beyond& y) {
      return x.edge != y.edge ? x.edge < y.edge : x.s != y.s ? x.s < y.s : x.goal < y.goal;
    });
    std::vector<std::array<double, 2>> need(3 * nf, std::array<double, 2>{0, 0});
    std::vector<std::array<double, 2>> hull;
    for (size_t i = 0; i < beyond_points.size();) {
      size_t j = i;
      while (j < beyond_points.size() && beyond_points[j].edge == beyond_points[i].edge) ++j;
      hull.clear();
      const auto push = [&](double hs, double hg) {
        // Monotone chain (s ascending): drop the last point while it lies on
        // or under the line from the one before it to the new one.
        while (hull.size() >= 2) {
          const auto& o = hull[hull.size() - 2];
          const auto& a = hull.back();
          if ((a[0] - o[0]) * (hg - o[1]) - (a[1] - o[1]) * (hs - o[0]) >= 0) {
            hull.pop_back();
          } else {
            break;
          }
        }
        hull.push_back({hs, hg});
      };
      push(0, 0);
      for (size_t k = i; k < j; ++k) push(beyond_points[k].s, beyond_points[k].goal);
      push(1, 0);
      size_t seg = 0;
      while (seg + 2 < hull.size() && hull[seg + 1][0] < 0.5) ++seg;
      const auto& p0 = hull[seg];
      const auto& p1 = hull[seg + 1];
      const double slope = p1[0] > p0[0] ? (p1[1] - p0[1]) / (p1[0] - p0[0]) : 0;
      need[beyond_points[i].edge] = {std::max(0.0, p0[1] - slope * p0[0]),
                                     std::max(0.0, p0[1] + slope * (1 - p0[0]))};
      i = j;
    }
    // Per border vertex of exactly two border edges: the shortest move in
    // the span of their outward directions that meets both needs, at most
    // border_reach_edges of its input mean edge.
    std::vector<std::array<double, 2>> vneed(nv, std::array<double, 2>{0, 0});
    std::vector<std::array<V3, 2>> vdir(nv);
    std::vector<uint8_t> vslots(nv, 0);
    for (size_t e = 0; e < 3 * nf; ++e) {
      if (!border_corner[e]) continue;
      const size_t f = e / 3;
      const int k = static_cast<int>(e % 3);
      const uint32_t ends[2] = {mesh.indices[3 * f + k], mesh.indices[3 * f + (k + 1) % 3]};
      for (int end = 0; end < 2; ++end) {
        const uint32_t v = ends[end];
        if (border_count[v] != 2 || vslots[v] >= 2) continue;
        vdir[v][vslots[v]] = outward[e];
        vneed[v][vslots[v]] = need[e][end];
        ++vslots[v];
      }
    }
    std::vector<V3> move(nv, V3{0, 0, 0});
    bool any = false;
    for (size_t v = 0; v < nv; ++v) {
      if (vslots[v] != 2 || input_edge[v] == 0) continue;
      const double m1 = vneed[v][0], m2 = vneed[v][1];
      if (m1 <= 0 && m2 <= 0) continue;
      const V3 &o1 = vdir[v][0], &o2 = vdir[v][1];
      const double c = Dot(o1, o2);
      const double slack = 1e-9;
      V3 d = {0, 0, 0};
      bool found = false;
      // The shortest candidate meeting both needs: one direction alone,
      // else the corner of the two constraints.
      for (int which = 0; which < 2 && !found; ++which) {
        const int first = m1 >= m2 ? which : 1 - which;
        const V3& o = first == 0 ? o1 : o2;
        const double m = first == 0 ? m1 : m2;
        const V3 cand = {o[0] * m, o[1] * m, o[2] * m};
        if (Dot(cand, o1) >= m1 - slack && Dot(cand, o2) >= m2 - slack) {
          d = cand;
          found = true;
        }
      }
      if (!found && c > -0.5 && c < 0.999) {
        const double alpha = (m1 - c * m2) / (1 - c * c), beta = (m2 - c * m1) / (1 - c * c);
        for (int x = 0; x < 3; ++x) d[x] = alpha * o1[x] + beta * o2[x];
        found = true;
      }
      if (!found) continue;
      // At most border_reach_edges of the vertex's mean edge from where the
      // pass found it, over both rounds of the pass.
      const V3 done = Sub(Position(positions, static_cast<uint32_t>(v)), Position(start, static_cast<uint32_t>(v)));
      V3 total = {done[0] + d[0], done[1] + d[1], done[2] + d[2]};
      const double length = Norm(total);
      const double limit = options.border_reach_edges * input_edge[v];
      if (length > limit) {
        for (int x = 0; x < 3; ++x) total[x] *= limit / length;
      }
      move[v] = Sub(total, done);
      any = true;
    }
    if (!any) break;
    std::vector<uint8_t> moving(nv, 0);
    for (size_t v = 0; v < nv; ++v) moving[v] = Norm(move[v]) > 0;
    std::vector<double> scale(nv, 1.0);
    std::vector<float> moved(positions.size());
    GuardFaceTurns(mesh, crosses, input_crosses, cos_turn, moving, scale, moved, [&] {
      for (size_t v = 0; v < nv; ++v) {
        for (int c = 0; c < 3; ++c) {
          moved[3 * v + c] = static_cast<float>(positions[3 * v + c] + scale[v] * move[v][c]);
        }
      }
    }, report.steps_halved);
    for (size_t v = 0; v < nv; ++v) {
      if (moving[v] && scale[v] > 0 && !ever_moved[v]) {
        ever_moved[v] = 1;
        ++total_moved;
      }
    }
    positions.swap(moved);
  }
  return total_moved;
}

Status CheckOptions(const FitOptions& o) {
  const auto bad = [](const std::string& what) {
    return Status::Invalid("mesh fit: option " + what);
  };
  if (o.iterations < 1) return bad("iterations must be >= 1");
  if (!(o.support_spacings >= 0)) return bad("support_spacings must be >= 0");
  if (!(o.support_edges >= 0)) return bad("support_edges must be >= 0");
  if (!(o.support_spacings > 0 || o.support_edges > 0)) {
    return bad("support_spacings and support_edges cannot both be 0");
  }
  if (!(o.min_normal_cosine >= -1 && o.min_normal_cosine <= 1)) {
    return bad("min_normal_cosine must be in [-1, 1]");
  }
  if (!(o.smoothness >= 0)) return bad("smoothness must be >= 0");
  if (!(o.outside_weight > 0 && o.outside_weight < 1)) return bad("outside_weight must be in (0, 1)");
  if (o.sweeps < 1) return bad("sweeps must be >= 1");
  if (!(o.damping > 0 && o.damping <= 1)) return bad("damping must be in (0, 1]");
  if (!(o.max_step_edges > 0)) return bad("max_step_edges must be > 0");
  if (!(o.max_offset_edges > 0)) return bad("max_offset_edges must be > 0");
  if (!(o.max_turn_deg > 0 && o.max_turn_deg < 180)) return bad("max_turn_deg must be in (0, 180)");
  if (o.spacing_neighbors < 1) return bad("spacing_neighbors must be >= 1");
  if (!(o.border_reach_edges >= 0)) return bad("border_reach_edges must be >= 0");
  if (!(o.border_margin_spacings >= 0)) return bad("border_margin_spacings must be >= 0");
  if (!(o.tangent_weight > 0)) return bad("tangent_weight must be > 0");
  if (!(o.crease_deg >= 0 && o.crease_deg < 180)) return bad("crease_deg must be in [0, 180)");
  return Status::Ok();
}

Expected<Mesh> Fit(const Mesh& mesh, const PointCloud& points, const FitOptions& options,
                   FitReport& report) {
  PB_RETURN_IF_ERROR(Validate(mesh));
  PB_RETURN_IF_ERROR(Validate(points));
  PB_RETURN_IF_ERROR(CheckOptions(options));
  if (mesh.face_count() == 0) return Status::Invalid("mesh fit: the mesh has no faces");
  PB_RETURN_IF_ERROR(CheckFinitePositions(points, "mesh fit"));
  if (points.size() <= static_cast<size_t>(options.spacing_neighbors)) {
    return Status::Invalid("mesh fit: needs more than " +
                           std::to_string(options.spacing_neighbors) +
                           " points for the local spacing, the cloud has " +
                           std::to_string(points.size()));
  }
  for (float x : mesh.positions) {
    if (!std::isfinite(x)) return Status::Invalid("mesh fit: the mesh has a non-finite position");
  }
  PB_ASSIGN_OR_RETURN(KnnIndex index, KnnIndex::Build(points.positions));
  PB_ASSIGN_OR_RETURN(std::vector<float> spacing, LocalSpacing(index, options.spacing_neighbors));
  report.median_spacing_m = MedianLocalSpacing(spacing);
  report.points = points.size();
  report.mean_edge_m = MeanEdgeLength(mesh);
  const double edge_floor = options.support_edges * report.mean_edge_m;

  // The points in the mesh's frame.
  std::vector<V3> local(points.size());
  const V3 shift = {points.origin[0] - mesh.origin[0], points.origin[1] - mesh.origin[1],
                    points.origin[2] - mesh.origin[2]};
  for (size_t i = 0; i < local.size(); ++i) {
    for (int c = 0; c < 3; ++c) local[i][c] = points.positions[3 * i + c] + shift[c];
  }

  const size_t nv = mesh.vertex_count();
  const size_t nf = mesh.face_count();
  // Vertex neighbours (CSR, sorted, unique) and each vertex's mean edge length.
  std::vector<uint32_t> nb_start(nv + 1, 0), nb;
  {
    std::vector<std::pair<uint32_t, uint32_t>> pairs;
    pairs.reserve(6 * nf);
    for (size_t f = 0; f < nf; ++f) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = mesh.indices[3 * f + k], b = mesh.indices[3 * f + (k + 1) % 3];
        pairs.emplace_back(a, b);
        pairs.emplace_back(b, a);
      }
    }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    for (const auto& p : pairs) ++nb_start[p.first + 1];
    for (size_t v = 0; v < nv; ++v) nb_start[v + 1] += nb_start[v];
    nb.resize(pairs.size());
    for (size_t i = 0; i < pairs.size(); ++i) nb[i] = pairs[i].second;
  }

  // Each vertex's mean edge length in the input: the unit of its step per
  // round and of its total offset (the input's, so a vertex that moves and
  // lengthens its edges does not earn a longer leash).
  std::vector<double> input_edge(nv, 0);
  for (size_t v = 0; v < nv; ++v) {
    const uint32_t s = nb_start[v], e = nb_start[v + 1];
    if (s == e) continue;
    const V3 p = Position(mesh.positions, static_cast<uint32_t>(v));
    for (uint32_t j = s; j < e; ++j) input_edge[v] += Norm(Sub(Position(mesh.positions, nb[j]), p));
    input_edge[v] /= static_cast<double>(e - s);
  }
  // Vertex -> face corners (3 f + corner), CSR, in face order.
  std::vector<uint32_t> vf_start(nv + 1, 0), vf(3 * nf);
  for (size_t i = 0; i < 3 * nf; ++i) ++vf_start[mesh.indices[i] + 1];
  for (size_t v = 0; v < nv; ++v) vf_start[v + 1] += vf_start[v];
  {
    std::vector<uint32_t> fill(vf_start.begin(), vf_start.end() - 1);
    for (size_t i = 0; i < 3 * nf; ++i) vf[fill[mesh.indices[i]]++] = static_cast<uint32_t>(i);
  }
  const double cos_turn = std::cos(options.max_turn_deg * std::numbers::pi / 180);
  const std::vector<V3> input_crosses = FaceCrosses(mesh, mesh.positions);
  std::vector<float> positions = mesh.positions;
  std::vector<uint8_t> supported_before(points.size(), 0);
  std::vector<uint32_t> nearest_face(points.size(), UINT32_MAX);  // hints for the next round
  std::vector<Assignment> assigned;  // each assignment's, reused
  // Border sides (BorderSides: 3 f + k alone on its edge) and the vertices
  // on them, for the free directions and the border pass.
  const std::vector<uint8_t> border_sides = BorderSides(mesh);
  std::vector<uint8_t> on_border(nv, 0);
  for (size_t e = 0; e < border_sides.size(); ++e) {
    if (!border_sides[e]) continue;
    on_border[mesh.indices[e]] = 1;
    on_border[mesh.indices[3 * (e / 3) + (e % 3 + 1) % 3]] = 1;
  }

  for (int round = 0; round < options.iterations; ++round) {
    const std::vector<V3> crosses = FaceCrosses(mesh, positions);
    const std::vector<V3> vnormals = VertexNormals(mesh, crosses);
    Assign(mesh, positions, crosses, local, spacing, points, options, edge_floor, nearest_face,
           assigned);
    if (round == 0) {
      double sum_abs = 0, sum = 0;
      size_t outside = 0;
      for (size_t i = 0; i < assigned.size(); ++i) {
        if (assigned[i].face == UINT32_MAX) continue;
        supported_before[i] = 1;
        ++report.supported_before;
        sum_abs += std::abs(assigned[i].d);
        sum += assigned[i].d;
        if (assigned[i].d > 0) ++outside;
      }
      if (report.supported_before > 0) {
        report.mean_abs_distance_before_m = sum_abs / report.supported_before;
        report.mean_signed_distance_before_m = sum / report.supported_before;
        report.outside_fraction_before = static_cast<double>(outside) / report.supported_before;
      }
    }
    // The least-squares problem of the round, in the displacements u along
    // the vertex normals: sum over points of w (sum_k b_k u_k - d)^2 (w by
    // the side of the point, outside_weight), gathered per face as the 3 x 3
    // matrix sum w b b^T and the vector sum w b d (in point order), plus
    // lambda W sum over edges of (u_i - u_j)^2.
    std::vector<std::array<double, 6>> face_m(nf, std::array<double, 6>{});  // 00 11 22 01 02 12
    std::vector<std::array<double, 3>> face_r(nf, std::array<double, 3>{});
    const double w_out = 2 * options.outside_weight, w_in = 2 * (1 - options.outside_weight);
    for (const Assignment& a : assigned) {
      if (a.face == UINT32_MAX) continue;
      auto& m = face_m[a.face];
      const double w = a.d > 0 ? w_out : w_in;
      const double b0 = a.b[0], b1 = a.b[1], b2 = a.b[2];
      m[0] += w * b0 * b0;
      m[1] += w * b1 * b1;
      m[2] += w * b2 * b2;
      m[3] += w * b0 * b1;
      m[4] += w * b0 * b2;
      m[5] += w * b1 * b2;
      face_r[a.face][0] += w * b0 * a.d;
      face_r[a.face][1] += w * b1 * a.d;
      face_r[a.face][2] += w * b2 * a.d;
    }
    std::vector<double> diagonal(nv, 0);
    for (size_t f = 0; f < nf; ++f) {
      for (int k = 0; k < 3; ++k) diagonal[mesh.indices[3 * f + k]] += face_m[f][k];
    }
    double weight_sum = 0;
    size_t with_data = 0;
    for (size_t v = 0; v < nv; ++v) {
      if (diagonal[v] > 0) {
        weight_sum += diagonal[v];
        ++with_data;
      }
    }
    if (with_data == 0) break;
    const double lambda_w = options.smoothness * weight_sum / static_cast<double>(with_data);
    // Gauss-Seidel sweeps in vertex order (sequential: the same result for
    // any thread count), from u = 0.
    const auto m_at = [&](uint32_t f, int i, int j) {
      if (i == j) return face_m[f][i];
      const int lo = std::min(i, j), hi = std::max(i, j);
      return face_m[f][lo == 0 ? (hi == 1 ? 3 : 4) : 5];
    };
    // Each vertex's solved displacement this round, a vector (along its
    // normal unless free_directions).
    std::vector<V3> d(nv, V3{0, 0, 0});
    if (!options.free_directions) {
      std::vector<double> u(nv, 0);
      for (int sweep = 0; sweep < options.sweeps; ++sweep) {
        for (size_t v = 0; v < nv; ++v) {
          double numerator = 0, denominator = 0;
          for (uint32_t j = vf_start[v]; j < vf_start[v + 1]; ++j) {
            const uint32_t f = vf[j] / 3;
            const int c = static_cast<int>(vf[j] % 3);
            denominator += m_at(f, c, c);
            numerator += face_r[f][c];
            for (int k = 0; k < 3; ++k) {
              if (k != c) numerator -= m_at(f, c, k) * u[mesh.indices[3 * size_t{f} + k]];
            }
          }
          const uint32_t s = nb_start[v], e = nb_start[v + 1];
          for (uint32_t j = s; j < e; ++j) numerator += lambda_w * u[nb[j]];
          denominator += lambda_w * static_cast<double>(e - s);
          u[v] = denominator > 0 ? numerator / denominator : 0.0;
        }
      }
      for (size_t v = 0; v < nv; ++v) {
        for (int c = 0; c < 3; ++c) d[v][c] = u[v] * vnormals[v][c];
      }
    } else {
      // Free directions: the displacement D_v is a vector, a point's distance
      // changes by n_f . sum_k b_k D_k, so each sweep solves a vertex's 3 x 3
      // block. Sliding along the vertex's own tangent plane costs as much as
      // the smoothness (lambda W per neighbour), so a vertex in a flat or
      // smooth region keeps moving along its normal, and one on a rounded
      // crease, whose faces face two ways, moves out to the crease.
      std::vector<V3> unit_normal(nf);
      for (size_t f = 0; f < nf; ++f) unit_normal[f] = Unit(crosses[f]);
      // Border vertices move along their normals only, as in version 3 (the
      // border pass moves them outward after the rounds): with half their
      // neighbours missing, the tie of a free one is too weak, and the
      // diagonals of the faces along a rim twist it a few millimeters.
      // Only a vertex on a crease moves freely: one with a face turned
      // more than crease_deg from its normal. Elsewhere the points pull
      // along the normals anyway, and a free vertex would only drift along
      // the surface with the noise.
      const double cos_crease = std::cos(options.crease_deg * std::numbers::pi / 180);
      std::vector<uint8_t> along_normal_only(on_border);
      for (size_t v = 0; v < nv; ++v) {
        if (along_normal_only[v]) continue;
        bool crease = false;
        for (uint32_t j = vf_start[v]; j < vf_start[v + 1] && !crease; ++j) {
          crease = Dot(unit_normal[vf[j] / 3], vnormals[v]) < cos_crease;
        }
        along_normal_only[v] = !crease;
      }
      const double tangent_weight = options.tangent_weight;
      // A face's data for corner c of the vertex: its weight m_cc and its
      // residual with the other corners' displacements of this sweep.
      const auto face_residual = [&](uint32_t f, int c) {
        const V3& n = unit_normal[f];
        double r = face_r[f][c];
        for (int k = 0; k < 3; ++k) {
          if (k != c) r -= m_at(f, c, k) * Dot(n, d[mesh.indices[3 * size_t{f} + k]]);
        }
        return r;
      };
      for (int sweep = 0; sweep < options.sweeps; ++sweep) {
        for (size_t v = 0; v < nv; ++v) {
          const uint32_t s = nb_start[v], e = nb_start[v + 1];
          const V3& nv_v = vnormals[v];
          const double count = static_cast<double>(e - s);
          V3 sum{0, 0, 0};
          for (uint32_t j = s; j < e; ++j) {
            for (int x = 0; x < 3; ++x) sum[x] += d[nb[j]][x];
          }
          const double along = Dot(nv_v, sum);
          if (along_normal_only[v]) {
            // D_v = u N: the block below restricted to the normal,
            // u = (N . rhs) / (N^T A N), with (N . n_f) for each face and
            // only the smoothness's component along N (projecting the 3 x 3
            // solution onto N would not be the minimizer: the block couples
            // u to the tangential terms).
            double numerator = lambda_w * along, denominator = lambda_w * count;
            for (uint32_t j = vf_start[v]; j < vf_start[v + 1]; ++j) {
              const uint32_t f = vf[j] / 3;
              const int c = static_cast<int>(vf[j] % 3);
              const double cosine = Dot(unit_normal[f], nv_v);
              numerator += face_residual(f, c) * cosine;
              denominator += m_at(f, c, c) * cosine * cosine;
            }
            const double u = denominator > 0 ? numerator / denominator : 0.0;
            for (int x = 0; x < 3; ++x) d[v][x] = u * nv_v[x];
            continue;
          }
          std::array<double, 9> a{};  // row-major 3 x 3
          V3 rhs{0, 0, 0};
          for (uint32_t j = vf_start[v]; j < vf_start[v + 1]; ++j) {
            const uint32_t f = vf[j] / 3;
            const int c = static_cast<int>(vf[j] % 3);
            const V3& n = unit_normal[f];
            const double mcc = m_at(f, c, c);
            const double r = face_residual(f, c);
            for (int x = 0; x < 3; ++x) {
              rhs[x] += r * n[x];
              for (int y = 0; y < 3; ++y) a[3 * x + y] += mcc * n[x] * n[y];
            }
          }
          // The smoothness, split along the vertex normal (weight lambda W
          // per neighbour) and across it (tangent_weight of that), plus a
          // tie of the tangential part to the vertex's place.
          for (int x = 0; x < 3; ++x) {
            rhs[x] += lambda_w * (along * nv_v[x] + tangent_weight * (sum[x] - along * nv_v[x]));
            for (int y = 0; y < 3; ++y) {
              const double nn = nv_v[x] * nv_v[y];
              const double tangent = (x == y ? 1.0 : 0.0) - nn;
              a[3 * x + y] += lambda_w * count * (nn + 2 * tangent_weight * tangent);
            }
          }
          // A ridge of a thousandth of the block's trace across the normal,
          // so that without smoothness a flat vertex (data along n_f only)
          // still solves, moving along its normal.
          const double ridge = 1e-3 * (a[0] + a[4] + a[8]);
          for (int x = 0; x < 3; ++x) {
            for (int y = 0; y < 3; ++y) {
              a[3 * x + y] += ridge * ((x == y ? 1.0 : 0.0) - nv_v[x] * nv_v[y]);
            }
          }
          d[v] = SolveSymmetric3(a, rhs);
        }
      }
    }
    // Steps, clamped to a fraction of each vertex's mean edge.
    std::vector<V3> step(nv, V3{0, 0, 0});
    for (size_t v = 0; v < nv; ++v) {
      if (input_edge[v] == 0 || vnormals[v] == V3{0, 0, 0}) continue;
      const double limit = options.max_step_edges * input_edge[v];
      const double length = Norm(d[v]);
      const double take = options.damping * (length > limit ? limit / length : 1.0);
      for (int c = 0; c < 3; ++c) step[v][c] = take * d[v][c];
    }
    // The face-turn guard halves the steps of the vertices of faces that
    // turn too far (or lose their area), then drops them. A vertex never
    // ends farther than max_offset_edges of its edge from where it started.
    std::vector<uint8_t> moving(nv, 0);
    for (size_t v = 0; v < nv; ++v) moving[v] = step[v] != V3{0, 0, 0};
    std::vector<double> scale(nv, 1.0);
    std::vector<float> moved(positions.size());
    GuardFaceTurns(mesh, crosses, input_crosses, cos_turn, moving, scale, moved, [&] {
      for (size_t v = 0; v < nv; ++v) {
        const double s = scale[v];
        V3 p;
        for (int c = 0; c < 3; ++c) p[c] = positions[3 * v + c] + s * step[v][c];
        const V3 p0 = Position(mesh.positions, static_cast<uint32_t>(v));
        const V3 offset = Sub(p, p0);
        const double length = Norm(offset);
        const double limit = options.max_offset_edges * input_edge[v];
        if (s != 0 && moving[v] && length > limit) {
          for (int c = 0; c < 3; ++c) p[c] = p0[c] + offset[c] * (limit / length);
        }
        for (int c = 0; c < 3; ++c) moved[3 * v + c] = static_cast<float>(p[c]);
      }
    }, report.steps_halved);
    positions.swap(moved);
  }

  if (options.border_reach_edges > 0) {
    report.border_vertices_moved =
        ExtendBorders(mesh, border_sides, positions, local, spacing, points, options, edge_floor, nearest_face,
                      input_edge, cos_turn, input_crosses, assigned, report);
  }

  // The figures after, on the points supported before.
  {
    std::vector<double> d;
    Assign(mesh, positions, FaceCrosses(mesh, positions), local, spacing, points, options,
           edge_floor, nearest_face, assigned, &d);
    double sum_abs = 0, sum = 0;
    size_t count = 0, outside = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      if (assigned[i].face != UINT32_MAX) ++report.supported_after;
      if (!supported_before[i]) continue;
      sum_abs += std::abs(d[i]);
      sum += d[i];
      if (d[i] > 0) ++outside;
      ++count;
    }
    if (count > 0) {
      report.mean_abs_distance_after_m = sum_abs / count;
      report.mean_signed_distance_after_m = sum / count;
      report.outside_fraction_after = static_cast<double>(outside) / count;
    }
  }

  Mesh out = mesh;
  out.positions = positions;
  double total_move = 0;
  for (size_t v = 0; v < nv; ++v) {
    const double move = Norm(Sub(Position(positions, static_cast<uint32_t>(v)),
                                 Position(mesh.positions, static_cast<uint32_t>(v))));
    if (move > 0) ++report.vertices_moved;
    report.max_move_m = std::max(report.max_move_m, move);
    total_move += move;
  }
  report.mean_move_m = nv > 0 ? total_move / static_cast<double>(nv) : 0;
  if (out.has_normals()) {
    // The input's normals (a Poisson surface's, smoother than the decimated
    // faces) turned by the rotation that takes each vertex's geometric
    // normal before to the one after: recomputing them from the faces
    // instead would show every facet of the decimated mesh in the lighting.
    const std::vector<V3> before = VertexNormals(mesh, input_crosses);
    const std::vector<V3> after = VertexNormals(out, FaceCrosses(out, out.positions));
    for (size_t v = 0; v < nv; ++v) {
      const V3& a = before[v];
      const V3& b = after[v];
      const double c = Dot(a, b);
      if (a == V3{0, 0, 0} || b == V3{0, 0, 0} || c < -0.99) continue;
      const V3 axis = Cross(a, b);
      const V3 n = {mesh.normals[3 * v], mesh.normals[3 * v + 1], mesh.normals[3 * v + 2]};
      const V3 turned_axis = Cross(axis, n);
      const double k = Dot(axis, n) / (1 + c);
      V3 r;
      for (int i = 0; i < 3; ++i) r[i] = n[i] * c + turned_axis[i] + axis[i] * k;
      r = Unit(r);
      if (r == V3{0, 0, 0}) continue;
      for (int i = 0; i < 3; ++i) out.normals[3 * v + i] = static_cast<float>(r[i]);
    }
  }
  return out;
}

}  // namespace

Expected<Mesh> FitMeshToPoints(const Mesh& mesh, const PointCloud& points,
                               const FitOptions& options, FitReport* report) {
  FitReport local_report;
  FitReport& r = report != nullptr ? *report : local_report;
  r = FitReport{};
  Expected<Mesh> result = Status::Internal("not run");
  if (options.threads > 0) {
    tbb::task_arena arena(options.threads);
    arena.execute([&] { result = Fit(mesh, points, options, r); });
  } else {
    result = Fit(mesh, points, options, r);
  }
  return result;
}

}  // namespace pb
