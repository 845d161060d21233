// Mesh-to-mesh distance (see mesh_distance.h). Point-triangle distance:
// Ericson, "Real-Time Collision Detection", Morgan Kaufmann 2005, 5.1.5.
// Area-uniform triangle sampling: Osada, Funkhouser, Chazelle, Dobkin,
// "Shape distributions", ACM TOG 21(4), 2002, section 4.2.
#include "stages/geometry/mesh/distance.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace pb {
namespace {

Vec3 Sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double Dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 Madd(const Vec3& a, const Vec3& d, double t) {
  return {a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2]};
}
double Norm2(const Vec3& a) { return Dot(a, a); }

Vec3 Corner(const Mesh& mesh, uint32_t v, const std::array<double, 3>& shift) {
  return {mesh.positions[3 * size_t{v}] + shift[0], mesh.positions[3 * size_t{v} + 1] + shift[1],
          mesh.positions[3 * size_t{v} + 2] + shift[2]};
}

// splitmix64 (Steele, Lea, Flood, "Fast splittable pseudorandom number
// generators", OOPSLA 2014): fixed across platforms, unlike std distributions.
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}
  double Uniform() {  // [0, 1)
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
  }

 private:
  uint64_t state_;
};

// Squared distance from p to the box, 0 inside.
double BoxDistance2(const Vec3& p, const std::array<double, 3>& lo,
                    const std::array<double, 3>& hi) {
  double d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double d = p[a] < lo[a] ? lo[a] - p[a] : (p[a] > hi[a] ? p[a] - hi[a] : 0);
    d2 += d * d;
  }
  return d2;
}

// The float at or above x.
float Up(double x) {
  const float f = static_cast<float>(x);
  return static_cast<double>(f) < x ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}

// One point query of TriangleBvh's Embree engine: the point, relative to
// the mesh's origin, and the best face so far.
struct EmbreeQuery {
  const std::array<Vec3, 3>* triangles;  // in face order
  const std::array<float, 6>* boxes;     // each triangle's bounds (min xyz, max xyz)
  Vec3 p;
  double slack;  // added to the search radius (see SearchRadius)
  double best2;
  Vec3 best_q;
  uint32_t face;
};

// The radius Embree searches: the best distance plus a slack far above the
// float rounding of the query point and of Embree's boxes, rounded up to a
// float, so no candidate that could be nearer or tied is culled.
float SearchRadius(double best2, double slack) { return Up(std::sqrt(best2) + slack); }

// Called by rtcPointQuery for each triangle in a leaf within the radius.
// Returns true when it shrinks the radius.
bool OnEmbreeCandidate(RTCPointQueryFunctionArguments* args) {
  EmbreeQuery& q = *static_cast<EmbreeQuery*>(args->userPtr);
  const uint32_t f = args->primID;
  if (f == q.face) return false;  // the hint, measured already
  // Embree calls for every triangle of a leaf the sphere reaches; the
  // triangle's own box (float bounds of float corners: exact) culls most
  // before the exact distance, by the same radius and slack.
  const std::array<float, 6>& box = q.boxes[f];
  double box2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double lo = box[a], hi = box[3 + a];
    const double d = q.p[a] < lo ? lo - q.p[a] : (q.p[a] > hi ? q.p[a] - hi : 0);
    box2 += d * d;
  }
  const double radius = args->query->radius;
  if (box2 > radius * radius) return false;
  const auto& tri = q.triangles[f];
  const Vec3 c = ClosestPointOnTriangle(q.p, tri[0], tri[1], tri[2]);
  const double d2 = Norm2(Sub(q.p, c));
  if (!(d2 < q.best2 || (d2 == q.best2 && f < q.face))) return false;
  q.best2 = d2;
  q.best_q = c;
  q.face = f;
  args->query->radius = SearchRadius(d2, q.slack);
  return true;
}

// Distances for `points` by `distance`, in parallel, in chunks so progress
// is reported from one thread: from `begin` to `end` of the overall fraction.
template <typename F>
std::vector<double> Distances(const std::vector<Vec3>& points, const F& distance,
                              const MeshDistanceOptions& options, double begin, double end) {
  std::vector<double> out(points.size());
  constexpr size_t kChunk = 1 << 14;
  for (size_t start = 0; start < points.size(); start += kChunk) {
    const size_t stop = std::min(points.size(), start + kChunk);
    tbb::parallel_for(tbb::blocked_range<size_t>(start, stop, 256),
                      [&](const tbb::blocked_range<size_t>& range) {
                        for (size_t i = range.begin(); i < range.end(); ++i) {
                          out[i] = distance(points[i]);
                        }
                      });
    if (options.progress) {
      options.progress(begin + (end - begin) * static_cast<double>(stop) / points.size());
    }
  }
  return out;
}

}  // namespace

Vec3 ClosestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = Sub(b, a), ac = Sub(c, a), ap = Sub(p, a);
  const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;  // vertex region A
  const Vec3 bp = Sub(p, b);
  const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;  // vertex region B
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return Madd(a, ab, d1 / (d1 - d3));  // edge AB
  const Vec3 cp = Sub(p, c);
  const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;  // vertex region C
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return Madd(a, ac, d2 / (d2 - d6));  // edge AC
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {  // edge BC
    return Madd(b, Sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) {
    // Degenerate (collinear) triangle that fell through the region tests:
    // the nearest of its three edges.
    Vec3 best = a;
    double best_d2 = Norm2(Sub(p, a));
    const std::array<std::array<const Vec3*, 2>, 3> edges = {{{&a, &b}, {&b, &c}, {&a, &c}}};
    for (const auto& e : edges) {
      const Vec3 d = Sub(*e[1], *e[0]);
      const double len2 = Norm2(d);
      const double t = len2 > 0 ? std::clamp(Dot(Sub(p, *e[0]), d) / len2, 0.0, 1.0) : 0.0;
      const Vec3 q = Madd(*e[0], d, t);
      const double q_d2 = Norm2(Sub(p, q));
      if (q_d2 < best_d2) {
        best_d2 = q_d2;
        best = q;
      }
    }
    return best;
  }
  const double v = vb / sum, w = vc / sum;  // interior
  return {a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w};
}

// An Embree device with one scene of the mesh's triangles (its own copy of
// the float positions and of the indices).
struct TriangleBvh::EmbreeScene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  double magnitude = 0;  // largest |coordinate| of the vertices, for the slack
  std::vector<std::array<float, 6>> boxes;  // per face: min xyz, max xyz
  ~EmbreeScene() {
    if (scene != nullptr) rtcReleaseScene(scene);
    if (device != nullptr) rtcReleaseDevice(device);
  }
};

// The mesh's faces as an Embree scene, built with TBB in the caller's arena;
// null if Embree fails (no device, out of memory), the caller then uses the
// built-in tree.
std::unique_ptr<TriangleBvh::EmbreeScene> TriangleBvh::NewEmbreeScene(const Mesh& mesh) {
  auto out = std::make_unique<TriangleBvh::EmbreeScene>();
  out->device = rtcNewDevice(nullptr);
  if (out->device == nullptr) return nullptr;
  out->scene = rtcNewScene(out->device);
  RTCGeometry geometry =
      out->scene != nullptr ? rtcNewGeometry(out->device, RTC_GEOMETRY_TYPE_TRIANGLE) : nullptr;
  if (geometry == nullptr) return nullptr;
  // Embree's own buffers: they pad the end for its 16-byte vector loads.
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
      mesh.vertex_count()));
  auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t),
      mesh.face_count()));
  if (vertices == nullptr || indices == nullptr) {
    rtcReleaseGeometry(geometry);
    return nullptr;
  }
  std::copy(mesh.positions.begin(), mesh.positions.end(), vertices);
  std::copy(mesh.indices.begin(), mesh.indices.end(), indices);
  for (float x : mesh.positions) out->magnitude = std::max(out->magnitude, std::abs(double{x}));
  out->boxes.resize(mesh.face_count());
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    for (int a = 0; a < 3; ++a) {
      const float x0 = mesh.positions[3 * size_t{t[0]} + a];
      const float x1 = mesh.positions[3 * size_t{t[1]} + a];
      const float x2 = mesh.positions[3 * size_t{t[2]} + a];
      out->boxes[f][a] = std::min({x0, x1, x2});
      out->boxes[f][3 + a] = std::max({x0, x1, x2});
    }
  }
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(out->scene, geometry);
  rtcReleaseGeometry(geometry);  // the scene holds it
  rtcCommitScene(out->scene);
  if (rtcGetDeviceError(out->device) != RTC_ERROR_NONE) return nullptr;
  return out;
}

TriangleBvh::TriangleBvh(const Mesh& mesh, Engine engine) : origin_(mesh.origin) {
  triangles_.resize(mesh.face_count());
  const std::array<double, 3> zero{};
  for (size_t f = 0; f < triangles_.size(); ++f) {
    for (int k = 0; k < 3; ++k) triangles_[f][k] = Corner(mesh, mesh.indices[3 * f + k], zero);
  }
  if (triangles_.empty()) return;
  if (engine == Engine::kEmbree) {
    embree_ = NewEmbreeScene(mesh);
    if (embree_) return;
  }
  faces_.resize(triangles_.size());
  for (size_t f = 0; f < faces_.size(); ++f) faces_[f] = static_cast<uint32_t>(f);
  nodes_.reserve(2 * triangles_.size() / 4 + 2);
  Build();
  slots_.resize(faces_.size());
  for (size_t t = 0; t < faces_.size(); ++t) slots_[faces_[t]] = static_cast<uint32_t>(t);
}

TriangleBvh::~TriangleBvh() = default;

// Top-down median split on the longest axis of the centroid bounds; the two
// children of a node are adjacent in nodes_.
void TriangleBvh::Build() {
  constexpr uint32_t kLeafSize = 4;
  struct Task {
    uint32_t node, begin, end;
  };
  nodes_.emplace_back();
  std::vector<Task> stack = {{0, 0, static_cast<uint32_t>(triangles_.size())}};
  while (!stack.empty()) {
    const Task task = stack.back();
    stack.pop_back();
    Node node;
    node.min = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                std::numeric_limits<double>::infinity()};
    node.max = {-node.min[0], -node.min[1], -node.min[2]};
    std::array<double, 3> cmin = node.min, cmax = node.max;  // centroid bounds
    for (uint32_t t = task.begin; t < task.end; ++t) {
      for (int a = 0; a < 3; ++a) {
        const auto& tri = triangles_[t];
        node.min[a] = std::min({node.min[a], tri[0][a], tri[1][a], tri[2][a]});
        node.max[a] = std::max({node.max[a], tri[0][a], tri[1][a], tri[2][a]});
        const double c = tri[0][a] + tri[1][a] + tri[2][a];
        cmin[a] = std::min(cmin[a], c);
        cmax[a] = std::max(cmax[a], c);
      }
    }
    if (task.end - task.begin <= kLeafSize) {
      node.first = task.begin;
      node.count = task.end - task.begin;
      nodes_[task.node] = node;
      continue;
    }
    int axis = 0;
    for (int a = 1; a < 3; ++a) {
      if (cmax[a] - cmin[a] > cmax[axis] - cmin[axis]) axis = a;
    }
    const uint32_t mid = task.begin + (task.end - task.begin) / 2;
    // The split moves each triangle's face index with it (a permutation
    // sorted alongside, then applied).
    std::vector<uint32_t> order(task.end - task.begin);
    for (uint32_t i = 0; i < order.size(); ++i) order[i] = task.begin + i;
    std::nth_element(order.begin(), order.begin() + (mid - task.begin), order.end(),
                     [this, axis](uint32_t i, uint32_t j) {
                       const auto& x = triangles_[i];
                       const auto& y = triangles_[j];
                       return x[0][axis] + x[1][axis] + x[2][axis] <
                              y[0][axis] + y[1][axis] + y[2][axis];
                     });
    {
      std::vector<std::array<Vec3, 3>> tris(order.size());
      std::vector<uint32_t> faces(order.size());
      for (size_t i = 0; i < order.size(); ++i) {
        tris[i] = triangles_[order[i]];
        faces[i] = faces_[order[i]];
      }
      std::copy(tris.begin(), tris.end(), triangles_.begin() + task.begin);
      std::copy(faces.begin(), faces.end(), faces_.begin() + task.begin);
    }
    node.first = static_cast<uint32_t>(nodes_.size());
    node.count = 0;
    nodes_[task.node] = node;
    nodes_.emplace_back();
    nodes_.emplace_back();
    stack.push_back({node.first, task.begin, mid});
    stack.push_back({node.first + 1, mid, task.end});
  }
}

double TriangleBvh::Distance(const Vec3& point) const {
  return std::sqrt(Nearest(point).squared_distance_m2);
}

TriangleBvh::Hit TriangleBvh::Nearest(const Vec3& point) const {
  return Nearest(point, UINT32_MAX);
}

TriangleBvh::Hit TriangleBvh::Nearest(const Vec3& point, uint32_t hint_face) const {
  if (triangles_.empty()) return Hit{};
  const Vec3 p = Sub(point, origin_);
  Hit hit = embree_ ? NearestEmbree(p, hint_face) : NearestBuiltin(p, hint_face);
  hit.closest = {hit.closest[0] + origin_[0], hit.closest[1] + origin_[1],
                 hit.closest[2] + origin_[2]};
  return hit;
}

// Both engines take p relative to origin_ and return the closest point so.
TriangleBvh::Hit TriangleBvh::NearestEmbree(const Vec3& p, uint32_t hint_face) const {
  EmbreeQuery q;
  q.triangles = triangles_.data();
  q.boxes = embree_->boxes.data();
  q.p = p;
  // 1e-6 of the coordinates' magnitude: float rounding is 6e-8 of it.
  q.slack = 1e-6 * (1 + std::max({embree_->magnitude, std::abs(p[0]), std::abs(p[1]),
                                   std::abs(p[2])}));
  q.best2 = std::numeric_limits<double>::infinity();
  q.best_q = {};
  q.face = UINT32_MAX;
  if (hint_face < triangles_.size()) {
    const auto& tri = triangles_[hint_face];
    q.best_q = ClosestPointOnTriangle(p, tri[0], tri[1], tri[2]);
    q.best2 = Norm2(Sub(p, q.best_q));
    q.face = hint_face;
  }
  RTCPointQuery query;
  query.x = static_cast<float>(p[0]);
  query.y = static_cast<float>(p[1]);
  query.z = static_cast<float>(p[2]);
  query.time = 0;
  query.radius = SearchRadius(q.best2, q.slack);  // infinite without a hint
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(embree_->scene, &query, &context, &OnEmbreeCandidate, &q);
  Hit hit;
  hit.face = q.face;
  hit.closest = q.best_q;
  hit.squared_distance_m2 = q.best2;
  return hit;
}

TriangleBvh::Hit TriangleBvh::NearestBuiltin(const Vec3& p, uint32_t hint_face) const {
  Hit hit;
  double best2 = std::numeric_limits<double>::infinity();
  Vec3 best_q{};
  // The hint's distance prunes from the start. The answer cannot change: a
  // nearer face, or an equally near one of lower index, lies in a node at
  // most that far, which is never pruned (the test is "farther than").
  if (hint_face < slots_.size()) {
    const auto& tri = triangles_[slots_[hint_face]];
    best_q = ClosestPointOnTriangle(p, tri[0], tri[1], tri[2]);
    best2 = Norm2(Sub(p, best_q));
    hit.face = hint_face;
  }
  uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (BoxDistance2(p, node.min, node.max) > best2) continue;  // ties may still win
    if (node.count > 0) {
      for (uint32_t t = node.first; t < node.first + node.count; ++t) {
        const auto& tri = triangles_[t];
        const Vec3 q = ClosestPointOnTriangle(p, tri[0], tri[1], tri[2]);
        const double d2 = Norm2(Sub(p, q));
        if (d2 < best2 || (d2 == best2 && faces_[t] < hit.face)) {
          best2 = d2;
          best_q = q;
          hit.face = faces_[t];
        }
      }
      continue;
    }
    const Node& left = nodes_[node.first];
    const Node& right = nodes_[node.first + 1];
    const double dl = BoxDistance2(p, left.min, left.max);
    const double dr = BoxDistance2(p, right.min, right.max);
    if (dl < dr) {
      if (dr <= best2) stack[top++] = node.first + 1;
      if (dl <= best2) stack[top++] = node.first;
    } else {
      if (dl <= best2) stack[top++] = node.first;
      if (dr <= best2) stack[top++] = node.first + 1;
    }
  }
  hit.closest = best_q;
  hit.squared_distance_m2 = best2;
  return hit;
}

std::vector<Vec3> SampleMeshSurface(const Mesh& mesh, size_t count, uint64_t seed) {
  const size_t faces = mesh.face_count();
  std::vector<double> cumulative(faces);
  const std::array<double, 3> zero{};
  double total = 0;
  for (size_t f = 0; f < faces; ++f) {
    const Vec3 a = Corner(mesh, mesh.indices[3 * f], zero);
    const Vec3 u = Sub(Corner(mesh, mesh.indices[3 * f + 1], zero), a);
    const Vec3 v = Sub(Corner(mesh, mesh.indices[3 * f + 2], zero), a);
    const Vec3 n = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0]};
    total += 0.5 * std::sqrt(Norm2(n));
    cumulative[f] = total;
  }
  std::vector<Vec3> points;
  if (!(total > 0)) return points;
  points.reserve(count);
  Random random(seed);
  for (size_t i = 0; i < count; ++i) {
    const double pick = random.Uniform() * total;
    const size_t f =
        std::min<size_t>(faces - 1, std::upper_bound(cumulative.begin(), cumulative.end(), pick) -
                                        cumulative.begin());
    const double s = std::sqrt(random.Uniform());
    const double r2 = random.Uniform();
    const double wa = 1 - s, wb = s * (1 - r2), wc = s * r2;
    const Vec3 a = Corner(mesh, mesh.indices[3 * f], mesh.origin);
    const Vec3 b = Corner(mesh, mesh.indices[3 * f + 1], mesh.origin);
    const Vec3 c = Corner(mesh, mesh.indices[3 * f + 2], mesh.origin);
    points.push_back({wa * a[0] + wb * b[0] + wc * c[0], wa * a[1] + wb * b[1] + wc * c[1],
                      wa * a[2] + wb * b[2] + wc * c[2]});
  }
  return points;
}

DistanceStats ComputeDistanceStats(std::vector<double> d) {
  DistanceStats stats;
  stats.samples = d.size();
  if (d.empty()) return stats;
  double sum = 0, sum2 = 0;
  for (double x : d) {
    sum += x;
    sum2 += x * x;
    stats.max_m = std::max(stats.max_m, x);
  }
  stats.mean_m = sum / d.size();
  stats.rms_m = std::sqrt(sum2 / d.size());
  const size_t rank = static_cast<size_t>(std::ceil(0.95 * d.size())) - 1;  // nearest rank
  std::nth_element(d.begin(), d.begin() + rank, d.end());
  stats.p95_m = d[rank];
  return stats;
}

Expected<MeshDistanceResult> MeasureMeshDistance(const Mesh& mesh, const Mesh& truth_mesh,
                                                 const SynthScene* scene,
                                                 const MeshDistanceOptions& options) {
  if (Status s = Validate(mesh); !s.ok()) return s.WithContext("evaluated mesh");
  if (Status s = Validate(truth_mesh); !s.ok()) return s.WithContext("truth mesh");
  if (options.samples == 0) return Status::Invalid("mesh distance: samples must be > 0");
  // Different seeds per direction so the two sample sets are independent.
  const std::vector<Vec3> on_mesh = SampleMeshSurface(mesh, options.samples, options.seed);
  if (on_mesh.empty()) return Status::Invalid("evaluated mesh: no faces with positive area");
  const std::vector<Vec3> on_truth =
      SampleMeshSurface(truth_mesh, options.samples, options.seed ^ 0x5bd1e995u);
  if (on_truth.empty()) return Status::Invalid("truth mesh: no faces with positive area");
  if (options.progress) options.progress(0.05);

  MeshDistanceResult result;
  std::vector<double> forward;
  if (scene != nullptr) {
    result.analytic_mesh_to_truth = true;
    forward = Distances(
        on_mesh, [scene](const Vec3& p) { return std::abs(SampleSurface(*scene, p).distance_m); },
        options, 0.05, 0.4);
  } else {
    const TriangleBvh truth_bvh(truth_mesh);
    forward = Distances(
        on_mesh, [&truth_bvh](const Vec3& p) { return truth_bvh.Distance(p); }, options, 0.1, 0.4);
  }
  const TriangleBvh mesh_bvh(mesh);
  if (options.progress) options.progress(0.5);
  std::vector<double> backward = Distances(
      on_truth, [&mesh_bvh](const Vec3& p) { return mesh_bvh.Distance(p); }, options, 0.5, 1.0);

  std::vector<double> pooled = forward;
  pooled.insert(pooled.end(), backward.begin(), backward.end());
  result.mesh_to_truth = ComputeDistanceStats(std::move(forward));
  result.truth_to_mesh = ComputeDistanceStats(std::move(backward));
  result.symmetric = ComputeDistanceStats(std::move(pooled));
  result.symmetric.mean_m = 0.5 * (result.mesh_to_truth.mean_m + result.truth_to_mesh.mean_m);
  result.symmetric.max_m = std::max(result.mesh_to_truth.max_m, result.truth_to_mesh.max_m);
  return result;
}

Expected<std::vector<float>> VertexDistanceToTruth(const Mesh& mesh, const Mesh& truth_mesh,
                                                   const SynthScene* scene) {
  if (Status s = Validate(mesh); !s.ok()) return s.WithContext("evaluated mesh");
  if (Status s = Validate(truth_mesh); !s.ok()) return s.WithContext("truth mesh");
  if (scene == nullptr && truth_mesh.face_count() == 0) return Status::Invalid("truth mesh: no faces");
  std::vector<Vec3> vertices(mesh.vertex_count());
  for (size_t v = 0; v < vertices.size(); ++v) vertices[v] = Corner(mesh, uint32_t(v), mesh.origin);
  const MeshDistanceOptions no_progress;
  std::vector<double> d;
  if (scene != nullptr) {
    d = Distances(
        vertices, [scene](const Vec3& p) { return std::abs(SampleSurface(*scene, p).distance_m); }, no_progress, 0, 1);
  } else {
    const TriangleBvh truth_bvh(truth_mesh);
    d = Distances(vertices, [&truth_bvh](const Vec3& p) { return truth_bvh.Distance(p); }, no_progress, 0, 1);
  }
  return std::vector<float>(d.begin(), d.end());
}

}  // namespace pb
