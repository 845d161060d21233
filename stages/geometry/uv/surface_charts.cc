// Charts grown by normal cone, flattened by LSCM, split where they distort;
// algorithm and sources in surface_charts.h.
#include "stages/geometry/uv/surface_charts.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <deque>
#include <iterator>
#include <limits>
#include <queue>
#include <thread>
#include <utility>

#include "stages/geometry/core/vec3.h"
#include "stages/geometry/uv/conformal.h"

namespace pb {
namespace {

using vec3::V3;
using vec3::Add;
using vec3::Dot;
using vec3::Cross;
using vec3::Norm;

using Tri2 = std::array<double, 6>;

constexpr uint32_t kNone = kNoFace;
constexpr uint32_t kIsolated = kNoFace - 1;
// Charts under this many faces are merged into a neighbour where the normals
// allow it.
constexpr size_t kSmallChartFaces = 16;
// Smoothing and merging never cross an edge folding more than this (or
// cone_deg if larger).
constexpr double kMergeCreaseDeg = 75;
// Curved charts with more vertices than this are split rather than solved:
// on a noisy scan such charts fail the stretch bound anyway, and each
// failed solve of a huge chart cost as much as the rest of the unwrap
// (the room's 10^6-face depth-10 mesh: chart making 35 -> 16 s on one
// thread from 60,000 to 10,000, 773 -> 774 charts; the benchmark meshes of
// docs/uv.md have no curved chart that large and do not change).
constexpr size_t kMaxSolveVertices = 10000;

V3 Normalized(const V3& v) {
  const double n = Norm(v);
  return n > 0 ? V3{v[0] / n, v[1] / n, v[2] / n} : V3{0, 0, 0};
}

struct FaceData {
  Topology topo;
  std::vector<V3> unit_normal;  // {0,0,0} for faces without area
  std::vector<double> area;
};

FaceData BuildFaceData(const Mesh& mesh) {
  FaceData data;
  data.topo = BuildTopology(mesh);
  const size_t faces = mesh.face_count();
  data.unit_normal.resize(faces);
  data.area.resize(faces);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, faces, 8192), [&](const auto& r) {
    for (size_t f = r.begin(); f < r.end(); ++f) {
      data.unit_normal[f] = Normalized(data.topo.area_normal[f]);
      data.area[f] = 0.5 * Norm(data.topo.area_normal[f]);
    }
  });
  return data;
}

// Growth (step 1 of the header): the chart of every face (kIsolated for
// isolated ones) and the number of charts.
std::vector<uint32_t> GrowCharts(const FaceData& data, double cone_cos,
                                 const std::vector<uint32_t>& isolated, uint32_t* count) {
  const size_t faces = data.area.size();
  const Topology& topo = data.topo;
  std::vector<uint32_t> chart_of(faces, kNone);
  for (uint32_t f : isolated) chart_of[f] = kIsolated;
  // Flattest faces seed first: the smallest cosine to an edge neighbour.
  std::vector<double> flatness(faces, 1.0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, faces, 8192), [&](const auto& r) {
    for (size_t f = r.begin(); f < r.end(); ++f) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t g = topo.neighbor[3 * f + k];
        if (g != kNone) {
          flatness[f] = std::min(flatness[f], Dot(data.unit_normal[f], data.unit_normal[g]));
        }
      }
    }
  });
  // Flattest first, then face order: a total order, so a parallel sort of
  // (flatness, face) keys gives what a stable sort of the faces by flatness
  // gave (on one core, a fifth of growth on a 10^6-face scan).
  struct Key {
    double flatness;
    uint32_t face;
    bool operator<(const Key& o) const {
      return flatness > o.flatness || (flatness == o.flatness && face < o.face);
    }
  };
  std::vector<Key> keys;
  keys.reserve(faces);
  for (size_t f = 0; f < faces; ++f) {
    if (chart_of[f] == kNone && data.area[f] > 0) keys.push_back({flatness[f], uint32_t(f)});
  }
  tbb::parallel_sort(keys.begin(), keys.end());
  std::vector<uint32_t> order(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) order[i] = keys[i].face;
  keys = std::vector<Key>();

  using Entry = std::pair<double, uint32_t>;  // (1 - cos to the mean, face)
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap;
  uint32_t charts = 0;
  for (uint32_t seed : order) {
    if (chart_of[seed] != kNone) continue;
    const uint32_t chart = charts++;
    chart_of[seed] = chart;
    V3 sum = topo.area_normal[seed];
    V3 mean = Normalized(sum);
    auto push_neighbors = [&](uint32_t f) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t g = topo.neighbor[3 * size_t(f) + k];
        if (g == kNone || chart_of[g] != kNone) continue;
        // Never across a crease.
        if (Dot(data.unit_normal[f], data.unit_normal[g]) < cone_cos) continue;
        heap.push({1.0 - Dot(data.unit_normal[g], mean), g});
      }
    };
    push_neighbors(seed);
    while (!heap.empty()) {
      const auto [cost, g] = heap.top();
      heap.pop();
      if (chart_of[g] != kNone) continue;
      const double now = 1.0 - Dot(data.unit_normal[g], mean);
      if (1.0 - now < cone_cos) continue;
      // The mean moved since g was queued: requeue it if others now come first.
      if (now > cost + 1e-12 && !heap.empty() && now > heap.top().first) {
        heap.push({now, g});
        continue;
      }
      chart_of[g] = chart;
      sum = Add(sum, topo.area_normal[g]);
      mean = Normalized(sum);
      push_neighbors(g);
    }
  }
  // Faces without area (not isolated: the caller isolates slivers, so
  // rarely any) join a neighbouring chart, or make their own.
  for (bool changed = true; changed;) {
    changed = false;
    for (size_t f = 0; f < faces; ++f) {
      if (chart_of[f] != kNone) continue;
      for (int k = 0; k < 3; ++k) {
        const uint32_t g = topo.neighbor[3 * f + k];
        if (g != kNone && chart_of[g] != kNone && chart_of[g] != kIsolated) {
          chart_of[f] = chart_of[g];
          changed = true;
          break;
        }
      }
    }
  }
  for (size_t f = 0; f < faces; ++f) {
    if (chart_of[f] == kNone) chart_of[f] = charts++;
  }
  *count = charts;
  return chart_of;
}

// Smoothing (part of step 2): a face with two or three edge neighbours in
// one other chart moves there if its normal is within `cos_limit` of that
// chart's mean normal. Greedy growth leaves saw-tooth borders on noisy
// meshes; they cost seam length and packing space.
void SmoothBorders(const FaceData& data, uint32_t count, double cos_limit, double crease_cos,
                   std::vector<uint32_t>* chart_of_io) {
  std::vector<uint32_t>& chart_of = *chart_of_io;
  const size_t faces = data.area.size();
  std::vector<V3> normal_sum(count, V3{0, 0, 0});
  for (size_t f = 0; f < faces; ++f) {
    if (chart_of[f] != kIsolated) {
      normal_sum[chart_of[f]] = Add(normal_sum[chart_of[f]], data.topo.area_normal[f]);
    }
  }
  for (int pass = 0; pass < 4; ++pass) {
    size_t moved = 0;
    for (size_t f = 0; f < faces; ++f) {
      const uint32_t own = chart_of[f];
      if (own == kIsolated) continue;
      uint32_t other[3];
      int n = 0;
      for (int k = 0; k < 3; ++k) {
        const uint32_t g = data.topo.neighbor[3 * f + k];
        if (g != kNone && chart_of[g] != own && chart_of[g] != kIsolated &&
            Dot(data.unit_normal[f], data.unit_normal[g]) >= crease_cos) {
          other[n++] = chart_of[g];
        }
      }
      if (n < 2) continue;
      uint32_t target = kNone;
      if (other[0] == other[1] || (n == 3 && other[0] == other[2])) {
        target = other[0];
      } else if (n == 3 && other[1] == other[2]) {
        target = other[1];
      }
      if (target == kNone) continue;
      if (data.area[f] > 0 &&
          Dot(data.unit_normal[f], Normalized(normal_sum[target])) < cos_limit) {
        continue;
      }
      const V3& an = data.topo.area_normal[f];
      normal_sum[own] = {normal_sum[own][0] - an[0], normal_sum[own][1] - an[1],
                         normal_sum[own][2] - an[2]};
      normal_sum[target] = Add(normal_sum[target], an);
      chart_of[f] = target;
      ++moved;
    }
    if (moved == 0) break;
  }
}

// Merging (step 2): returns the faces of each chart, increasing, charts in
// order of their lowest face.
std::vector<std::vector<uint32_t>> MergeSmallCharts(const Mesh& mesh, const FaceData& data,
                                                    std::vector<uint32_t> chart_of, uint32_t count,
                                                    double merge_cos, double crease_cos) {
  const size_t faces = data.area.size();
  std::vector<std::vector<uint32_t>> members(count);
  std::vector<V3> normal_sum(count, V3{0, 0, 0});
  for (size_t f = 0; f < faces; ++f) {
    if (chart_of[f] == kIsolated) continue;
    members[chart_of[f]].push_back(uint32_t(f));
    normal_sum[chart_of[f]] = Add(normal_sum[chart_of[f]], data.topo.area_normal[f]);
  }
  std::vector<uint32_t> small;
  for (uint32_t c = 0; c < count; ++c) {
    if (members[c].size() < kSmallChartFaces) small.push_back(c);
  }
  std::stable_sort(small.begin(), small.end(),
                   [&](uint32_t a, uint32_t b) { return members[a].size() < members[b].size(); });
  std::vector<std::pair<uint32_t, double>> shared;  // (chart, boundary length)
  for (uint32_t c : small) {
    if (members[c].empty() || members[c].size() >= kSmallChartFaces) continue;
    shared.clear();
    for (uint32_t f : members[c]) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t g = data.topo.neighbor[3 * size_t(f) + k];
        if (g == kNone || chart_of[g] == c || chart_of[g] == kIsolated) continue;
        if (Dot(data.unit_normal[f], data.unit_normal[g]) < crease_cos) continue;  // a crease
        const V3 a = VertexPosition(mesh, mesh.indices[3 * size_t(f) + k]);
        const V3 b = VertexPosition(mesh, mesh.indices[3 * size_t(f) + (k + 1) % 3]);
        const double length = Norm({a[0] - b[0], a[1] - b[1], a[2] - b[2]});
        auto it = std::find_if(shared.begin(), shared.end(),
                               [&](const auto& s) { return s.first == chart_of[g]; });
        if (it == shared.end()) {
          shared.push_back({chart_of[g], length});
        } else {
          it->second += length;
        }
      }
    }
    std::stable_sort(shared.begin(), shared.end(), [](const auto& a, const auto& b) {
      return a.second > b.second || (a.second == b.second && a.first < b.first);
    });
    for (const auto& [target, length] : shared) {
      const V3 mean = Normalized(Add(normal_sum[target], normal_sum[c]));
      bool fits = true;
      for (uint32_t f : members[c]) {
        if (data.area[f] > 0 && Dot(data.unit_normal[f], mean) < merge_cos) {
          fits = false;
          break;
        }
      }
      if (!fits) continue;
      for (uint32_t f : members[c]) chart_of[f] = target;
      members[target].insert(members[target].end(), members[c].begin(), members[c].end());
      normal_sum[target] = Add(normal_sum[target], normal_sum[c]);
      members[c].clear();
      break;
    }
  }
  std::vector<std::vector<uint32_t>> charts;
  for (auto& m : members) {
    if (m.empty()) continue;
    std::sort(m.begin(), m.end());
    charts.push_back(std::move(m));
  }
  std::sort(charts.begin(), charts.end(),
            [](const auto& a, const auto& b) { return a.front() < b.front(); });
  return charts;
}

Tri2 ChartTriangle(const FlatChart& chart, size_t i) {
  Tri2 t;
  for (int k = 0; k < 3; ++k) {
    const uint32_t v = chart.corners[3 * i + k];
    t[2 * k] = chart.uv_m[2 * v];
    t[2 * k + 1] = chart.uv_m[2 * v + 1];
  }
  return t;
}

// Projects the chart on the plane through its first vertex with unit
// normal `normal` (right-handed basis: front faces stay counter-clockwise).
void ProjectOnPlane(const Mesh& mesh, const V3& normal, FlatChart* chart) {
  V3 t1, t2;
  PlaneBasis(normal, &t1, &t2);
  const V3 origin = VertexPosition(mesh, chart->vertices.front());
  chart->uv_m.assign(2 * chart->vertices.size(), 0.0);
  for (size_t i = 0; i < chart->vertices.size(); ++i) {
    const V3 p = VertexPosition(mesh, chart->vertices[i]);
    const V3 d{p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]};
    chart->uv_m[2 * i] = Dot(d, t1);
    chart->uv_m[2 * i + 1] = Dot(d, t2);
  }
}

// Scales a flattened chart to UV area = 3-D area and checks it (step 4):
// every face counter-clockwise, L2 stretch at most max_stretch, no overlaps.
bool ScaleAndCheck(const Mesh& mesh, const FaceData& data, double max_stretch, FlatChart* chart) {
  const size_t faces = chart->faces.size();
  double area3 = 0, area2 = 0, extent = 0;
  std::vector<Box2> boxes(faces);
  for (size_t i = 0; i < faces; ++i) {
    const Tri2 t = ChartTriangle(*chart, i);
    const double a2 = SignedArea(t);
    const double a3 = data.area[chart->faces[i]];
    if (a3 > 0 && !(a2 > 1e-9 * a3) && faces > 1) return false;  // flipped or folded
    area3 += a3;
    area2 += std::max(a2, 0.0);
    boxes[i] = {std::min({t[0], t[2], t[4]}), std::min({t[1], t[3], t[5]}),
                std::max({t[0], t[2], t[4]}), std::max({t[1], t[3], t[5]})};
    extent = std::max({extent, boxes[i][2] - boxes[i][0], boxes[i][3] - boxes[i][1]});
  }
  if (!(area2 > 0) || !(area3 > 0)) return faces == 1;
  const double scale = std::sqrt(area3 / area2);
  for (double& x : chart->uv_m) x *= scale;
  if (faces == 1) return true;
  if (ChartStretchL2(mesh, *chart) > max_stretch) return false;
  const double tolerance = 1e-9 * extent * scale;
  for (Box2& b : boxes) {
    for (double& x : b) x *= scale;
  }
  return !ChartFacesOverlap(*chart, boxes, tolerance);
}

// Flattens (step 3) and validates (step 4); false if the chart must split.
// A planar projection is kept when it stretches no more than 1/50 of the
// allowed excess (nearly flat charts, like relief walls: exact rectangles
// pack better, and it costs no solve); larger charts than kMaxSolveVertices
// that need a solve are split instead (the factorization grows faster than
// the chart).
bool FlattenChart(const Mesh& mesh, const FaceData& data, double max_stretch, FlatChart* chart) {
  V3 sum{0, 0, 0};
  for (uint32_t f : chart->faces) sum = Add(sum, data.topo.area_normal[f]);
  const V3 normal = Normalized(sum);
  if (Norm(normal) > 0) {
    ProjectOnPlane(mesh, normal, chart);
    if (ScaleAndCheck(mesh, data, 1.0 + 0.02 * (max_stretch - 1.0), chart)) return true;
  }
  const size_t n = chart->vertices.size();
  if (n > kMaxSolveVertices) return false;
  const V3 origin = VertexPosition(mesh, chart->vertices.front());
  std::vector<double> positions(3 * n);
  for (size_t i = 0; i < n; ++i) {
    const V3 p = VertexPosition(mesh, chart->vertices[i]);
    for (int d = 0; d < 3; ++d) positions[3 * i + d] = p[d] - origin[d];
  }
  if (!LscmFlatten(positions, chart->corners, &chart->uv_m)) return chart->faces.size() == 1;
  return ScaleAndCheck(mesh, data, max_stretch, chart);
}

// Local index of each face of a chart (kNone for faces outside it): one
// lookup per neighbour instead of a binary search in the chart's face list,
// which dominated splitting the huge charts of noisy scans. Kept per thread
// at the mesh's face count and cleared after use.
class LocalIndex {
 public:
  LocalIndex(size_t face_count, const std::vector<uint32_t>& faces) : faces_(faces) {
    thread_local std::vector<uint32_t> storage;
    if (storage.size() < face_count) storage.assign(face_count, kNone);
    local_ = &storage;
    for (size_t i = 0; i < faces.size(); ++i) storage[faces[i]] = uint32_t(i);
  }
  ~LocalIndex() {
    for (uint32_t f : faces_) (*local_)[f] = kNone;
  }
  LocalIndex(const LocalIndex&) = delete;
  LocalIndex& operator=(const LocalIndex&) = delete;
  // The index of face f in the chart, or kNone.
  uint32_t operator()(uint32_t f) const { return (*local_)[f]; }

 private:
  const std::vector<uint32_t>& faces_;
  std::vector<uint32_t>* local_;
};

// Breadth-first hop distances from `start` within the chart (-1: unreached).
std::vector<int> Hops(const Topology& topo, const LocalIndex& local, size_t chart_faces,
                      uint32_t start) {
  std::vector<int> hops(chart_faces, -1);
  std::deque<uint32_t> queue{start};
  hops[local(start)] = 0;
  while (!queue.empty()) {
    const uint32_t f = queue.front();
    queue.pop_front();
    const int h = hops[local(f)];
    for (int k = 0; k < 3; ++k) {
      const uint32_t g = topo.neighbor[3 * size_t(f) + k];
      if (g == kNone || local(g) == kNone) continue;
      int& hg = hops[local(g)];
      if (hg >= 0) continue;
      hg = h + 1;
      queue.push_back(g);
    }
  }
  return hops;
}

// Geodesic halves: a breadth-first race from two far-apart faces; each
// label's faces, split into edge-connected parts, in order of lowest face.
std::vector<std::vector<uint32_t>> SplitChart(const Topology& topo,
                                              const std::vector<uint32_t>& faces) {
  auto farthest = [&](const std::vector<int>& hops) {
    size_t best = 0;
    for (size_t i = 0; i < hops.size(); ++i) {
      if (hops[i] > hops[best]) best = i;
    }
    return faces[best];
  };
  const LocalIndex local(topo.neighbor.size() / 3, faces);
  const uint32_t a = farthest(Hops(topo, local, faces.size(), faces.front()));
  const uint32_t b = farthest(Hops(topo, local, faces.size(), a));
  std::vector<int> label(faces.size(), -1);
  std::deque<uint32_t> queue{a, b};
  label[local(a)] = 0;
  label[local(b)] = 1;
  while (!queue.empty()) {
    const uint32_t f = queue.front();
    queue.pop_front();
    const int l = label[local(f)];
    for (int k = 0; k < 3; ++k) {
      const uint32_t g = topo.neighbor[3 * size_t(f) + k];
      if (g == kNone || local(g) == kNone) continue;
      int& lg = label[local(g)];
      if (lg >= 0) continue;
      lg = l;
      queue.push_back(g);
    }
  }
  for (int& l : label) l = std::max(l, 0);  // unreached (not edge-connected) faces
  // Edge-connected parts of each label.
  std::vector<char> done(faces.size(), 0);
  std::vector<std::vector<uint32_t>> parts;
  std::vector<uint32_t> stack;
  for (size_t s = 0; s < faces.size(); ++s) {
    if (done[s]) continue;
    std::vector<uint32_t> part;
    stack.assign(1, faces[s]);
    done[s] = 1;
    while (!stack.empty()) {
      const uint32_t f = stack.back();
      stack.pop_back();
      part.push_back(f);
      for (int k = 0; k < 3; ++k) {
        const uint32_t g = topo.neighbor[3 * size_t(f) + k];
        if (g == kNone || local(g) == kNone) continue;
        const size_t i = local(g);
        if (done[i] || label[i] != label[s]) continue;
        done[i] = 1;
        stack.push_back(g);
      }
    }
    std::sort(part.begin(), part.end());
    parts.push_back(std::move(part));
  }
  return parts;
}

// After flattening, a chart of fewer than kSmallChartFaces faces joins a
// neighbouring chart (longest shared border first, up to three tried) if
// the union flattens validly; in order of size then position, each chart
// seeing the joins before it.
//
// The attempts run in parallel, speculatively: a window of the next small
// charts is tried against the current charts, then the results are taken
// in order as long as nothing an attempt read (its own chart and every
// neighbouring chart: their faces, and so the shared borders and the
// unions) has changed since it was made; the first stale attempt is made
// again in the next window. So every join is the one the sequential loop
// makes, whatever the thread count.
void MergeFlatSmallCharts(const Mesh& mesh, const FaceData& data, double max_stretch,
                          double crease_cos, std::vector<FlatChart>* charts_io) {
  std::vector<FlatChart>& charts = *charts_io;
  std::vector<uint32_t> chart_of(data.area.size(), kNone);
  std::vector<uint32_t> small;
  for (size_t c = 0; c < charts.size(); ++c) {
    for (uint32_t f : charts[c].faces) chart_of[f] = uint32_t(c);
    if (charts[c].faces.size() < kSmallChartFaces) small.push_back(uint32_t(c));
  }
  std::stable_sort(small.begin(), small.end(), [&](uint32_t a, uint32_t b) {
    return charts[a].faces.size() < charts[b].faces.size();
  });
  constexpr size_t kMaxTargetFaces = 20000;  // keeps re-solving cheap on huge meshes

  struct Attempt {
    bool made = false;
    uint64_t step = 0;             // joins committed when it was made
    std::vector<uint32_t> read;    // the charts it depends on
    uint32_t target = kNone;       // kNone: stays alone
    FlatChart merged;
  };
  // The attempt of small chart c against the current charts.
  auto attempt = [&](uint32_t c, uint64_t step, Attempt* out) {
    out->made = true;
    out->step = step;
    out->read.assign(1, c);
    out->target = kNone;
    out->merged = FlatChart();
    if (charts[c].faces.empty() || charts[c].faces.size() >= kSmallChartFaces) return;
    std::vector<std::pair<uint32_t, double>> shared;  // (chart, border length)
    for (uint32_t f : charts[c].faces) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t g = data.topo.neighbor[3 * size_t(f) + k];
        if (g == kNone || chart_of[g] == c || chart_of[g] == kNone) continue;
        if (Dot(data.unit_normal[f], data.unit_normal[g]) < crease_cos) continue;  // a crease
        const V3 a = VertexPosition(mesh, mesh.indices[3 * size_t(f) + k]);
        const V3 b = VertexPosition(mesh, mesh.indices[3 * size_t(f) + (k + 1) % 3]);
        const double length = Norm({a[0] - b[0], a[1] - b[1], a[2] - b[2]});
        auto it = std::find_if(shared.begin(), shared.end(),
                               [&](const auto& x) { return x.first == chart_of[g]; });
        if (it == shared.end()) {
          shared.push_back({chart_of[g], length});
        } else {
          it->second += length;
        }
      }
    }
    for (const auto& [other, length] : shared) out->read.push_back(other);
    std::stable_sort(shared.begin(), shared.end(), [](const auto& a, const auto& b) {
      return a.second > b.second || (a.second == b.second && a.first < b.first);
    });
    for (size_t i = 0; i < shared.size() && i < 3; ++i) {
      const uint32_t target = shared[i].first;
      if (charts[target].faces.size() > kMaxTargetFaces) continue;
      std::vector<uint32_t> faces = charts[target].faces;
      faces.insert(faces.end(), charts[c].faces.begin(), charts[c].faces.end());
      std::sort(faces.begin(), faces.end());
      FlatChart merged = ChartSkeleton(mesh, std::move(faces));
      if (!FlattenChart(mesh, data, max_stretch, &merged)) continue;
      FitRectangle(&merged);
      out->target = target;
      out->merged = std::move(merged);
      return;
    }
  };

  // changed[c]: the number of joins committed when chart c last changed.
  std::vector<uint64_t> changed(charts.size(), 0);
  uint64_t step = 0;
  auto fresh = [&](const Attempt& a) {
    for (uint32_t c : a.read) {
      if (changed[c] > a.step) return false;
    }
    return true;
  };
  constexpr size_t kWindow = 32;
  std::vector<Attempt> window(kWindow);
  std::vector<size_t> todo;
  for (size_t next = 0; next < small.size();) {
    const size_t count = std::min(kWindow, small.size() - next);
    // Window slot i holds the attempt of small[next + i]; slots are kept
    // across windows by rotating them with `next`.
    todo.clear();
    for (size_t i = 0; i < count; ++i) {
      const Attempt& a = window[(next + i) % kWindow];
      if (!a.made || !fresh(a)) todo.push_back(next + i);
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, todo.size(), 1), [&](const auto& r) {
      for (size_t t = r.begin(); t < r.end(); ++t) {
        attempt(small[todo[t]], step, &window[todo[t] % kWindow]);
      }
    });
    for (size_t i = 0; i < count; ++i, ++next) {
      Attempt& a = window[next % kWindow];
      if (!fresh(a)) break;
      a.made = false;
      if (a.target == kNone) continue;
      const uint32_t c = small[next];
      ++step;
      changed[c] = changed[a.target] = step;
      for (uint32_t f : charts[c].faces) chart_of[f] = a.target;
      charts[a.target] = std::move(a.merged);
      charts[c] = FlatChart();
    }
  }
  charts.erase(std::remove_if(charts.begin(), charts.end(),
                              [](const FlatChart& c) { return c.faces.empty(); }),
               charts.end());
}

}  // namespace

double ChartStretchL2(const Mesh& mesh, const FlatChart& chart) {
  double area3 = 0, area2 = 0, weighted = 0;
  for (size_t i = 0; i < chart.faces.size(); ++i) {
    const Tri2 t = ChartTriangle(chart, i);
    const double a2 = SignedArea(t);
    V3 q[3];
    for (int k = 0; k < 3; ++k) q[k] = VertexPosition(mesh, mesh.indices[3 * size_t(chart.faces[i]) + k]);
    const V3 e1{q[1][0] - q[0][0], q[1][1] - q[0][1], q[1][2] - q[0][2]};
    const V3 e2{q[2][0] - q[0][0], q[2][1] - q[0][1], q[2][2] - q[0][2]};
    const double a3 = 0.5 * Norm(Cross(e1, e2));
    if (!(a2 > 0) || !(a3 > 0)) continue;
    const double s1 = t[0], t1 = t[1], s2 = t[2], t2 = t[3], s3 = t[4], t3 = t[5];
    double a = 0, c = 0;
    for (int d = 0; d < 3; ++d) {
      const double ss =
          (q[0][d] * (t2 - t3) + q[1][d] * (t3 - t1) + q[2][d] * (t1 - t2)) / (2 * a2);
      const double st =
          (q[0][d] * (s3 - s2) + q[1][d] * (s1 - s3) + q[2][d] * (s2 - s1)) / (2 * a2);
      a += ss * ss;
      c += st * st;
    }
    area3 += a3;
    area2 += a2;
    weighted += a3 * 0.5 * (a + c);
  }
  if (!(area3 > 0) || !(area2 > 0)) return 1.0;
  return std::sqrt(weighted / area3) * std::sqrt(area2 / area3);
}

std::vector<FlatChart> MakeSurfaceCharts(const Mesh& mesh, const SurfaceChartOptions& options,
                                         const std::function<void(double)>& progress) {
  const FaceData data = BuildFaceData(mesh);
  if (progress) progress(0.15);
  const double cone_cos = std::cos(options.cone_deg * M_PI / 180.0);
  const double merge_cos = std::cos(std::min(89.0, 1.5 * options.cone_deg) * M_PI / 180.0);
  // Growth stops at any fold beyond the cone; merging only at folds a scan's
  // noise does not make (single faces of a noisy scan often fold 45 deg).
  const double crease_cos = std::cos(std::max(options.cone_deg, kMergeCreaseDeg) * M_PI / 180.0);
  uint32_t count = 0;
  std::vector<uint32_t> chart_of = GrowCharts(data, cone_cos, options.isolated_faces, &count);
  SmoothBorders(data, count, merge_cos, crease_cos, &chart_of);
  std::vector<std::vector<uint32_t>> pending =
      MergeSmallCharts(mesh, data, std::move(chart_of), count, merge_cos, crease_cos);
  if (progress) progress(0.3);

  // Flatten; split what fails, until nothing does. A split chart's parts
  // take its place, so the order does not depend on the threads. Each
  // part is flattened (and split) as soon as it exists, as a task of its
  // own: no round waits for its largest chart (on a noisy scan the first
  // rounds were a few huge charts, one core idle).
  const auto caller = std::this_thread::get_id();
  const size_t total_faces = std::max<size_t>(1, mesh.face_count());
  std::atomic<size_t> faces_done{0};
  double reported = 0.3;
  std::function<std::vector<FlatChart>(std::vector<uint32_t>)> flatten =
      [&](std::vector<uint32_t> faces) -> std::vector<FlatChart> {
    FlatChart chart = ChartSkeleton(mesh, std::move(faces));
    if (FlattenChart(mesh, data, options.max_chart_stretch, &chart)) {
      FitRectangle(&chart);
      faces_done += chart.faces.size();
      // Progress from the calling thread only (the callback need not be
      // thread-safe).
      if (progress && std::this_thread::get_id() == caller) {
        const double fraction = 0.3 + 0.6 * double(faces_done) / double(total_faces);
        if (fraction > reported + 0.01) {
          reported = fraction;
          progress(fraction);
        }
      }
      std::vector<FlatChart> one;
      one.push_back(std::move(chart));
      return one;
    }
    std::vector<std::vector<uint32_t>> parts = SplitChart(data.topo, chart.faces);
    chart = FlatChart();
    std::vector<std::vector<FlatChart>> flat(parts.size());
    tbb::parallel_for(size_t(0), parts.size(),
                      [&](size_t i) { flat[i] = flatten(std::move(parts[i])); });
    std::vector<FlatChart> all = std::move(flat[0]);
    for (size_t i = 1; i < flat.size(); ++i) {
      std::move(flat[i].begin(), flat[i].end(), std::back_inserter(all));
    }
    return all;
  };
  std::vector<std::vector<FlatChart>> flat(pending.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pending.size(), 1), [&](const auto& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) flat[i] = flatten(std::move(pending[i]));
  });
  std::vector<FlatChart> charts;
  for (auto& f : flat) std::move(f.begin(), f.end(), std::back_inserter(charts));
  flat.clear();
  if (progress) progress(0.9);
  MergeFlatSmallCharts(mesh, data, options.max_chart_stretch, crease_cos, &charts);
  for (uint32_t f : options.isolated_faces) {
    FlatChart chart = ChartSkeleton(mesh, {f});
    chart.isolated = true;
    chart.uv_m.assign(2 * chart.vertices.size(), 0.0);
    charts.push_back(std::move(chart));
  }
  if (progress) progress(1.0);
  return charts;
}

}  // namespace pb
