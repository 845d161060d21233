// Normal estimation. References: H. Hoppe, T. DeRose, T. Duchamp,
// J. McDonald, W. Stuetzle, "Surface reconstruction from unorganized points",
// SIGGRAPH 1992: section 3.2 (tangent plane = PCA of the k-neighbourhood) and
// 3.3 (consistent orientation along a minimum spanning tree of the Riemannian
// graph, weight 1 - |n_i . n_j|). Departures: the graph is the directed kNN
// graph (each point's 8 nearest) without the Euclidean MST edges; Prim's
// priority queue is a 256-bucket queue (weights quantized); and the seed
// of each connected part is its point farthest from the cloud's centroid,
// oriented away from it (Hoppe seeds the highest point toward +z, which turns
// closed objects inside out when their top is not the seed's side), after
// the points whose side an enclosed space (a room) or rays (an object)
// decide. The 3x3
// eigen problem: eigenvalues in closed form (O. K. Smith, "Eigenvalues of a
// symmetric 3x3 matrix", CACM 4(4), 1961), then the eigenvector as a cross
// product of two rows of A - lambda I. The small eigenvalue loses relative
// accuracy to cancellation, but the eigenvector's error is that absolute
// error over the gap to the middle eigenvalue, tiny for a surface; when the
// gap is small (lines, blobs) cyclic Jacobi rotations (Golub & Van Loan,
// section 8.5) take over: accurate there, but 4x slower.
#include "stages/geometry/points/normals.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "stages/geometry/core/module.h"
#include "stages/geometry/points/enclosure.h"
#include "stages/geometry/points/knn.h"
#include "stages/geometry/points/lost_station.h"
#include "stages/geometry/points/module_calls.h"

namespace pb {
namespace {

constexpr int kMaxK = 100;
// Out-degree of the propagation graph: enough to cross sampling gaps, small
// enough that the graph stays at 32 bytes per point.
constexpr int kPropagationNeighbors = 8;
constexpr uint32_t kNoNeighbor = std::numeric_limits<uint32_t>::max();
// Points per progress step; each step is one parallel_for.
constexpr size_t kChunk = size_t{1} << 20;

// PCA normal of each point; fills `graph` (kPropagationNeighbors per point,
// self excluded) when it is not empty. With `widen_to_m` > 0, a point whose
// k nearest all lie within that radius takes its nearest points out to it
// instead (knn.h, WidenNeighborhood; NormalOptions::widen_dense); returns
// how many points gained neighbours.
size_t EstimateUnoriented(const KnnIndex& index, int k, double widen_to_m, std::vector<float>& normals,
                          std::vector<uint32_t>& graph, const std::function<void(double)>& progress) {
  const size_t n = index.size();
  const bool want_graph = !graph.empty();
  const int most = widen_to_m > 0 ? kWidenedNeighbors * k : k;
  std::atomic<size_t> widened{0};
  for (size_t chunk = 0; chunk < n; chunk += kChunk) {
    const size_t chunk_end = std::min(n, chunk + kChunk);
    // Walk tree slots so that consecutive queries share cache lines.
    tbb::parallel_for(tbb::blocked_range<size_t>(chunk, chunk_end, 1024),
                      [&](const tbb::blocked_range<size_t>& range) {
      // k + 1: the point itself may be among k duplicates, and the graph
      // wants kPropagationNeighbors others.
      std::vector<Neighbor> neighbors(std::max(most, kPropagationNeighbors + 1));
      size_t range_widened = 0;
      for (size_t slot = range.begin(); slot < range.end(); ++slot) {
        const uint32_t i = index.PointAtSlot(slot);
        const std::array<float, 3> p = index.PositionAtSlot(slot);
        int count = index.Query(p.data(), k, neighbors);
        if (widen_to_m > 0) {
          const int found = count;
          count = WidenNeighborhood([&](int want, std::span<Neighbor> out) { return index.Query(p.data(), want, out); },
                                    k, count, widen_to_m, neighbors);
          range_widened += count != found;
        }
        // Covariance about the neighbourhood's mean, relative to p for
        // precision far from the origin; the sums are double because a
        // near-planar neighbourhood's smallest eigenvalue is ~1e-6 of the
        // largest.
        double mean[3] = {0, 0, 0};
        for (int j = 0; j < count; ++j) {
          const std::array<float, 3> q = index.PositionAtSlot(neighbors[j].slot);
          for (int a = 0; a < 3; ++a) mean[a] += static_cast<double>(q[a]) - p[a];
        }
        for (double& m : mean) m /= count;
        double cov[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
        for (int j = 0; j < count; ++j) {
          const std::array<float, 3> q = index.PositionAtSlot(neighbors[j].slot);
          double d[3];
          for (int a = 0; a < 3; ++a) d[a] = static_cast<double>(q[a]) - p[a] - mean[a];
          for (int r = 0; r < 3; ++r) {
            for (int c = r; c < 3; ++c) cov[3 * r + c] += d[r] * d[c];
          }
        }
        cov[3] = cov[1];
        cov[6] = cov[2];
        cov[7] = cov[5];
        double normal[3];
        PlaneNormal(cov, normal);
        for (int a = 0; a < 3; ++a) normals[3 * i + a] = static_cast<float>(normal[a]);
        if (want_graph) {
          // The PCA neighbourhood holds the graph edges when it is big enough.
          const int others = k > kPropagationNeighbors
                                 ? count
                                 : index.QueryPoint(i, kPropagationNeighbors, neighbors);
          uint32_t* edges = &graph[size_t{kPropagationNeighbors} * i];
          int edge = 0;
          for (int j = 0; j < others && edge < kPropagationNeighbors; ++j) {
            if (neighbors[j].index != i) edges[edge++] = neighbors[j].index;
          }
        }
      }
      widened += range_widened;
    });
    if (progress) progress(0.8 * static_cast<double>(chunk_end) / static_cast<double>(n));
  }
  return widened.load();
}

// Turns each normal toward its point's station, or toward `only` (absolute)
// for every point when given.
size_t OrientTowardStations(PointCloud& cloud, const std::array<double, 3>* only = nullptr) {
  const size_t n = cloud.size();
  std::vector<std::array<double, 3>> stations;
  for (const auto& station : only ? std::vector<std::array<double, 3>>{*only} : cloud.stations) {
    stations.push_back({station[0] - cloud.origin[0], station[1] - cloud.origin[1],
                        station[2] - cloud.origin[2]});
  }
  size_t flipped = 0;
  for (size_t i = 0; i < n; ++i) {
    const auto& s = stations[only ? 0 : cloud.station_ids[i]];
    float* normal = &cloud.normals[3 * i];
    double dot = 0;
    for (int a = 0; a < 3; ++a) dot += (s[a] - cloud.positions[3 * i + a]) * normal[a];
    if (dot < 0) {
      for (int a = 0; a < 3; ++a) normal[a] = -normal[a];
      ++flipped;
    }
  }
  return flipped;
}

// Index of the first point whose normal is not finite or (nearly) zero, or
// n when every normal can give a side.
size_t FirstUnusableNormal(const std::vector<float>& normals) {
  const size_t n = normals.size() / 3;
  for (size_t i = 0; i < n; ++i) {
    const float* v = &normals[3 * i];
    const double length2 = double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2];
    if (!std::isfinite(length2) || !(length2 > 1e-12)) return i;
  }
  return n;
}

size_t OrientLikeInput(PointCloud& cloud, const std::vector<float>& input) {
  const size_t n = cloud.size();
  size_t flipped = 0;
  for (size_t i = 0; i < n; ++i) {
    float* normal = &cloud.normals[3 * i];
    double dot = 0;
    for (int a = 0; a < 3; ++a) dot += double(input[3 * i + a]) * normal[a];
    if (dot < 0) {
      for (int a = 0; a < 3; ++a) normal[a] = -normal[a];
      ++flipped;
    }
  }
  return flipped;
}

// Of the graph's pairs of neighbours on one smooth surface (PCA normals
// within 26 degrees) whose file normals lie within 60 degrees of their PCA
// normals' lines, the share whose file sides disagree: a file whose
// normals a tool computed without orienting them (random signs, or all on
// one side of an axis: a "preferred orientation") disagrees on many, an
// oriented one only where two close surfaces meet. Measured on the statue
// stand-in: random 50 %, all toward +y 13 %, its stations' sides 1.1 %;
// the living room's file 0.007 % (kMaxInputSidesDisagree, normals.h).

double InputSidesDisagree(const std::vector<float>& normals, const std::vector<float>& input,
                          const std::vector<uint32_t>& graph) {
  const size_t n = normals.size() / 3;
  // The file's side at point i: +1, -1, or 0 when its normal is nearly
  // across the PCA normal's line.
  auto side = [&](size_t i) {
    double d = 0, m = 0;
    for (int a = 0; a < 3; ++a) {
      d += double(input[3 * i + a]) * normals[3 * i + a];
      m += double(input[3 * i + a]) * input[3 * i + a];
    }
    return d >= 0.5 * std::sqrt(m) ? 1 : d <= -0.5 * std::sqrt(m) ? -1 : 0;
  };
  size_t pairs = 0, disagree = 0;
  for (size_t i = 0; i < n; ++i) {
    const int si = side(i);
    if (si == 0) continue;
    for (int j = 0; j < kPropagationNeighbors; ++j) {
      const uint32_t t = graph[size_t{kPropagationNeighbors} * i + j];
      if (t == kNoNeighbor) continue;
      double c = 0;
      for (int a = 0; a < 3; ++a) c += double(normals[3 * i + a]) * normals[3 * size_t{t} + a];
      if (std::fabs(c) < 0.9) continue;
      const int st = side(t);
      if (st == 0) continue;
      ++pairs;
      disagree += (si * st * c) < 0;
    }
  }
  return pairs == 0 ? 0.0 : double(disagree) / double(pairs);
}

struct Edge {
  uint32_t target;
  uint32_t parent;
};

// Prim's frontier as a bucket queue over the weight 1 - |n_i . n_j| in [0, 1]
// (Dial's algorithm): O(1) per edge instead of a binary heap's O(log E), 3x
// faster on 10^6 points. Edges within one bucket (weights within 1/256) pop
// last-in first-out, so the tree is an MST up to that quantization.
class Frontier {
 public:
  void Push(float weight, Edge edge) {
    const size_t bucket = std::min(kBuckets - 1, static_cast<size_t>(weight * kBuckets));
    buckets_[bucket].push_back(edge);
    lowest_ = std::min(lowest_, bucket);
    ++size_;
  }
  bool empty() const { return size_ == 0; }
  Edge Pop() {
    while (buckets_[lowest_].empty()) ++lowest_;
    const Edge edge = buckets_[lowest_].back();
    buckets_[lowest_].pop_back();
    --size_;
    return edge;
  }

 private:
  static constexpr size_t kBuckets = 256;
  std::array<std::vector<Edge>, kBuckets> buckets_;
  size_t lowest_ = 0;
  size_t size_ = 0;
};

// Which side of the surface at a point is its outside, by rays (kPropagate
// of an object): the voxels holding points, on a grid over the cloud's box
// (0.1st to 99.9th percentile per axis), voxels at least twice the median
// distance to a point's kPropagationNeighbors-th neighbour so that a sampled
// surface stops a ray, at most kEscapeGridSide a side. A ray from a point,
// started kEscapeStartVoxels out so that it clears the point's own surface,
// escapes when it leaves the box without entering an occupied voxel.
constexpr int kEscapeGridSide = 256;
constexpr double kEscapeStartVoxels = 3;
constexpr double kNearVoxels = 2;
constexpr int kRayDirections = 48;
constexpr double kOpenShare = 0.75;
// Points whose sides rays look for, at most (every n / this-th point).
constexpr size_t kMaxRayPoints = 100000;
constexpr int kRayNeighbours = 8;
constexpr int kRayConsensus = 3;

class EscapeGrid {
 public:
  EscapeGrid(const PointCloud& cloud, const std::vector<uint32_t>& graph) {
    const size_t n = cloud.size();
    const float* positions = cloud.positions.data();
    const Bounds box = RobustLocalBounds(cloud, 0.001);
    double extent = 0;
    for (int a = 0; a < 3; ++a) {
      lo_[a] = box.min_m[a];
      extent = std::max(extent, box.max_m[a] - box.min_m[a]);
    }
    const size_t step = std::max<size_t>(1, n / 100000);
    std::vector<double> reach;
    for (size_t i = 0; i < n; i += step) {
      double farthest = 0;
      for (int j = 0; j < kPropagationNeighbors; ++j) {
        const uint32_t t = graph[size_t{kPropagationNeighbors} * i + j];
        if (t == kNoNeighbor) continue;
        double d2 = 0;
        for (int a = 0; a < 3; ++a) {
          const double d = double(positions[3 * t + a]) - positions[3 * i + a];
          d2 += d * d;
        }
        farthest = std::max(farthest, d2);
      }
      reach.push_back(std::sqrt(farthest));
    }
    std::nth_element(reach.begin(), reach.begin() + reach.size() / 2, reach.end());
    voxel_ = std::max({extent / kEscapeGridSide, 2.0 * reach[reach.size() / 2], 1e-9});
    for (int a = 0; a < 3; ++a) {
      dims_[a] = std::clamp(int(std::ceil((box.max_m[a] - box.min_m[a]) / voxel_)), 1, kEscapeGridSide);
    }
    // A Fibonacci sphere: kRayDirections nearly even directions.
    for (int k = 0; k < kRayDirections; ++k) {
      const double z = 1.0 - (2.0 * k + 1.0) / kRayDirections;
      const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
      const double phi = k * std::numbers::pi * (3.0 - std::sqrt(5.0));
      directions_.push_back({float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)});
    }
    occupied_.assign(size_t(dims_[0]) * dims_[1] * dims_[2], 0);
    for (size_t i = 0; i < n; ++i) {
      const size_t cell = Cell(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]);
      if (cell != kOutside) occupied_[cell] = 1;
    }
  }

  // +1 when the side the normal faces is open and the other closed: of the
  // rays within 60 degrees of the normal (kRayDirections spread over the
  // sphere) at least kOpenShare more escape than of those within 60 degrees
  // of its opposite; -1 for the reverse; else 0. Cones, not one ray each
  // way, so that a gap in the scan behind the surface does not decide
  // alone, and the share, so that a ground beside a wall (half its sky
  // hidden, nothing scanned below it) does not decide either.
  int OpenSide(const float* p, const float* normal) const {
    int out = 0, out_rays = 0, in = 0, in_rays = 0;
    for (const auto& d : directions_) {
      const double cosine = d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2];
      if (std::fabs(cosine) < 0.5) continue;
      const Ray ray = Cast(p, d.data());
      if (ray == Ray::kNear) continue;
      if (cosine > 0) {
        ++out_rays;
        out += ray == Ray::kEscapes;
      } else {
        ++in_rays;
        in += ray == Ray::kEscapes;
      }
    }
    if (out_rays == 0 || in_rays == 0) return 0;
    const double open = double(out) / out_rays - double(in) / in_rays;
    return open >= kOpenShare ? 1 : open <= -kOpenShare ? -1 : 0;
  }

  // kEscapes: the ray leaves the box; kMeets: it meets surface at least
  // kNearVoxels past its start; kNear: sooner. A ray that meets surface at
  // once runs along a neighbouring one (a ground point at the foot of a
  // wall, looking up the wall) and tells nothing of an inside.
  enum class Ray { kEscapes, kMeets, kNear };
  Ray Cast(const float* p, const float* direction) const {
    const double step = 0.5 * voxel_;
    const double start = kEscapeStartVoxels * voxel_, near = start + kNearVoxels * voxel_;
    for (double t = start;; t += step) {
      double q[3];
      for (int a = 0; a < 3; ++a) q[a] = p[a] + t * direction[a];
      const size_t cell = Cell(q[0], q[1], q[2]);
      if (cell == kOutside) return Ray::kEscapes;
      if (occupied_[cell]) return t < near ? Ray::kNear : Ray::kMeets;
    }
  }

 private:
  static constexpr size_t kOutside = std::numeric_limits<size_t>::max();
  size_t Cell(double x, double y, double z) const {
    const double q[3] = {x, y, z};
    int c[3];
    for (int a = 0; a < 3; ++a) {
      const double f = (q[a] - lo_[a]) / voxel_;
      if (!(f >= 0) || f >= dims_[a]) return kOutside;
      c[a] = int(f);
    }
    return (size_t(c[2]) * dims_[1] + c[1]) * dims_[0] + c[0];
  }

  double lo_[3] = {0, 0, 0};
  double voxel_ = 1;
  int dims_[3] = {1, 1, 1};
  std::vector<uint8_t> occupied_;
  std::vector<std::array<float, 3>> directions_;
};

// Propagation (normals.h, kPropagate). `inward` seeds each part facing the
// centroid instead of away from it. With a non-empty `enclosure`, every point
// whose one side lies in the enclosed space and whose other does not faces
// it first, and the propagation spreads from those points.
void OrientByPropagation(PointCloud& cloud, const std::vector<uint32_t>& graph, bool inward,
                         const EnclosedSpace* enclosure, NormalReport& report) {
  const size_t n = cloud.size();
  const float* positions = cloud.positions.data();
  float* normals = cloud.normals.data();
  double centroid[3] = {0, 0, 0};
  for (size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) centroid[a] += positions[3 * i + a];
  }
  for (double& c : centroid) c /= static_cast<double>(n);
  // Seeds in order of decreasing distance from the centroid.
  std::vector<std::pair<double, uint32_t>> by_distance(n);
  for (size_t i = 0; i < n; ++i) {
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
      const double d = positions[3 * i + a] - centroid[a];
      d2 += d * d;
    }
    by_distance[i] = {-d2, static_cast<uint32_t>(i)};
  }
  std::sort(by_distance.begin(), by_distance.end());

  auto dot = [normals](size_t a, size_t b) {
    return normals[3 * a] * normals[3 * b] + normals[3 * a + 1] * normals[3 * b + 1] +
           normals[3 * a + 2] * normals[3 * b + 2];
  };
  size_t flipped = 0;
  auto flip = [normals, &flipped](size_t i) {
    for (int a = 0; a < 3; ++a) normals[3 * i + a] = -normals[3 * i + a];
    ++flipped;
  };
  std::vector<uint8_t> visited(n, 0);
  Frontier frontier;
  auto visit = [&](uint32_t i) {
    visited[i] = 1;
    for (int j = 0; j < kPropagationNeighbors; ++j) {
      const uint32_t t = graph[size_t{kPropagationNeighbors} * i + j];
      if (t == kNoNeighbor || visited[t]) continue;
      frontier.Push(1.0f - std::fabs(dot(i, t)), {t, i});
    }
  };
  auto grow = [&] {
    while (!frontier.empty()) {
      const Edge edge = frontier.Pop();
      if (visited[edge.target]) continue;
      if (dot(edge.parent, edge.target) < 0) flip(edge.target);
      visit(edge.target);
    }
  };
  if (enclosure != nullptr) {
    // Probes 1.5 voxels ahead of and behind each point: one in the space,
    // the other not, decides the side (a wall's, a table's in the room);
    // both or neither (a thin part, a wall between two rooms, surface far
    // from the room) leaves it to the propagation.
    const float probe = float(1.5 * enclosure->voxel_m());
    std::vector<uint32_t> decided;
    for (size_t i = 0; i < n; ++i) {
      float ahead[3], behind[3];
      for (int a = 0; a < 3; ++a) {
        ahead[a] = positions[3 * i + a] + probe * normals[3 * i + a];
        behind[a] = positions[3 * i + a] - probe * normals[3 * i + a];
      }
      const bool front = enclosure->Contains(ahead), back = enclosure->Contains(behind);
      if (front == back) continue;
      if (back) flip(i);
      visited[i] = 1;
      decided.push_back(uint32_t(i));
    }
    report.facing_enclosure = decided.size();
    for (uint32_t i : decided) {
      visited[i] = 0;  // visit() marks it again and queues its edges
      visit(i);
    }
    grow();
  } else if (!inward) {
    // An object (no enclosed space): rays decide the points whose outside
    // they see, open within 60 degrees of one side and closed on the other
    // (EscapeGrid::OpenSide), at most kMaxRayPoints of them; the
    // propagation grows from those points. The seeds below alone fail where the point
    // farthest from the centroid has its normal across the way out: a
    // statue's ground, seeded at its rim, faced down, and through the
    // ground the plinth standing on it faced in. Points open on both sides
    // (an open sheet, a ground, a front-only scan) or closed on both (a
    // concave fold) are left to the propagation.
    const EscapeGrid grid(cloud, graph);
    const size_t stride = std::max<size_t>(1, n / kMaxRayPoints);
    const size_t probes = (n + stride - 1) / stride;
    std::vector<int8_t> side(probes, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, probes, 256), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t k = range.begin(); k < range.end(); ++k) {
        const size_t i = k * stride;
        side[k] = grid.OpenSide(&positions[3 * i], &normals[3 * i]);
      }
    });
    // A decision stands when at least kRayConsensus of the nearest
    // kRayNeighbours probes are decided alike (their outsides within 60
    // degrees) and more than are decided against: a lone decision (a
    // ground point at a wall's foot; a ray through a scan's gap) would
    // otherwise win a whole undecided ground for its side.
    std::vector<float> at(3 * probes);
    for (size_t k = 0; k < probes; ++k) {
      for (int a = 0; a < 3; ++a) at[3 * k + a] = positions[3 * k * stride + a];
    }
    const Expected<KnnIndex> probe_index = KnnIndex::Build(at);
    std::vector<uint32_t> decided;
    if (probe_index.ok()) {
      std::vector<Neighbor> near(kRayNeighbours);
      for (size_t k = 0; k < probes; ++k) {
        if (side[k] == 0) continue;
        const int found = probe_index->QueryPoint(uint32_t(k), kRayNeighbours, near);
        int agree = 0, against = 0;
        for (int j = 0; j < found; ++j) {
          const size_t m = near[j].index;
          if (side[m] == 0) continue;
          const double alike = side[k] * side[m] * dot(k * stride, m * stride);
          agree += alike >= 0.5;
          against += alike <= -0.5;
        }
        if (agree >= kRayConsensus && agree > against) decided.push_back(uint32_t(k * stride));
      }
    }
    for (uint32_t i : decided) {
      if (side[i / stride] < 0) flip(i);
      visited[i] = 1;
    }
    report.facing_rays = decided.size();
    for (uint32_t i : decided) {
      visited[i] = 0;  // visit() marks it again and queues its edges
      visit(i);
    }
    grow();
  }
  for (const auto& [negative_d2, seed] : by_distance) {
    if (visited[seed]) continue;
    double outward = 0;
    for (int a = 0; a < 3; ++a) outward += (positions[3 * seed + a] - centroid[a]) * normals[3 * seed + a];
    if (inward ? outward > 0 : outward < 0) flip(seed);
    visit(seed);
    grow();
  }
  report.flipped = flipped;
}

// The propagation graph alone (kPropagationNeighbors per point, self
// excluded), for normals computed by another library.
void NeighborGraph(const KnnIndex& index, std::vector<uint32_t>& graph) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, index.size(), 1024),
                    [&](const tbb::blocked_range<size_t>& range) {
    std::vector<Neighbor> neighbors(kPropagationNeighbors);
    for (size_t slot = range.begin(); slot < range.end(); ++slot) {
      const uint32_t i = index.PointAtSlot(slot);
      const int count = index.QueryPoint(i, kPropagationNeighbors, neighbors);
      uint32_t* edges = &graph[size_t{kPropagationNeighbors} * i];
      int edge = 0;
      for (int j = 0; j < count && edge < kPropagationNeighbors; ++j) {
        if (neighbors[j].index != i) edges[edge++] = neighbors[j].index;
      }
    }
  });
}

// Unoriented normals from PCL's NormalEstimationOMP or Open3D's
// EstimateNormals, through their module. A normal the library could not fit
// (non-finite or zero) becomes +z, so every normal is a unit vector.
Status EstimateWithModule(PointCloud& cloud, const NormalOptions& options) {
  // Our kd-tree names a non-finite point; the libraries would not.
  PB_RETURN_IF_ERROR(CheckFinitePositions(cloud, "normal estimation"));
  const bool pcl = options.implementation == NormalImplementation::kPcl;
  PB_ASSIGN_OR_RETURN(
      void* symbol,
      pcl ? ModuleSymbol(kPclModule, PB_PCL_NORMALS_SYMBOL,
                         "normal estimation (implementation 'pcl')")
          : ModuleSymbol(kOpen3dModule, PB_OPEN3D_NORMALS_SYMBOL,
                         "normal estimation (implementation 'open3d')"));
  std::vector<float> normals;
  std::string error;
  NormalsModuleCall call;
  call.cloud = &cloud;
  call.k = options.k;
  call.threads = options.threads > 0 ? options.threads
                                     : tbb::this_task_arena::max_concurrency();
  call.normals = &normals;
  call.error = &error;
  if (!reinterpret_cast<bool (*)(NormalsModuleCall*)>(symbol)(&call)) {
    return Status::Internal(std::string(pcl ? "PCL" : "Open3D") + " normal estimation failed: " +
                            error);
  }
  if (normals.size() != cloud.positions.size()) {
    return Status::Internal(std::string(pcl ? "PCL" : "Open3D") + " returned " +
                            std::to_string(normals.size() / 3) + " normals for " +
                            std::to_string(cloud.size()) + " points");
  }
  for (size_t i = 0; i < cloud.size(); ++i) {
    float* q = &normals[3 * i];
    const double length = std::sqrt(double{q[0]} * q[0] + double{q[1]} * q[1] + double{q[2]} * q[2]);
    if (!(length > 0) || !std::isfinite(length)) {
      q[0] = q[1] = 0;
      q[2] = 1;
      continue;
    }
    for (int a = 0; a < 3; ++a) q[a] = static_cast<float>(q[a] / length);
  }
  cloud.normals = std::move(normals);
  if (options.progress) options.progress(0.8);
  return Status::Ok();
}

Status EstimateInArena(PointCloud& cloud, const NormalOptions& options, NormalReport& report) {
  const size_t n = cloud.size();
  NormalOrientation orientation = options.orientation;
  // The cloud's own normals, kept for their sides before they are replaced.
  std::vector<float> input;
  const size_t unusable = cloud.has_normals() ? FirstUnusableNormal(cloud.normals) : 0;
  if (orientation == NormalOrientation::kAuto) {
    orientation = cloud.has_stations() && !cloud.stations.empty() ? NormalOrientation::kStations
                  : cloud.has_normals() && unusable == n     ? NormalOrientation::kInput
                                                             : NormalOrientation::kPropagate;
  }
  if (orientation == NormalOrientation::kInput) {
    if (!cloud.has_normals()) {
      return Status::Invalid(
          "normal estimation: orientation 'input' needs the cloud's own normals, and this cloud "
          "has none; use orientation 'auto', 'stations' or 'propagate'");
    }
    if (unusable < n) {
      return Status::Invalid("normal estimation: orientation 'input': point " +
                             std::to_string(unusable) +
                             " has a zero or non-finite normal; use orientation 'propagate'");
    }
    input = cloud.normals;
  }
  if (orientation == NormalOrientation::kStations) {
    if (!cloud.has_stations() || cloud.stations.empty()) {
      return Status::Invalid(
          "normal estimation: orientation 'stations' needs per-point station ids and station "
          "positions, and this cloud has none; use orientation 'propagate' or 'auto'");
    }
  }
  // `auto` checks the sides of the normals it would take from the file.
  const bool check_input =
      options.orientation == NormalOrientation::kAuto && orientation == NormalOrientation::kInput;
  std::vector<uint32_t> graph;
  if (orientation == NormalOrientation::kPropagate || check_input) {
    graph.assign(n * kPropagationNeighbors, kNoNeighbor);
  }
  // Kept for the lost station's search (released after it): the points do
  // not move.
  std::optional<KnnIndex> index;
  if (options.implementation == NormalImplementation::kOwn) {
    PB_ASSIGN_OR_RETURN(index, KnnIndex::Build(cloud.positions));
    cloud.normals.assign(3 * n, 0.0f);
    if (options.widen_dense) report.widen_to_m = MedianNeighborhoodRadius(*index, options.k);
    report.widened = EstimateUnoriented(*index, options.k, report.widen_to_m, cloud.normals, graph, options.progress);
  } else {
    PB_RETURN_IF_ERROR(EstimateWithModule(cloud, options));
    if (!graph.empty()) {
      PB_ASSIGN_OR_RETURN(index, KnnIndex::Build(cloud.positions));
      NeighborGraph(*index, graph);
    }
  }
  report.points = n;
  if (check_input) {
    report.input_sides_checked = true;
    report.input_sides_disagree = InputSidesDisagree(cloud.normals, input, graph);
    if (report.input_sides_disagree > kMaxInputSidesDisagree) orientation = NormalOrientation::kPropagate;
  }
  report.orientation_used = orientation;
  if (orientation == NormalOrientation::kStations) report.flipped = OrientTowardStations(cloud);
  if (orientation == NormalOrientation::kInput) report.flipped = OrientLikeInput(cloud, input);
  if (orientation == NormalOrientation::kPropagate) {
    std::optional<EnclosedSpace> enclosure;
    if (options.interior == NormalInterior::kAuto) {
      PB_ASSIGN_OR_RETURN(enclosure, EnclosedSpace::Find(cloud));
      report.enclosed_volume_m3 = enclosure->volume_m3();
      if (enclosure->empty()) enclosure.reset();
    }
    if (!enclosure && options.find_station && options.orientation == NormalOrientation::kAuto &&
        options.interior == NormalInterior::kAuto && n >= kLeastPointsForStation) {
      LostStationOptions lost_options;
      lost_options.up = {0, 0, 0};  // unknown: the cloud's x, y or z
      // A cloud the search cannot read (all its points at one place) is
      // left to the propagation, as before.
      if (const Expected<LostStation> lost = FindLostStation(cloud, lost_options, index ? &*index : nullptr);
          lost.ok()) {
        report.station_searched = true;
        report.station_found = lost->found;
        report.station = lost->position;
        report.station_verdict = lost->verdict + " (" + lost->figures + ")";
      }
    }
    index.reset();
    // No room closed in and no station: a room open on a side or small
    // (a corridor, a cell; enclosure.h's FindOpen) still faces in.
    if (!enclosure && !report.station_found && options.interior == NormalInterior::kAuto) {
      PB_ASSIGN_OR_RETURN(enclosure, EnclosedSpace::FindOpen(cloud));
      report.enclosed_volume_m3 = enclosure->volume_m3();
      report.enclosure_open = !enclosure->empty();
      if (enclosure->empty()) enclosure.reset();
    }
    if (report.station_found) {
      report.orientation_used = NormalOrientation::kStations;
      report.flipped = OrientTowardStations(cloud, &report.station);
    } else {
      OrientByPropagation(cloud, graph, options.interior == NormalInterior::kYes,
                          enclosure ? &*enclosure : nullptr, report);
    }
  }
  if (options.progress) options.progress(1.0);
  return Status::Ok();
}

}  // namespace

double SmallestEigenvector(const double matrix[9], double vector[3]) {
  double a[3][3], v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) a[r][c] = matrix[3 * r + c];
  }
  for (int sweep = 0; sweep < 50; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double diagonal = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
    if (off <= 1e-30 * diagonal || off == 0) break;
    for (int p = 0; p < 2; ++p) {
      for (int q = p + 1; q < 3; ++q) {
        if (a[p][q] == 0) continue;
        // Rotation that zeroes a[p][q] (Golub & Van Loan, Algorithm 8.5.1).
        const double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < 3; ++k) {
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {
          const double vkp = v[k][p], vkq = v[k][q];
          v[k][p] = c * vkp - s * vkq;
          v[k][q] = s * vkp + c * vkq;
        }
      }
    }
  }
  int smallest = 0;
  for (int i = 1; i < 3; ++i) {
    if (a[i][i] < a[smallest][smallest]) smallest = i;
  }
  const double length = std::sqrt(v[0][smallest] * v[0][smallest] + v[1][smallest] * v[1][smallest] +
                                  v[2][smallest] * v[2][smallest]);
  for (int r = 0; r < 3; ++r) vector[r] = v[r][smallest] / length;
  return a[smallest][smallest];
}

void PlaneNormal(const double a[9], double vector[3]) {
  const double a00 = a[0], a01 = a[1], a02 = a[2], a11 = a[4], a12 = a[5], a22 = a[8];
  // Eigenvalues in closed form (Smith 1961): B = (A - q I) / p has
  // eigenvalues 2 cos(phi + 2 pi j / 3) with cos(3 phi) = det(B) / 2.
  const double q = (a00 + a11 + a22) / 3;
  const double b00 = a00 - q, b11 = a11 - q, b22 = a22 - q;
  const double off = a01 * a01 + a02 * a02 + a12 * a12;
  const double p = std::sqrt((b00 * b00 + b11 * b11 + b22 * b22 + 2 * off) / 6);
  if (p > 0 && std::isfinite(p)) {
    const double det = b00 * (b11 * b22 - a12 * a12) - a01 * (a01 * b22 - a12 * a02) +
                       a02 * (a01 * a12 - b11 * a02);
    const double r = std::clamp(det / (2 * p * p * p), -1.0, 1.0);
    const double phi = std::acos(r) / 3;
    const double largest = q + 2 * p * std::cos(phi);
    const double smallest = q + 2 * p * std::cos(phi + 2 * std::numbers::pi / 3);
    const double middle = 3 * q - largest - smallest;
    // The eigenvector is as accurate as (rounding of A) / (middle -
    // smallest); with a gap of 1/1000 of the spread that is ~1e-13 rad.
    if (middle - smallest >= 1e-3 * (largest - smallest)) {
      // A - smallest I has rank 2; its null vector is the cross product of
      // two rows: take the best conditioned pair.
      const double r0[3] = {a00 - smallest, a01, a02};
      const double r1[3] = {a01, a11 - smallest, a12};
      const double r2[3] = {a02, a12, a22 - smallest};
      auto cross = [](const double u[3], const double v[3], double out[3]) {
        out[0] = u[1] * v[2] - u[2] * v[1];
        out[1] = u[2] * v[0] - u[0] * v[2];
        out[2] = u[0] * v[1] - u[1] * v[0];
        return out[0] * out[0] + out[1] * out[1] + out[2] * out[2];
      };
      double c[3][3];
      const double n01 = cross(r0, r1, c[0]), n02 = cross(r0, r2, c[1]), n12 = cross(r1, r2, c[2]);
      const int best = n01 >= n02 ? (n01 >= n12 ? 0 : 2) : (n02 >= n12 ? 1 : 2);
      const double norm2 = std::max({n01, n02, n12});
      if (norm2 > 0 && std::isfinite(norm2)) {
        const double length = std::sqrt(norm2);
        for (int i = 0; i < 3; ++i) vector[i] = c[best][i] / length;
        return;
      }
    }
  }
  SmallestEigenvector(a, vector);
}

Status EstimateNormals(PointCloud& cloud, const NormalOptions& options, NormalReport* report) {
  if (options.k < 3 || options.k > kMaxK) {
    return Status::Invalid("normal estimation: k must be between 3 and " + std::to_string(kMaxK) +
                           ", got " + std::to_string(options.k));
  }
  PB_RETURN_IF_ERROR(Validate(cloud));
  if (cloud.size() < 3) {
    return Status::Invalid("normal estimation: needs at least 3 points, the cloud has " +
                           std::to_string(cloud.size()));
  }
  NormalReport local;
  Status status;
  if (options.threads > 0) {
    tbb::task_arena arena(options.threads);
    arena.execute([&] { status = EstimateInArena(cloud, options, local); });
  } else {
    status = EstimateInArena(cloud, options, local);
  }
  if (!status.ok()) return status;
  if (report) *report = local;
  return Status::Ok();
}

}  // namespace pb
