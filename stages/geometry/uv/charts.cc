// Chart growing, planar flattening, overlap splitting and minimal-rectangle
// rotation for UV atlases.
//
// Charts follow Blender's Smart UV Project criterion (faces whose normals
// stay within an angle of the chart's), grown by breadth-first flood fill
// across manifold edges instead of Blender's projection-direction voting, so
// a chart is always edge-connected. Departures: (1) a second bound,
// max_stretch, limits each face's planar-projection stretch 1/cos(angle);
// Blender's 66 deg alone compresses faces by up to cos 66 = 0.41 on curved
// surfaces; (2) a chart whose projection folds or overlaps itself is split in
// two (breadth-first halves) until none does. The minimal-area rectangle uses
// the fact that it has a side on the convex hull (Freeman & Shapira 1975).
#include "stages/geometry/uv/charts.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>

#include "stages/geometry/core/vec3.h"

namespace pb {
namespace {

using vec3::V3;
using vec3::Sub;
using vec3::Dot;
using vec3::Cross;
using vec3::Norm;


constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

}  // namespace

FlatChart ChartSkeleton(const Mesh& mesh, std::vector<uint32_t> faces) {
  // Local vertex numbers through a per-thread table over the mesh's
  // vertices (kNone outside the chart, restored before returning) instead
  // of sorting every corner and a binary search per corner: that was 9 % of
  // the conformal unwrap of a 10^6-face scan, whose charts are made and
  // remade while they are split.
  thread_local std::vector<uint32_t> local;
  if (local.size() < mesh.vertex_count()) local.assign(mesh.vertex_count(), kNone);
  FlatChart chart;
  chart.faces = std::move(faces);
  uint32_t lowest = kNone, highest = 0;
  for (uint32_t f : chart.faces) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh.indices[3 * size_t(f) + k];
      if (local[v] != kNone) continue;
      local[v] = 0;
      chart.vertices.push_back(v);
      lowest = std::min(lowest, v);
      highest = std::max(highest, v);
    }
  }
  // Increasing vertex order: a scan of the marked range when the chart's
  // vertices are dense in it, else a sort.
  const size_t n = chart.vertices.size();
  if (n > 0 && size_t(highest - lowest) < 8 * n) {
    size_t i = 0;
    for (uint32_t v = lowest; i < n; ++v) {
      if (local[v] != kNone) chart.vertices[i++] = v;
    }
  } else {
    std::sort(chart.vertices.begin(), chart.vertices.end());
  }
  for (size_t i = 0; i < n; ++i) local[chart.vertices[i]] = uint32_t(i);
  chart.corners.resize(3 * chart.faces.size());
  for (size_t i = 0; i < chart.faces.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      chart.corners[3 * i + k] = local[mesh.indices[3 * size_t(chart.faces[i]) + k]];
    }
  }
  for (uint32_t v : chart.vertices) local[v] = kNone;
  return chart;
}

void PlaneBasis(const V3& normal, V3* t1, V3* t2) {
  const int least = std::fabs(normal[0]) <= std::fabs(normal[1])
                        ? (std::fabs(normal[0]) <= std::fabs(normal[2]) ? 0 : 2)
                        : (std::fabs(normal[1]) <= std::fabs(normal[2]) ? 1 : 2);
  V3 helper{0, 0, 0};
  helper[least] = 1;
  const V3 c = Cross(helper, normal);
  const double n = Norm(c);
  *t1 = n > 0 ? V3{c[0] / n, c[1] / n, c[2] / n} : V3{0, 0, 0};
  *t2 = Cross(normal, *t1);
}

double SignedArea(const std::array<double, 6>& t) {
  return 0.5 * ((t[2] - t[0]) * (t[5] - t[1]) - (t[4] - t[0]) * (t[3] - t[1]));
}

Topology BuildTopology(const Mesh& mesh) {
  const size_t faces = mesh.face_count(), vertices = mesh.vertex_count();
  Topology topo;
  topo.area_normal.resize(faces);
  topo.neighbor.assign(3 * faces, kNone);
  const uint32_t* idx = mesh.indices.data();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, faces, 4096), [&](const auto& r) {
    for (size_t f = r.begin(); f < r.end(); ++f) {
      const V3 a = VertexPosition(mesh, idx[3 * f]), b = VertexPosition(mesh, idx[3 * f + 1]),
               c = VertexPosition(mesh, idx[3 * f + 2]);
      topo.area_normal[f] = Cross(Sub(b, a), Sub(c, a));
    }
  });
  // Vertex -> faces (CSR), faces in increasing order.
  std::vector<uint32_t> offsets(vertices + 1, 0);
  for (size_t i = 0; i < mesh.indices.size(); ++i) ++offsets[idx[i] + 1];
  for (size_t v = 0; v < vertices; ++v) offsets[v + 1] += offsets[v];
  std::vector<uint32_t> incident(mesh.indices.size());
  {
    std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (size_t i = 0; i < mesh.indices.size(); ++i) incident[fill[idx[i]]++] = uint32_t(i / 3);
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, faces, 4096), [&](const auto& r) {
    for (size_t f = r.begin(); f < r.end(); ++f) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = idx[3 * f + k], b = idx[3 * f + (k + 1) % 3];
        uint32_t opposite = kNone;
        int opposite_count = 0, same_count = 0;
        for (uint32_t i = offsets[a]; i < offsets[a + 1]; ++i) {
          const uint32_t g = incident[i];
          if (g == f) continue;
          for (int m = 0; m < 3; ++m) {
            const uint32_t ga = idx[3 * size_t(g) + m], gb = idx[3 * size_t(g) + (m + 1) % 3];
            if (ga == b && gb == a) {
              opposite = g;
              ++opposite_count;
            } else if (ga == a && gb == b) {
              ++same_count;
            }
          }
        }
        if (opposite_count == 1 && same_count == 0) topo.neighbor[3 * f + k] = opposite;
      }
    }
  });
  return topo;
}

namespace {

V3 Normalized(const V3& v) {
  const double n = Norm(v);
  return n > 0 ? V3{v[0] / n, v[1] / n, v[2] / n} : V3{0, 0, 1};
}

// Flood fill from seeds in face order; returns the faces of each chart.
std::vector<std::vector<uint32_t>> GrowCharts(const Topology& topo, double min_cos,
                                              const std::vector<uint32_t>& isolated) {
  const size_t faces = topo.area_normal.size();
  std::vector<uint32_t> chart_of(faces, kNone);
  constexpr uint32_t kIsolated = kNone - 1;
  for (uint32_t f : isolated) chart_of[f] = kIsolated;
  std::vector<std::vector<uint32_t>> charts;
  std::deque<uint32_t> queue;
  for (size_t seed = 0; seed < faces; ++seed) {
    if (chart_of[seed] != kNone) continue;
    const uint32_t chart = uint32_t(charts.size());
    charts.emplace_back();
    std::vector<uint32_t>& members = charts.back();
    V3 sum = topo.area_normal[seed];
    chart_of[seed] = chart;
    queue.push_back(uint32_t(seed));
    while (!queue.empty()) {
      const uint32_t f = queue.front();
      queue.pop_front();
      members.push_back(f);
      const V3 mean = Normalized(sum);
      for (int k = 0; k < 3; ++k) {
        const uint32_t g = topo.neighbor[3 * size_t(f) + k];
        if (g == kNone || chart_of[g] != kNone) continue;
        const V3& n = topo.area_normal[g];
        const double length = Norm(n);
        // Degenerate faces (no normal) join whatever chart reaches them.
        if (length > 0 && Dot(n, mean) < min_cos * length) continue;
        chart_of[g] = chart;
        sum = {sum[0] + n[0], sum[1] + n[1], sum[2] + n[2]};
        queue.push_back(g);
      }
    }
    std::sort(members.begin(), members.end());
  }
  return charts;
}

using Tri2 = std::array<double, 6>;

Tri2 ChartTriangle(const FlatChart& chart, size_t i) {
  Tri2 t;
  for (int k = 0; k < 3; ++k) {
    const uint32_t v = chart.corners[3 * i + k];
    t[2 * k] = chart.uv_m[2 * v];
    t[2 * k + 1] = chart.uv_m[2 * v + 1];
  }
  return t;
}

// Projects `faces` on the plane of their mean normal (right-handed basis, so
// front faces stay counter-clockwise).
FlatChart Project(const Mesh& mesh, const Topology& topo, std::vector<uint32_t> faces) {
  V3 sum{0, 0, 0};
  for (uint32_t f : faces) {
    const V3& n = topo.area_normal[f];
    sum = {sum[0] + n[0], sum[1] + n[1], sum[2] + n[2]};
  }
  const V3 normal = Normalized(sum);
  V3 t1, t2;
  PlaneBasis(normal, &t1, &t2);
  FlatChart chart = ChartSkeleton(mesh, std::move(faces));
  chart.uv_m.resize(2 * chart.vertices.size());
  for (size_t i = 0; i < chart.vertices.size(); ++i) {
    const V3 p = VertexPosition(mesh, chart.vertices[i]);
    chart.uv_m[2 * i] = Dot(p, t1);
    chart.uv_m[2 * i + 1] = Dot(p, t2);
  }
  return chart;
}

enum class Flatness { kOk, kFolded, kDrifted };

// kOk when the flattened chart is one-to-one (every non-degenerate face
// counter-clockwise, no two faces overlapping) and no face lies beyond
// `min_cos` of the projection plane's normal (kDrifted: `drifted` lists
// them, positions in chart.faces); else kFolded.
Flatness CheckFlat(const FlatChart& chart, const Topology& topo, double min_cos,
                   std::vector<uint32_t>* drifted) {
  const size_t n = chart.faces.size();
  if (n <= 1) return Flatness::kOk;
  std::vector<Box2> boxes(n);
  double extent = 0;
  bool folded = false;
  for (size_t i = 0; i < n; ++i) {
    const Tri2 t = ChartTriangle(chart, i);
    const double area3 = 0.5 * Norm(topo.area_normal[chart.faces[i]]);
    const double area2 = SignedArea(t);
    // A projected area far below the 3-D one is a near-fold: reject it too.
    if (area3 > 0 && area2 <= 1e-6 * area3) folded = true;
    if (area3 > 0 && area2 < min_cos * area3) drifted->push_back(uint32_t(i));
    boxes[i] = {std::min({t[0], t[2], t[4]}), std::min({t[1], t[3], t[5]}),
                std::max({t[0], t[2], t[4]}), std::max({t[1], t[3], t[5]})};
    extent = std::max({extent, boxes[i][2] - boxes[i][0], boxes[i][3] - boxes[i][1]});
  }
  // Peeling drifted faces also removes flipped ones; split only otherwise.
  if (!drifted->empty() && drifted->size() < n) return Flatness::kDrifted;
  drifted->clear();
  if (folded) return Flatness::kFolded;
  // Faces of overlapping pairs are peeled off like drifted ones (a fold is
  // usually a small wrinkle); halves only when every face is involved.
  const double tolerance = 1e-9 * extent;
  ForEachIntersectingBoxPair(boxes, [&](uint32_t i, uint32_t j) {
    if (TrianglesOverlap(ChartTriangle(chart, i), ChartTriangle(chart, j), tolerance)) {
      drifted->push_back(i);
      drifted->push_back(j);
    }
    return true;
  });
  if (drifted->empty()) return Flatness::kOk;
  std::sort(drifted->begin(), drifted->end());
  drifted->erase(std::unique(drifted->begin(), drifted->end()), drifted->end());
  if (drifted->size() < n) return Flatness::kDrifted;
  drifted->clear();
  return Flatness::kFolded;
}

// Where each face sits in the round's pending charts: chart `owner[f]`,
// index `position[f]` in its face list. Charts are disjoint, so threads fill
// and read it without conflict.
struct FaceSlots {
  std::vector<uint32_t> owner, position;
};

// The connected components of pending chart `chart` (faces increasing)
// across manifold edges between faces with equal `keep`, in order of their
// lowest face.
std::vector<std::vector<uint32_t>> Components(const std::vector<uint32_t>& faces, uint32_t chart,
                                              const std::vector<char>& keep, const Topology& topo,
                                              const FaceSlots& slots) {
  std::vector<char> done(faces.size(), 0);
  std::vector<std::vector<uint32_t>> parts;
  std::vector<uint32_t> stack;
  for (size_t start = 0; start < faces.size(); ++start) {
    if (done[start]) continue;
    std::vector<uint32_t> part;
    stack.assign(1, faces[start]);
    done[start] = 1;
    while (!stack.empty()) {
      const uint32_t f = stack.back();
      stack.pop_back();
      part.push_back(f);
      for (int k = 0; k < 3; ++k) {
        const uint32_t g = topo.neighbor[3 * size_t(f) + k];
        if (g == kNone || slots.owner[g] != chart) continue;
        const size_t i = slots.position[g];
        if (done[i] || keep[i] != keep[start]) continue;
        done[i] = 1;
        stack.push_back(g);
      }
    }
    std::sort(part.begin(), part.end());
    parts.push_back(std::move(part));
  }
  return parts;
}

// Breadth-first halves: the first half of the faces reached from the
// chart's first face, then each connected component of the rest.
std::vector<std::vector<uint32_t>> SplitInHalves(const std::vector<uint32_t>& faces, uint32_t chart,
                                                 const Topology& topo, const FaceSlots& slots) {
  auto in_chart = [&](uint32_t f) { return slots.owner[f] == chart; };
  std::vector<char> taken(faces.size(), 0);
  auto local = [&](uint32_t f) { return size_t(slots.position[f]); };
  std::vector<std::vector<uint32_t>> parts;
  size_t budget = (faces.size() + 1) / 2;
  for (size_t start = 0; start < faces.size(); ++start) {
    if (taken[start]) continue;
    std::vector<uint32_t> part;
    std::deque<uint32_t> queue{faces[start]};
    taken[start] = 1;
    while (!queue.empty() && part.size() < budget) {
      const uint32_t f = queue.front();
      queue.pop_front();
      part.push_back(f);
      for (int k = 0; k < 3; ++k) {
        const uint32_t g = topo.neighbor[3 * size_t(f) + k];
        if (g == kNone || !in_chart(g) || taken[local(g)]) continue;
        taken[local(g)] = 1;
        queue.push_back(g);
      }
    }
    for (uint32_t f : queue) taken[local(f)] = 0;  // reached but not kept
    budget = faces.size();                         // only the first part is halved
    std::sort(part.begin(), part.end());
    parts.push_back(std::move(part));
  }
  return parts;
}

}  // namespace

// Rotates the chart to its minimal-area bounding rectangle, landscape, with
// its min corner at the origin. Rotations only: no chart is mirrored.
void FitRectangle(FlatChart* chart) {
  const size_t n = chart->vertices.size();
  std::vector<std::array<double, 2>> points(n);
  for (size_t i = 0; i < n; ++i) points[i] = {chart->uv_m[2 * i], chart->uv_m[2 * i + 1]};
  std::sort(points.begin(), points.end());
  // Andrew's monotone chain.
  std::vector<std::array<double, 2>> hull(2 * n);
  size_t h = 0;
  auto cross = [](const auto& o, const auto& a, const auto& b) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
  };
  for (size_t i = 0; i < n; ++i) {
    while (h >= 2 && cross(hull[h - 2], hull[h - 1], points[i]) <= 0) --h;
    hull[h++] = points[i];
  }
  for (size_t i = n - 1, lower = h + 1; i-- > 0;) {
    while (h >= lower && cross(hull[h - 2], hull[h - 1], points[i]) <= 0) --h;
    hull[h++] = points[i];
  }
  hull.resize(h > 1 ? h - 1 : h);
  double best_area = std::numeric_limits<double>::infinity();
  double best_e[2] = {1, 0};
  for (size_t i = 0; i < hull.size(); ++i) {
    const auto& a = hull[i];
    const auto& b = hull[(i + 1) % hull.size()];
    double ex = b[0] - a[0], ey = b[1] - a[1];
    const double length = std::hypot(ex, ey);
    if (!(length > 0)) continue;
    ex /= length;
    ey /= length;
    double min_u = 1e300, max_u = -1e300, min_v = 1e300, max_v = -1e300;
    for (const auto& p : hull) {
      const double u = p[0] * ex + p[1] * ey, v = -p[0] * ey + p[1] * ex;
      min_u = std::min(min_u, u);
      max_u = std::max(max_u, u);
      min_v = std::min(min_v, v);
      max_v = std::max(max_v, v);
    }
    const double area = (max_u - min_u) * (max_v - min_v);
    if (area < best_area * (1 - 1e-12)) {
      best_area = area;
      best_e[0] = ex;
      best_e[1] = ey;
    }
  }
  double min_u = 1e300, max_u = -1e300, min_v = 1e300, max_v = -1e300;
  for (size_t i = 0; i < n; ++i) {
    const double x = chart->uv_m[2 * i], y = chart->uv_m[2 * i + 1];
    const double u = x * best_e[0] + y * best_e[1], v = -x * best_e[1] + y * best_e[0];
    chart->uv_m[2 * i] = u;
    chart->uv_m[2 * i + 1] = v;
    min_u = std::min(min_u, u);
    max_u = std::max(max_u, u);
    min_v = std::min(min_v, v);
    max_v = std::max(max_v, v);
  }
  const double width = max_u - min_u, height = max_v - min_v;
  const bool turn = height > width;  // a quarter turn makes it landscape
  for (size_t i = 0; i < n; ++i) {
    const double u = chart->uv_m[2 * i] - min_u, v = chart->uv_m[2 * i + 1] - min_v;
    chart->uv_m[2 * i] = turn ? height - v : u;
    chart->uv_m[2 * i + 1] = turn ? u : v;
  }
  chart->width_m = turn ? height : width;
  chart->height_m = turn ? width : height;
}

std::vector<FlatChart> MakeFlatCharts(const Mesh& mesh, const ChartOptions& options,
                                      double* seam_length_m,
                                      const std::function<void(double)>& progress) {
  const Topology topo = BuildTopology(mesh);
  if (progress) progress(0.2);
  const double min_cos = std::max(std::cos(options.max_angle_deg * M_PI / 180.0),
                                  1.0 / std::max(options.max_stretch, 1.0));
  std::vector<std::vector<uint32_t>> pending = GrowCharts(topo, min_cos, options.isolated_faces);
  // Growth compares faces with the running mean; the final mean may have
  // moved. Faces beyond 1.2 x the stretch bound of it are peeled off.
  const double drift_cos = min_cos / 1.2;
  FaceSlots slots;
  slots.owner.assign(mesh.face_count(), kNone);
  slots.position.assign(mesh.face_count(), 0);
  if (progress) progress(0.4);

  // Flatten; split what folds, until nothing does. Order is kept: a split
  // chart's parts take its place.
  std::vector<FlatChart> charts;
  for (int round = 0; !pending.empty(); ++round) {
    std::vector<FlatChart> flat(pending.size());
    std::vector<Flatness> ok(pending.size(), Flatness::kOk);
    std::vector<std::vector<std::vector<uint32_t>>> parts(pending.size());
    // Faces of charts settled in earlier rounds must not keep their old
    // pending index: Components and SplitInHalves would take them for faces
    // of the chart now at that index (and write out of its bounds).
    std::fill(slots.owner.begin(), slots.owner.end(), kNone);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, pending.size(), 16), [&](const auto& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) {
        for (size_t j = 0; j < pending[i].size(); ++j) {
          slots.owner[pending[i][j]] = uint32_t(i);
          slots.position[pending[i][j]] = uint32_t(j);
        }
      }
    });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, pending.size(), 16), [&](const auto& r) {
      std::vector<uint32_t> drifted;
      for (size_t i = r.begin(); i < r.end(); ++i) {
        flat[i] = Project(mesh, topo, pending[i]);
        drifted.clear();
        ok[i] = CheckFlat(flat[i], topo, drift_cos, &drifted);
        if (ok[i] == Flatness::kDrifted) {
          std::vector<char> keep(pending[i].size(), 1);
          for (uint32_t j : drifted) keep[j] = 0;
          parts[i] = Components(pending[i], uint32_t(i), keep, topo, slots);
        } else if (ok[i] == Flatness::kFolded) {
          parts[i] = SplitInHalves(pending[i], uint32_t(i), topo, slots);
        }
        if (ok[i] != Flatness::kOk) flat[i] = FlatChart();
      }
    });
    // `charts` holds the charts that passed in earlier rounds and an empty
    // placeholder where each pending one goes.
    if (round == 0) charts.resize(flat.size());
    std::vector<FlatChart> merged;
    std::vector<std::vector<uint32_t>> next_pending;
    size_t pi = 0;
    for (FlatChart& c : charts) {
      if (!c.faces.empty()) {
        merged.push_back(std::move(c));
        continue;
      }
      if (ok[pi] == Flatness::kOk) {
        merged.push_back(std::move(flat[pi]));
      } else {
        for (auto& part : parts[pi]) {
          merged.emplace_back();  // placeholder
          next_pending.push_back(std::move(part));
        }
      }
      ++pi;
    }
    charts = std::move(merged);
    pending = std::move(next_pending);
  }
  if (progress) progress(0.8);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, charts.size(), 16), [&](const auto& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) FitRectangle(&charts[i]);
  });
  for (uint32_t f : options.isolated_faces) {
    FlatChart chart;
    chart.faces = {f};
    chart.isolated = true;
    for (int k = 0; k < 3; ++k) chart.vertices.push_back(mesh.indices[3 * size_t(f) + k]);
    std::sort(chart.vertices.begin(), chart.vertices.end());
    chart.vertices.erase(std::unique(chart.vertices.begin(), chart.vertices.end()),
                         chart.vertices.end());
    for (int k = 0; k < 3; ++k) {
      chart.corners.push_back(
          uint32_t(std::lower_bound(chart.vertices.begin(), chart.vertices.end(),
                                    mesh.indices[3 * size_t(f) + k]) -
                   chart.vertices.begin()));
    }
    chart.uv_m.assign(2 * chart.vertices.size(), 0.0);
    charts.push_back(std::move(chart));
  }

  if (seam_length_m != nullptr) {
    std::vector<uint32_t> chart_of(mesh.face_count());
    for (size_t c = 0; c < charts.size(); ++c) {
      for (uint32_t f : charts[c].faces) chart_of[f] = uint32_t(c);
    }
    // Interior edges between charts, each counted from its lower face.
    double seam = 0;
    for (size_t f = 0; f < mesh.face_count(); ++f) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t g = topo.neighbor[3 * f + k];
        if (g == kNone || g < f || chart_of[g] == chart_of[f]) continue;
        seam += Norm(Sub(VertexPosition(mesh, mesh.indices[3 * f + k]),
                         VertexPosition(mesh, mesh.indices[3 * f + (k + 1) % 3])));
      }
    }
    *seam_length_m = seam;
  }
  if (progress) progress(0.9);
  return charts;
}

bool TrianglesOverlap(const Tri2& a, const Tri2& b, double tolerance) {
  for (const Tri2* t : {&a, &b}) {
    for (int k = 0; k < 3; ++k) {
      const int m = (k + 1) % 3;
      // Axis not normalized: compare the overlap with tolerance * |axis|.
      const double nx = -((*t)[2 * m + 1] - (*t)[2 * k + 1]), ny = (*t)[2 * m] - (*t)[2 * k];
      const double length2 = nx * nx + ny * ny;
      if (!(length2 > 0)) continue;
      double min_a = 1e300, max_a = -1e300, min_b = 1e300, max_b = -1e300;
      for (int v = 0; v < 3; ++v) {
        const double pa = a[2 * v] * nx + a[2 * v + 1] * ny;
        const double pb = b[2 * v] * nx + b[2 * v + 1] * ny;
        min_a = std::min(min_a, pa);
        max_a = std::max(max_a, pa);
        min_b = std::min(min_b, pb);
        max_b = std::max(max_b, pb);
      }
      const double overlap = std::min(max_a, max_b) - std::max(min_a, min_b);
      if (overlap <= 0 || overlap * overlap <= tolerance * tolerance * length2) return false;
    }
  }
  return true;
}

bool ChartFacesOverlap(const FlatChart& chart, const std::vector<Box2>& boxes, double tolerance) {
  const size_t faces = chart.faces.size();
  std::vector<char> ccw(faces);
  for (size_t i = 0; i < faces; ++i) ccw[i] = SignedArea(ChartTriangle(chart, i)) > 0;
  auto point = [&](uint32_t v) {
    return std::array<double, 2>{chart.uv_m[2 * size_t(v)], chart.uv_m[2 * size_t(v) + 1]};
  };
  auto cross = [](const std::array<double, 2>& o, const std::array<double, 2>& a,
                  const std::array<double, 2>& b) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
  };
  bool overlap = false;
  ForEachIntersectingBoxPair(boxes, [&](uint32_t i, uint32_t j) {
    const uint32_t* a = &chart.corners[3 * size_t(i)];
    const uint32_t* b = &chart.corners[3 * size_t(j)];
    if (ccw[i] && ccw[j]) {
      // Shared corners: a[ka] == b[kb].
      int shared = 0, ka = 0, kb = 0;
      for (int x = 0; x < 3; ++x) {
        for (int y = 0; y < 3; ++y) {
          if (a[x] == b[y]) {
            ++shared;
            ka = x;
            kb = y;
          }
        }
      }
      if (shared == 2) {
        // The shared edge a[ka] -> a[ka + 1] in a is b[kb] <- b[kb - 1] in
        // b (or the other way around when the last match is the edge's
        // end): opposite directions put the third corners on either side
        // of it.
        if (a[(ka + 1) % 3] == b[(kb + 2) % 3] || a[(ka + 2) % 3] == b[(kb + 1) % 3]) return true;
      } else if (shared == 1) {
        // Both angles at the shared corner o are under a half turn (the
        // faces are counter-clockwise), a's from side d1 to d2 and b's from
        // e1 to e2: they are disjoint iff a line through o along one of
        // the four sides has them on either side.
        const auto o = point(a[ka]);
        const auto a1 = point(a[(ka + 1) % 3]), a2 = point(a[(ka + 2) % 3]);
        const auto b1 = point(b[(kb + 1) % 3]), b2 = point(b[(kb + 2) % 3]);
        const double c11 = cross(o, a1, b1), c12 = cross(o, a1, b2);
        const double c21 = cross(o, a2, b1), c22 = cross(o, a2, b2);
        if ((c11 <= 0 && c12 <= 0) || (c21 >= 0 && c22 >= 0) || (c11 >= 0 && c21 >= 0) ||
            (c12 <= 0 && c22 <= 0)) {
          return true;
        }
      }
    }
    overlap = TrianglesOverlap(ChartTriangle(chart, i), ChartTriangle(chart, j), tolerance);
    return !overlap;
  });
  return overlap;
}

namespace {

double PointSegmentDistance(double px, double py, double ax, double ay, double bx, double by) {
  const double dx = bx - ax, dy = by - ay, length2 = dx * dx + dy * dy;
  double t = length2 > 0 ? ((px - ax) * dx + (py - ay) * dy) / length2 : 0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(px - (ax + t * dx), py - (ay + t * dy));
}

}  // namespace

double TriangleDistance(const Tri2& a, const Tri2& b) {
  if (TrianglesOverlap(a, b, 0)) return 0;
  // Disjoint (or touching) convex polygons: the closest pair involves a
  // vertex of one and an edge of the other.
  double best = std::numeric_limits<double>::infinity();
  for (int pass = 0; pass < 2; ++pass) {
    const Tri2& p = pass == 0 ? a : b;
    const Tri2& q = pass == 0 ? b : a;
    for (int v = 0; v < 3; ++v) {
      for (int k = 0; k < 3; ++k) {
        const int m = (k + 1) % 3;
        best = std::min(best, PointSegmentDistance(p[2 * v], p[2 * v + 1], q[2 * k], q[2 * k + 1],
                                                   q[2 * m], q[2 * m + 1]));
      }
    }
  }
  return best;
}

}  // namespace pb
