// Quadric edge collapse: M. Garland, P. Heckbert, "Surface Simplification
// Using Quadric Error Metrics", SIGGRAPH 1997. Departures from the paper:
//  * only edges are collapsed (no "virtual pairs" of distant vertices): those
//    join separate sheets and break manifoldness;
//  * boundaries are kept with perpendicular constraint planes (Section 6 of
//    the paper mentions this; weight in DecimateOptions);
//  * every collapse is checked for the link condition (Dey, Edelsbrunner et
//    al., "Topology preserving edge contraction", 1999), face flips and
//    degenerate faces, because the output must stay manifold;
//  * the heap is lazy: an entry remembers the versions of its two vertices and
//    is skipped when either changed since it was pushed.
#include "stages/geometry/mesh/decimate.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "stages/geometry/mesh/holes.h"

namespace pb {
namespace {

using Vec3d = std::array<double, 3>;

Vec3d Sub(const Vec3d& a, const Vec3d& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3d Cross(const Vec3d& a, const Vec3d& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double Dot(const Vec3d& a, const Vec3d& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double Norm(const Vec3d& a) { return std::sqrt(Dot(a, a)); }

// Symmetric 4x4 quadric, upper triangle: a00 a01 a02 a03 a11 a12 a13 a22 a23 a33.
struct Quadric {
  std::array<double, 10> q{};

  // weight * (n.x + d)^2 for the plane n.x + d = 0, |n| = 1.
  static Quadric Plane(const Vec3d& n, double d, double weight) {
    Quadric r;
    r.q = {n[0] * n[0], n[0] * n[1], n[0] * n[2], n[0] * d, n[1] * n[1],
           n[1] * n[2], n[1] * d,    n[2] * n[2], n[2] * d, d * d};
    for (double& v : r.q) v *= weight;
    return r;
  }
  void Add(const Quadric& o) {
    for (int i = 0; i < 10; ++i) q[i] += o.q[i];
  }
  double Error(const Vec3d& p) const {
    const double x = p[0], y = p[1], z = p[2];
    const double e = q[0] * x * x + 2 * q[1] * x * y + 2 * q[2] * x * z + 2 * q[3] * x +
                     q[4] * y * y + 2 * q[5] * y * z + 2 * q[6] * y + q[7] * z * z + 2 * q[8] * z +
                     q[9];
    return std::max(e, 0.0);
  }
  // The minimizer of Error, if the 3x3 part is well conditioned.
  bool Optimum(Vec3d* p) const {
    const double a = q[0], b = q[1], c = q[2], d = q[4], e = q[5], f = q[7];
    const double det = a * (d * f - e * e) - b * (b * f - c * e) + c * (b * e - c * d);
    const double scale = a + d + f;
    if (!(scale > 0) || std::abs(det) < 1e-10 * scale * scale * scale) return false;
    const double inv = 1.0 / det;
    // Adjugate of the symmetric matrix; solves A p = -(q3, q6, q8).
    const double i00 = (d * f - e * e) * inv, i01 = (c * e - b * f) * inv,
                 i02 = (b * e - c * d) * inv, i11 = (a * f - c * c) * inv,
                 i12 = (b * c - a * e) * inv, i22 = (a * d - b * b) * inv;
    const double r0 = -q[3], r1 = -q[6], r2 = -q[8];
    *p = {i00 * r0 + i01 * r1 + i02 * r2, i01 * r0 + i11 * r1 + i12 * r2,
          i02 * r0 + i12 * r1 + i22 * r2};
    return std::isfinite((*p)[0]) && std::isfinite((*p)[1]) && std::isfinite((*p)[2]);
  }
};

// 16 bytes, so that the heap's working set stays small. Versions only grow,
// so the sum of the two endpoints' versions changes iff either one did.
struct HeapEntry {
  float cost;
  uint32_t v0, v1;  // v0 < v1
  uint32_t stamp;   // version_[v0] + version_[v1] when pushed
};

// For std::push_heap, which keeps the "largest" on top: larger = worse =
// popped later.
struct Later {
  bool operator()(const HeapEntry& a, const HeapEntry& b) const {
    if (a.cost != b.cost) return a.cost > b.cost;
    if (a.v0 != b.v0) return a.v0 > b.v0;
    return a.v1 > b.v1;
  }
};

// A 4-ary min-heap (by Later): four 16-byte children share a cache line, so a
// pop touches half the lines of a binary heap; at 10^7 entries the heap is
// memory bound.
class EdgeHeap {
 public:
  bool empty() const { return entries_.empty(); }
  size_t size() const { return entries_.size(); }
  void reserve(size_t n) { entries_.reserve(n); }
  // Add without ordering; call Heapify before the next Push or Pop.
  void Append(const HeapEntry& e) { entries_.push_back(e); }
  void Heapify() {
    for (size_t i = entries_.size() / 4 + 1; i-- > 0;) SiftDown(i, entries_[i]);
  }
  void Push(const HeapEntry& e) {
    size_t i = entries_.size();
    entries_.push_back(e);
    while (i > 0) {
      const size_t parent = (i - 1) / 4;
      if (!Later()(entries_[parent], e)) break;
      entries_[i] = entries_[parent];
      i = parent;
    }
    entries_[i] = e;
  }
  HeapEntry Pop() {
    const HeapEntry top = entries_[0];
    const HeapEntry last = entries_.back();
    entries_.pop_back();
    if (!entries_.empty()) SiftDown(0, last);
    return top;
  }
  template <typename Predicate>
  void RemoveIf(Predicate stale) {
    entries_.erase(std::remove_if(entries_.begin(), entries_.end(), stale), entries_.end());
    Heapify();
  }

 private:
  void SiftDown(size_t i, const HeapEntry e) {
    const size_t n = entries_.size();
    while (true) {
      const size_t first = 4 * i + 1;
      if (first >= n) break;
      size_t best = first;
      const size_t end = std::min(first + 4, n);
      for (size_t c = first + 1; c < end; ++c) {
        if (Later()(entries_[best], entries_[c])) best = c;
      }
      if (!Later()(e, entries_[best])) break;
      entries_[i] = entries_[best];
      i = best;
    }
    entries_[i] = e;
  }

  std::vector<HeapEntry> entries_;
};

class Decimator {
 public:
  Decimator(const Mesh& mesh, const DecimateOptions& options, DecimateReport* report)
      : mesh_(mesh), options_(options), report_(*report) {}

  Expected<Mesh> Run();

 private:
  Vec3d FaceCross(uint32_t f) const {
    const uint32_t* t = &faces_[3 * f];
    return Cross(Sub(positions_[t[1]], positions_[t[0]]), Sub(positions_[t[2]], positions_[t[0]]));
  }
  // The mean edge of `target_faces` equilateral triangles covering the
  // area of faces_.
  double OutputEdge() const {
    double area = 0;
    for (size_t f = 0; f < faces_.size() / 3; ++f) {
      area += 0.5 * Norm(FaceCross(static_cast<uint32_t>(f)));
    }
    return std::sqrt(4 * area / (std::sqrt(3.0) * static_cast<double>(options_.target_faces)));
  }
  // fill_hole_output_edges: appends the small holes' patches to faces_
  // (FillSmallHoles adds no vertex, so positions_ and the attributes stay).
  Status FillHolesBelowOutput() {
    if (!(options_.fill_hole_output_edges > 0) || options_.target_faces == 0 ||
        options_.target_faces >= faces_.size() / 3) {
      return Status::Ok();
    }
    Mesh shape;
    shape.positions = mesh_.positions;
    shape.indices = faces_;
    HoleFillOptions fill;
    const double output_edge = OutputEdge();
    fill.max_perimeter_m = options_.fill_hole_output_edges * output_edge;
    fill.max_reach_m = options_.fill_hole_reach * output_edge;
    fill.max_component_fraction = options_.fill_hole_max_component_fraction;
    if (options_.keep_hole_open) {
      fill.keep_open = [&](const std::vector<std::array<double, 9>>& patch) {
        return options_.keep_hole_open(patch, output_edge);
      };
    }
    HoleFillReport filled;
    PB_RETURN_IF_ERROR(FillSmallHoles(shape, fill, &filled));
    report_.holes_filled = filled.holes_filled;
    report_.holes_too_wide = filled.holes_too_wide;
    report_.outlines_kept = filled.outlines_kept;
    report_.holes_seen_through = filled.holes_kept_open;
    report_.hole_faces = filled.faces_added;
    faces_ = std::move(shape.indices);
    return Status::Ok();
  }
  void BuildAdjacency();
  void BuildQuadrics();
  // Alive faces around v (dropping dead ones from its list).
  void Faces(uint32_t v, std::vector<uint32_t>* out);
  // The vertices other than v of `faces`, sorted, without repeats.
  void Ring(const std::vector<uint32_t>& faces, uint32_t v, std::vector<uint32_t>* out) const;
  // Best position for collapsing edge (a, b) and its cost.
  double Place(uint32_t a, uint32_t b, Vec3d* p) const;
  HeapEntry Entry(uint32_t a, uint32_t b) const;
  void Push(uint32_t a, uint32_t b);
  bool Stale(const HeapEntry& entry) const {
    return !alive_[entry.v0] || !alive_[entry.v1] ||
           version_[entry.v0] + version_[entry.v1] != entry.stamp;
  }
  // Drops stale entries when they outnumber the live ones, bounding memory.
  void CompactHeap();
  void PushEdgesOf(uint32_t v);
  // Tries to collapse (a, b); false (and counted) if rejected.
  bool TryCollapse(uint32_t a, uint32_t b);
  void SetFaces(uint32_t v, const std::vector<uint32_t>& faces);
  void Interpolate(uint32_t keep, uint32_t gone, double t);
  Mesh Output() const;

  const Mesh& mesh_;
  const DecimateOptions& options_;
  DecimateReport& report_;

  std::vector<Vec3d> positions_;
  std::vector<uint32_t> faces_;  // 3 per face, rewritten as vertices merge
  std::vector<uint8_t> face_alive_;
  std::vector<float> face_normal_in_;  // unit normal per input face, 3 per face
  size_t faces_alive_ = 0;

  // Vertex -> faces: list of v is pool_[offset_[v] .. offset_[v] + count_[v]),
  // with room for capacity_[v]; lists that outgrow their room move to the end.
  std::vector<uint32_t> pool_, offset_, count_, capacity_;

  std::vector<Quadric> quadrics_;
  std::vector<uint32_t> version_;
  std::vector<uint8_t> alive_, boundary_, retry_;

  // Attributes per vertex, float, interpolated on collapse.
  std::vector<float> normals_, colors_, uvs_, tangents_;

  EdgeHeap heap_;
  size_t heap_size_compacted_ = 0;  // heap size after the last compaction
  std::vector<uint32_t> faces_a_, faces_b_, ring_a_, ring_b_, merged_;
};

void Decimator::BuildAdjacency() {
  const size_t n = positions_.size();
  count_.assign(n, 0);
  for (uint32_t v : faces_) ++count_[v];
  offset_.resize(n);
  uint64_t total = 0;
  for (size_t v = 0; v < n; ++v) {
    offset_[v] = static_cast<uint32_t>(total);
    total += count_[v];
  }
  capacity_ = count_;
  pool_.resize(total);
  std::vector<uint32_t> fill(n, 0);
  for (size_t i = 0; i < faces_.size(); ++i) {
    const uint32_t v = faces_[i];
    pool_[offset_[v] + fill[v]++] = static_cast<uint32_t>(i / 3);
  }
}

void Decimator::BuildQuadrics() {
  const size_t n = positions_.size();
  quadrics_.assign(n, Quadric());
  const size_t face_count = faces_.size() / 3;
  face_normal_in_.resize(3 * face_count);
  for (size_t f = 0; f < face_count; ++f) {
    const Vec3d c = FaceCross(static_cast<uint32_t>(f));
    const double len = Norm(c);
    const Vec3d nrm = len > 0 ? Vec3d{c[0] / len, c[1] / len, c[2] / len} : Vec3d{0, 0, 0};
    for (int k = 0; k < 3; ++k) face_normal_in_[3 * f + k] = static_cast<float>(nrm[k]);
    if (len <= 0) continue;
    const Quadric plane = Quadric::Plane(nrm, -Dot(nrm, positions_[faces_[3 * f]]), 0.5 * len);
    for (int k = 0; k < 3; ++k) quadrics_[faces_[3 * f + k]].Add(plane);
  }
  // Boundary edges: half-edges (a, b) whose twin (b, a) has no face. Found per
  // vertex from its face list, so no global edge table is needed.
  boundary_.assign(n, 0);
  struct BorderEdge {
    uint32_t a, b, f;
  };
  std::vector<BorderEdge> border;
  for (uint32_t a = 0; a < n; ++a) {
    for (uint32_t i = 0; i < count_[a]; ++i) {
      const uint32_t f = pool_[offset_[a] + i];
      const uint32_t* t = &faces_[3 * f];
      const int k = t[0] == a ? 0 : t[1] == a ? 1 : 2;
      const uint32_t b = t[(k + 1) % 3];
      // Count faces around a that contain the edge {a, b} in either direction.
      int shared = 0;
      for (uint32_t j = 0; j < count_[a]; ++j) {
        const uint32_t* s = &faces_[3 * pool_[offset_[a] + j]];
        if (s[0] == b || s[1] == b || s[2] == b) ++shared;
      }
      if (shared != 1) continue;
      boundary_[a] = boundary_[b] = 1;
      border.push_back({a, b, f});
    }
  }
  if (options_.boundary_weight <= 0) return;
  // The border simplified to the output's resolution (Douglas & Peucker,
  // "Algorithms for the reduction of the number of points required to
  // represent a digitized line", 1973): each simple course of the border
  // (vertices with one border edge in and one out; closed loops and the
  // stretches between vertices where several borders meet) is replaced by
  // chords that pass within `tolerance` outside and `boundary_erosion` times
  // that inside of every vertex, measured across the border in the surface
  // (perpendicular to the chord and to the vertex's face normal; a waver
  // along the normal is the face planes' business).
  // Every border edge's plane then runs through its chord instead of itself,
  // so the edges of one chord share a line and collapse along it at no
  // boundary cost, and the vertices between its ends move onto it.
  constexpr uint32_t kNoVertex = UINT32_MAX;
  const size_t border_count = border.size();
  std::vector<uint32_t> next(n, kNoVertex), prev(n, kNoVertex), in_edge(n, kNoVertex);
  std::vector<uint8_t> outs(n, 0), ins(n, 0);
  for (uint32_t i = 0; i < border_count; ++i) {
    const BorderEdge& e = border[i];
    next[e.a] = e.b;
    prev[e.b] = e.a;
    in_edge[e.b] = i;
    outs[e.a] = static_cast<uint8_t>(std::min(outs[e.a] + 1, 2));
    ins[e.b] = static_cast<uint8_t>(std::min(ins[e.b] + 1, 2));
  }
  const auto simple = [&](uint32_t v) { return outs[v] == 1 && ins[v] == 1; };
  const size_t face_total = faces_.size() / 3;
  double tolerance = 0;
  if (options_.boundary_tolerance > 0 && options_.target_faces > 0 &&
      options_.target_faces < face_total) {
    tolerance = options_.boundary_tolerance * OutputEdge();
  }
  // chord[i]: the (start, end) vertices of the chord of border edge i; by
  // default the edge itself.
  std::vector<std::pair<uint32_t, uint32_t>> chord(border_count);
  for (uint32_t i = 0; i < border_count; ++i) chord[i] = {border[i].a, border[i].b};
  if (tolerance > 0) {
    const auto face_normal = [this](uint32_t f) {
      return Vec3d{face_normal_in_[3 * f], face_normal_in_[3 * f + 1], face_normal_in_[3 * f + 2]};
    };
    // How far x lies from the chord s-t across the border (see above), in
    // units of its tolerance: `tolerance` where the chord passes outside x
    // (bridging a notch adds a sliver of surface), `inward` where it would
    // cut x off (taking surface away). Where that plane is undefined, the
    // 3D distance to the segment in units of the smaller one.
    const double inward = options_.boundary_erosion * tolerance;
    const auto excess = [&](uint32_t x, uint32_t s, uint32_t t, uint32_t x_face) {
      const Vec3d d = Sub(positions_[t], positions_[s]), w = Sub(positions_[x], positions_[s]);
      // Faces turn counterclockwise about their normal, so their inside lies
      // left of a border half-edge: perp points out of the surface.
      const Vec3d perp = Cross(d, face_normal(x_face));
      const double len = Norm(perp);
      const double dd = Dot(d, d);
      if (len > 1e-12 * dd && len > 0) {
        const double out = Dot(perp, w) / len;
        return out > 0 ? (inward > 0 ? out / inward : HUGE_VAL) : -out / tolerance;
      }
      const double u = dd > 0 ? std::clamp(Dot(w, d) / dd, 0.0, 1.0) : 0.0;
      const double dist = Norm(Sub(w, Vec3d{u * d[0], u * d[1], u * d[2]}));
      return dist == 0 ? 0.0 : inward > 0 ? dist / inward : HUGE_VAL;
    };
    std::vector<uint8_t> seen(n, 0);
    std::vector<uint32_t> course, edges;  // vertices c[0..m), edges c[k] -> c[k+1]
    std::vector<uint8_t> keep;
    std::vector<std::pair<size_t, size_t>> stack;
    const auto simplify = [&]() {
      const size_t m = course.size();
      keep.assign(m, 0);
      keep[0] = keep[m - 1] = 1;
      stack.clear();
      if (course.front() == course.back()) {
        // A closed loop: split at its start and the vertex farthest from it.
        size_t far = 0;
        double best = -1;
        for (size_t k = 1; k + 1 < m; ++k) {
          const double d = Norm(Sub(positions_[course[k]], positions_[course[0]]));
          if (d > best) best = d, far = k;
        }
        if (far == 0) return;
        keep[far] = 1;
        stack.push_back({far, m - 1});
        stack.push_back({0, far});
      } else {
        stack.push_back({0, m - 1});
      }
      while (!stack.empty()) {
        const auto [i, j] = stack.back();
        stack.pop_back();
        size_t far = 0;
        double best = 1;
        for (size_t k = i + 1; k < j; ++k) {
          const double d = excess(course[k], course[i], course[j], border[edges[k]].f);
          if (d > best) best = d, far = k;
        }
        if (far == 0) continue;
        keep[far] = 1;
        stack.push_back({far, j});
        stack.push_back({i, far});
      }
      for (size_t i = 0; i + 1 < m;) {
        size_t j = i + 1;
        while (!keep[j]) ++j;
        for (size_t k = i; k < j; ++k) chord[edges[k]] = {course[i], course[j]};
        i = j;
      }
    };
    // Courses between meeting points first, then closed simple loops, each
    // from its lowest vertex (deterministic).
    for (const bool loops : {false, true}) {
      for (uint32_t v = 0; v < n; ++v) {
        if (!simple(v) || seen[v] || (!loops && simple(prev[v]))) continue;
        course.assign(1, loops ? v : prev[v]);
        edges.clear();
        uint32_t w = v;
        if (loops) {
          seen[v] = 1;
          w = next[v];
        }
        while (true) {
          edges.push_back(in_edge[w]);
          course.push_back(w);
          if (!simple(w) || seen[w]) break;
          seen[w] = 1;
          w = next[w];
        }
        simplify();
      }
    }
  }
  for (uint32_t i = 0; i < border_count; ++i) {
    const BorderEdge& e = border[i];
    const Vec3d edge = Sub(positions_[e.b], positions_[e.a]);
    const Vec3d nrm = {face_normal_in_[3 * e.f], face_normal_in_[3 * e.f + 1], face_normal_in_[3 * e.f + 2]};
    const auto [s, t] = chord[i];
    Vec3d perp = Cross(Sub(positions_[t], positions_[s]), nrm);
    const double plen = Norm(perp);
    if (!(plen > 0)) continue;
    perp = {perp[0] / plen, perp[1] / plen, perp[2] / plen};
    const Quadric plane =
        Quadric::Plane(perp, -Dot(perp, positions_[s]), options_.boundary_weight * Dot(edge, edge));
    quadrics_[e.a].Add(plane);
    quadrics_[e.b].Add(plane);
  }
}
void Decimator::Faces(uint32_t v, std::vector<uint32_t>* out) {
  out->clear();
  uint32_t* list = &pool_[offset_[v]];
  for (uint32_t i = 0; i < count_[v]; ++i) {
    if (face_alive_[list[i]]) out->push_back(list[i]);
  }
  if (out->size() != count_[v]) {
    std::copy(out->begin(), out->end(), list);
    count_[v] = static_cast<uint32_t>(out->size());
  }
}

void Decimator::Ring(const std::vector<uint32_t>& faces, uint32_t v,
                     std::vector<uint32_t>* out) const {
  out->clear();
  for (uint32_t f : faces) {
    for (int k = 0; k < 3; ++k) {
      if (faces_[3 * f + k] != v) out->push_back(faces_[3 * f + k]);
    }
  }
  std::sort(out->begin(), out->end());
  out->erase(std::unique(out->begin(), out->end()), out->end());
}

double Decimator::Place(uint32_t a, uint32_t b, Vec3d* p) const {
  Quadric q = quadrics_[a];
  q.Add(quadrics_[b]);
  const Vec3d pa = positions_[a], pb = positions_[b];
  const Vec3d mid = {0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1]), 0.5 * (pa[2] + pb[2])};
  Vec3d opt;
  // A solution far from the edge comes from a nearly singular system (flat or
  // cylindrical regions): its error is tiny but the position is unstable.
  if (q.Optimum(&opt)) {
    const Vec3d d = Sub(opt, mid);
    const Vec3d e = Sub(pb, pa);
    if (Dot(d, d) <= Dot(e, e)) {
      *p = opt;
      return q.Error(opt);
    }
  }
  // Midpoint first: on flat regions all three have zero error, and the
  // midpoint keeps the triangulation even instead of growing one fan.
  double best = q.Error(mid);
  *p = mid;
  for (const Vec3d& c : {pa, pb}) {
    const double err = q.Error(c);
    if (err < best) {
      best = err;
      *p = c;
    }
  }
  // Where the minimizers form a line or a plane (a straight border on a
  // flat region: the border's plane and the face plane), none of the three
  // need lie on it: a border vertex off its chord (see BuildQuadrics) is.
  // The point of the minimizing set nearest the midpoint: the optimum of the
  // quadric plus a tiny pull towards the midpoint, kept if it halves the
  // error. Not tried where the error is already negligible against the
  // tie-breaking length term of Entry (flat regions, where the midpoint is
  // exact): that would cost a solve per edge for nothing.
  const Vec3d e = Sub(pb, pa);
  const double e2 = Dot(e, e);
  if (best <= 1e-8 * e2 * e2) return best;
  Quadric pulled = q;
  const double pull = 1e-6 * (q.q[0] + q.q[4] + q.q[7]);
  pulled.q[0] += pull;
  pulled.q[4] += pull;
  pulled.q[7] += pull;
  pulled.q[3] -= pull * mid[0];
  pulled.q[6] -= pull * mid[1];
  pulled.q[8] -= pull * mid[2];
  if (pulled.Optimum(&opt)) {
    const Vec3d d = Sub(opt, mid);
    const double err = q.Error(opt);
    if (Dot(d, d) <= e2 && err < 0.5 * best) {
      *p = opt;
      return err;
    }
  }
  return best;
}

HeapEntry Decimator::Entry(uint32_t a, uint32_t b) const {
  if (a > b) std::swap(a, b);
  Vec3d p;
  // Among equal errors (flat regions) short edges go first, which keeps
  // triangles well shaped: a penalty as if the surface deviated by 0.1% of
  // the edge length.
  const Vec3d e = Sub(positions_[b], positions_[a]);
  const double cost = Place(a, b, &p) + 1e-6 * Dot(e, e) * Dot(e, e);
  return {static_cast<float>(cost), a, b, version_[a] + version_[b]};
}

void Decimator::Push(uint32_t a, uint32_t b) { heap_.Push(Entry(a, b)); }

void Decimator::CompactHeap() {
  heap_.RemoveIf([this](const HeapEntry& e) { return Stale(e); });
}

void Decimator::PushEdgesOf(uint32_t v) {
  Faces(v, &faces_a_);
  Ring(faces_a_, v, &ring_a_);
  for (uint32_t w : ring_a_) Push(v, w);
}

void Decimator::SetFaces(uint32_t v, const std::vector<uint32_t>& faces) {
  const uint32_t n = static_cast<uint32_t>(faces.size());
  if (n > capacity_[v]) {
    offset_[v] = static_cast<uint32_t>(pool_.size());
    capacity_[v] = n + n / 2;
    pool_.resize(pool_.size() + capacity_[v]);
  }
  std::copy(faces.begin(), faces.end(), pool_.begin() + offset_[v]);
  count_[v] = n;
}

void Decimator::Interpolate(uint32_t keep, uint32_t gone, double t) {
  auto lerp = [t, keep, gone](std::vector<float>& a, int stride) {
    if (a.empty()) return;
    for (int k = 0; k < stride; ++k) {
      float& x = a[stride * size_t{keep} + k];
      x = static_cast<float>((1 - t) * x + t * a[stride * size_t{gone} + k]);
    }
  };
  auto normalize3 = [](float* x) {
    const double len = std::sqrt(double{x[0]} * x[0] + double{x[1]} * x[1] + double{x[2]} * x[2]);
    if (len > 0) {
      for (int k = 0; k < 3; ++k) x[k] = static_cast<float>(x[k] / len);
    }
  };
  lerp(colors_, 3);
  lerp(uvs_, 2);
  lerp(normals_, 3);
  if (!normals_.empty()) normalize3(&normals_[3 * size_t{keep}]);
  if (!tangents_.empty()) {
    const float w = t > 0.5 ? tangents_[4 * size_t{gone} + 3] : tangents_[4 * size_t{keep} + 3];
    lerp(tangents_, 4);
    normalize3(&tangents_[4 * size_t{keep}]);
    tangents_[4 * size_t{keep} + 3] = w;
  }
}

bool Decimator::TryCollapse(uint32_t a, uint32_t b) {
  Faces(a, &faces_a_);
  Faces(b, &faces_b_);
  // Faces on the edge and their opposite vertices.
  uint32_t opposite[2];
  int shared = 0;
  for (uint32_t f : faces_a_) {
    const uint32_t* t = &faces_[3 * f];
    if (t[0] != b && t[1] != b && t[2] != b) continue;
    if (shared == 2) {
      ++report_.rejected_link;  // non-manifold edge
      return false;
    }
    opposite[shared++] = t[0] != a && t[0] != b ? t[0] : t[1] != a && t[1] != b ? t[1] : t[2];
  }
  if (shared == 0) return false;  // no longer an edge
  if (shared == 2 && (boundary_[a] && boundary_[b])) {
    ++report_.rejected_link;
    return false;
  }
  Ring(faces_a_, a, &ring_a_);
  Ring(faces_b_, b, &ring_b_);
  merged_.clear();
  std::set_intersection(ring_a_.begin(), ring_a_.end(), ring_b_.begin(), ring_b_.end(),
                        std::back_inserter(merged_));
  const bool link_ok =
      shared == 1 ? merged_.size() == 1 && merged_[0] == opposite[0]
                  : merged_.size() == 2 && opposite[0] != opposite[1] &&
                        std::find(merged_.begin(), merged_.end(), opposite[0]) != merged_.end() &&
                        std::find(merged_.begin(), merged_.end(), opposite[1]) != merged_.end();
  // The link edges must match too: an edge of both links would become a
  // doubled face (an interior edge of a tetrahedron: c-d in both links) or a
  // dangling one (a lone triangle or a triangle hanging by its corners: both
  // other sides on the boundary, i.e. c-"outside" in both links).
  auto faces_with = [this](const std::vector<uint32_t>& faces, uint32_t x, uint32_t y) {
    int found = 0;
    for (uint32_t f : faces) {
      const uint32_t* t = &faces_[3 * f];
      const bool has_x = t[0] == x || t[1] == x || t[2] == x;
      const bool has_y = t[0] == y || t[1] == y || t[2] == y;
      found += has_x && has_y;
    }
    return found;
  };
  const bool link_edges_ok = shared == 1 ? faces_with(faces_a_, a, opposite[0]) != 1 ||
                                               faces_with(faces_b_, b, opposite[0]) != 1
                                         : faces_with(faces_a_, opposite[0], opposite[1]) == 0 ||
                                               faces_with(faces_b_, opposite[0], opposite[1]) == 0;
  if (!link_ok || !link_edges_ok) {
    ++report_.rejected_link;
    return false;
  }

  Vec3d p;
  Place(a, b, &p);
  // Every surviving face around a or b with the moved vertex at p.
  for (const std::vector<uint32_t>* list : {&faces_a_, &faces_b_}) {
    for (uint32_t f : *list) {
      const uint32_t* t = &faces_[3 * f];
      const bool has_a = t[0] == a || t[1] == a || t[2] == a;
      const bool has_b = t[0] == b || t[1] == b || t[2] == b;
      if (has_a && has_b) continue;
      Vec3d c[3];
      for (int k = 0; k < 3; ++k) c[k] = (t[k] == a || t[k] == b) ? p : positions_[t[k]];
      const Vec3d e0 = Sub(c[1], c[0]), e1 = Sub(c[2], c[0]), e2 = Sub(c[2], c[1]);
      const Vec3d n_new = Cross(e0, e1);
      const double len = Norm(n_new);
      const double longest2 = std::max({Dot(e0, e0), Dot(e1, e1), Dot(e2, e2)});
      if (!(len > 1e-6 * longest2)) {
        ++report_.rejected_degenerate;
        return false;
      }
      const Vec3d n_old = FaceCross(f);
      const double old_len = Norm(n_old);
      const Vec3d n_in = {face_normal_in_[3 * f], face_normal_in_[3 * f + 1],
                          face_normal_in_[3 * f + 2]};
      const double min_dot = options_.min_normal_dot;
      if ((old_len > 0 && Dot(n_new, n_old) < min_dot * len * old_len) ||
          Dot(n_new, n_in) < min_dot * len) {
        ++report_.rejected_flip;
        return false;
      }
    }
  }

  // Commit: keep a, remove b.
  const Vec3d pa = positions_[a], e = Sub(positions_[b], pa);
  const double e2 = Dot(e, e);
  const double t = e2 > 0 ? std::clamp(Dot(Sub(p, pa), e) / e2, 0.0, 1.0) : 0.0;
  Interpolate(a, b, t);
  positions_[a] = p;
  quadrics_[a].Add(quadrics_[b]);
  boundary_[a] = boundary_[a] || boundary_[b];
  alive_[b] = 0;
  merged_.clear();
  for (uint32_t f : faces_a_) {
    const uint32_t* t3 = &faces_[3 * f];
    if (t3[0] == b || t3[1] == b || t3[2] == b) {
      face_alive_[f] = 0;
      --faces_alive_;
    } else {
      merged_.push_back(f);
    }
  }
  for (uint32_t f : faces_b_) {
    if (!face_alive_[f]) continue;
    for (int k = 0; k < 3; ++k) {
      if (faces_[3 * f + k] == b) faces_[3 * f + k] = a;
    }
    merged_.push_back(f);
  }
  std::sort(merged_.begin(), merged_.end());
  SetFaces(a, merged_);
  count_[b] = 0;
  ++version_[a];
  ++report_.collapses;
  Ring(merged_, a, &ring_b_);
  for (uint32_t w : ring_b_) Push(a, w);
  // Neighbors with a rejected collapse may pass now that their surroundings
  // changed: recompute their edges too (PushEdgesOf leaves ring_b_ alone).
  for (uint32_t w : ring_b_) {
    if (!retry_[w]) continue;
    retry_[w] = 0;
    ++version_[w];
    PushEdgesOf(w);
  }
  return true;
}

Mesh Decimator::Output() const {
  Mesh out;
  out.origin = mesh_.origin;
  const size_t n = positions_.size();
  std::vector<uint32_t> remap(n, UINT32_MAX);
  uint32_t next = 0;
  // Vertices keep their input order; faces too.
  std::vector<uint8_t> used(n, 0);
  for (size_t f = 0; f < face_alive_.size(); ++f) {
    if (!face_alive_[f]) continue;
    for (int k = 0; k < 3; ++k) used[faces_[3 * f + k]] = 1;
  }
  for (size_t v = 0; v < n; ++v) {
    if (!used[v]) continue;
    remap[v] = next++;
    for (int k = 0; k < 3; ++k) out.positions.push_back(static_cast<float>(positions_[v][k]));
    auto copy = [v](const std::vector<float>& from, int stride, std::vector<float>* to) {
      for (int k = 0; k < stride && !from.empty(); ++k) to->push_back(from[stride * v + k]);
    };
    copy(normals_, 3, &out.normals);
    copy(uvs_, 2, &out.uvs);
    copy(tangents_, 4, &out.tangents);
    for (int k = 0; k < 3 && !colors_.empty(); ++k) {
      out.colors.push_back(
          static_cast<uint8_t>(std::clamp(std::lround(colors_[3 * v + k]), 0L, 255L)));
    }
  }
  out.indices.reserve(3 * faces_alive_);
  for (size_t f = 0; f < face_alive_.size(); ++f) {
    if (!face_alive_[f]) continue;
    for (int k = 0; k < 3; ++k) out.indices.push_back(remap[faces_[3 * f + k]]);
  }
  return out;
}

Expected<Mesh> Decimator::Run() {
  PB_RETURN_IF_ERROR(Validate(mesh_));
  const size_t n = mesh_.vertex_count();
  report_.faces_in = mesh_.face_count();
  report_.vertices_in = n;
  faces_ = mesh_.indices;
  for (size_t f = 0; f < mesh_.face_count(); ++f) {
    const uint32_t* t = &faces_[3 * f];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      return Status::Invalid("mesh face " + std::to_string(f) + " repeats vertex " +
                             std::to_string(t[0] == t[1] || t[0] == t[2] ? t[0] : t[1]) +
                             " (remove degenerate faces first)");
    }
  }
  positions_.resize(n);
  for (size_t v = 0; v < n; ++v) {
    for (int k = 0; k < 3; ++k) positions_[v][k] = mesh_.positions[3 * v + k];
    if (!std::isfinite(positions_[v][0] + positions_[v][1] + positions_[v][2])) {
      return Status::Invalid("mesh vertex " + std::to_string(v) + " has a non-finite coordinate");
    }
  }
  PB_RETURN_IF_ERROR(FillHolesBelowOutput());
  const size_t face_count = faces_.size() / 3;
  normals_ = mesh_.normals;
  uvs_ = mesh_.uvs;
  tangents_ = mesh_.tangents;
  colors_.assign(mesh_.colors.begin(), mesh_.colors.end());
  face_alive_.assign(face_count, 1);
  faces_alive_ = face_count;
  alive_.assign(n, 1);
  retry_.assign(n, 0);
  version_.assign(n, 0);
  BuildAdjacency();
  BuildQuadrics();

  if (faces_alive_ > options_.target_faces) {
    // Compaction below keeps the heap under this: no reallocation, whose
    // old and new copies would together be the peak memory.
    heap_.reserve(2 * face_count + 1024);
    for (uint32_t v = 0; v < n; ++v) {
      Faces(v, &faces_a_);
      Ring(faces_a_, v, &ring_a_);
      for (uint32_t w : ring_a_) {
        if (w > v) heap_.Append(Entry(v, w));
      }
    }
    heap_.Heapify();
  }
  const size_t to_remove =
      faces_alive_ > options_.target_faces ? faces_alive_ - options_.target_faces : 0;
  uint64_t steps = 0;
  while (faces_alive_ > options_.target_faces && !heap_.empty()) {
    const HeapEntry entry = heap_.Pop();
    if (Stale(entry)) continue;
    if (!TryCollapse(entry.v0, entry.v1)) {
      retry_[entry.v0] = retry_[entry.v1] = 1;
    }
    // About 1.5 edges per face are live, so this keeps the heap in its
    // reservation; growth by half since the last compaction keeps the cost
    // amortized O(1) on meshes with more edges per face (loose triangles).
    if (heap_.size() >= 2 * faces_alive_ + 1024 &&
        heap_.size() >= heap_size_compacted_ + heap_size_compacted_ / 2 + 1024) {
      CompactHeap();
      heap_size_compacted_ = heap_.size();
    }
    if (options_.progress && ++steps % 16384 == 0 && to_remove > 0) {
      const size_t done = face_count - faces_alive_;
      options_.progress(std::min(1.0, static_cast<double>(done) / static_cast<double>(to_remove)));
    }
  }
  Mesh out = Output();
  report_.faces_out = out.face_count();
  report_.vertices_out = out.vertex_count();
  if (options_.progress) options_.progress(1.0);
  return out;
}

}  // namespace

Expected<Mesh> DecimateMesh(const Mesh& mesh, const DecimateOptions& options,
                            DecimateReport* report) {
  if (!(options.boundary_weight >= 0) || !std::isfinite(options.boundary_weight)) {
    return Status::Invalid("decimate: boundary_weight must be finite and >= 0, got " +
                           std::to_string(options.boundary_weight));
  }
  if (!(options.boundary_tolerance >= 0) || !std::isfinite(options.boundary_tolerance)) {
    return Status::Invalid("decimate: boundary_tolerance must be finite and >= 0, got " +
                           std::to_string(options.boundary_tolerance));
  }
  if (!(options.boundary_erosion >= 0 && options.boundary_erosion <= 1)) {
    return Status::Invalid("decimate: boundary_erosion must be in [0, 1], got " +
                           std::to_string(options.boundary_erosion));
  }
  if (!(options.min_normal_dot >= -1 && options.min_normal_dot <= 1)) {
    return Status::Invalid("decimate: min_normal_dot must be in [-1, 1], got " +
                           std::to_string(options.min_normal_dot));
  }
  if (!(options.fill_hole_output_edges >= 0) || !std::isfinite(options.fill_hole_output_edges)) {
    return Status::Invalid("decimate: fill_hole_output_edges must be finite and >= 0, got " +
                           std::to_string(options.fill_hole_output_edges));
  }
  if (!(options.fill_hole_max_component_fraction >= 0) ||
      !std::isfinite(options.fill_hole_max_component_fraction)) {
    return Status::Invalid("decimate: fill_hole_max_component_fraction must be finite and >= 0");
  }
  if (!(options.fill_hole_reach >= 0) || !std::isfinite(options.fill_hole_reach)) {
    return Status::Invalid("decimate: fill_hole_reach must be finite and >= 0, got " +
                           std::to_string(options.fill_hole_reach));
  }
  DecimateReport local;
  Decimator decimator(mesh, options, report ? report : &local);
  *(report ? report : &local) = DecimateReport();
  return decimator.Run();
}

}  // namespace pb
