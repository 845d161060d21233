#include "stages/geometry/mesh/holes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <unordered_map>
#include <unordered_set>

#include "stages/geometry/core/union_find.h"
#include "stages/geometry/core/vec3.h"
#include "stages/geometry/mesh/hole_triangulation.h"

namespace pb {
namespace {

double EdgeLength(const Mesh& mesh, uint32_t a, uint32_t b) {
  double sum = 0;
  for (int c = 0; c < 3; ++c) {
    const double d = double{mesh.positions[3 * size_t{a} + c]} - mesh.positions[3 * size_t{b} + c];
    sum += d * d;
  }
  return std::sqrt(sum);
}

using vec3::V3;

V3 PointAt(std::span<const double> points, size_t i) {
  return {points[3 * i], points[3 * i + 1], points[3 * i + 2]};
}

// The largest distance from a point of the patch's triangles to the loop's
// edges, sampled on each triangle's barycentric grid of step 1/8 (the
// corners are on the loop); stops early once above `limit`.
double PatchReach(std::span<const double> points, const std::vector<std::array<uint32_t, 3>>& patch,
                  double limit) {
  constexpr int kSteps = 8;
  const size_t n = points.size() / 3;
  double reach = 0;
  for (const auto& t : patch) {
    const V3 a = PointAt(points, t[0]), b = PointAt(points, t[1]), c = PointAt(points, t[2]);
    for (int i = 0; i <= kSteps; ++i) {
      for (int j = 0; i + j <= kSteps; ++j) {
        const int k = kSteps - i - j;
        if (i == kSteps || j == kSteps || k == kSteps) continue;
        const V3 q = vec3::Scale(
            vec3::Add(vec3::Add(vec3::Scale(a, i), vec3::Scale(b, j)), vec3::Scale(c, k)),
            1.0 / kSteps);
        double nearest = std::numeric_limits<double>::infinity();
        for (size_t e = 0; e < n && nearest > reach; ++e) {
          const V3 p0 = PointAt(points, e), edge = vec3::Sub(PointAt(points, (e + 1) % n), p0);
          const double length2 = vec3::Dot(edge, edge);
          const double s =
              length2 > 0 ? std::clamp(vec3::Dot(vec3::Sub(q, p0), edge) / length2, 0.0, 1.0) : 0.0;
          const V3 closest = vec3::Add(p0, vec3::Scale(edge, s));
          nearest = std::min(nearest, vec3::Norm(vec3::Sub(q, closest)));
        }
        reach = std::max(reach, nearest);
        if (reach > limit) return reach;
      }
    }
  }
  return reach;
}

double TriangleArea(const V3& a, const V3& b, const V3& c) {
  return 0.5 * vec3::Norm(vec3::Cross(vec3::Sub(b, a), vec3::Sub(c, a)));
}

// Per vertex, the area of the faces connected to it (through shared
// vertices); 0 for a vertex of no face.
std::vector<double> ComponentAreaOfVertices(const Mesh& mesh) {
  UnionFind components(mesh.vertex_count());
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    components.Union(t[0], t[1]);
    components.Union(t[0], t[2]);
  }
  std::vector<double> area(mesh.vertex_count(), 0);
  const auto position = [&](uint32_t v) {
    return V3{mesh.positions[3 * size_t{v}], mesh.positions[3 * size_t{v} + 1],
              mesh.positions[3 * size_t{v} + 2]};
  };
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    area[components.Find(t[0])] += TriangleArea(position(t[0]), position(t[1]), position(t[2]));
  }
  for (uint32_t v = 0; v < area.size(); ++v) area[v] = area[components.Find(v)];
  return area;
}

}  // namespace

std::vector<uint8_t> BorderSides(const Mesh& mesh) {
  const size_t sides = mesh.indices.size();
  std::vector<std::pair<uint64_t, uint32_t>> keyed;  // (edge key, side)
  keyed.reserve(sides);
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    for (int k = 0; k < 3; ++k) {
      keyed.emplace_back(EdgeKey(t[k], t[(k + 1) % 3]), static_cast<uint32_t>(3 * f + k));
    }
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<uint8_t> border(sides, 0);
  for (size_t i = 0; i < keyed.size();) {
    size_t j = i;
    while (j < keyed.size() && keyed[j].first == keyed[i].first) ++j;
    if (j - i == 1) border[keyed[i].second] = 1;
    i = j;
  }
  return border;
}

std::vector<std::vector<uint32_t>> BoundaryLoops(const Mesh& mesh) {
  // A border side u -> v: the hole runs v -> u.
  const std::vector<uint8_t> border = BorderSides(mesh);
  constexpr uint32_t kNone = UINT32_MAX, kAmbiguous = UINT32_MAX - 1;
  std::vector<uint32_t> hole_next(mesh.vertex_count(), kNone);  // v -> next vertex along the hole
  std::vector<uint8_t> starts(mesh.vertex_count(), 0);
  for (size_t side = 0; side < border.size(); ++side) {
    if (!border[side]) continue;
    const size_t f = side / 3, k = side % 3;
    const uint32_t from = mesh.indices[3 * f + k], to = mesh.indices[3 * f + (k + 1) % 3];
    // Hole edge to -> from.
    hole_next[to] = hole_next[to] == kNone ? from : kAmbiguous;
    starts[from] = starts[from] < 2 ? starts[from] + 1 : 2;
  }
  std::vector<std::vector<uint32_t>> loops;
  std::vector<uint8_t> visited(mesh.vertex_count(), 0);
  for (uint32_t v0 = 0; v0 < mesh.vertex_count(); ++v0) {
    if (visited[v0] || hole_next[v0] == kNone) continue;
    std::vector<uint32_t> loop;
    bool ok = true;
    uint32_t v = v0;
    while (true) {
      if (visited[v]) {
        ok = ok && v == v0;
        break;
      }
      visited[v] = 1;
      loop.push_back(v);
      if (hole_next[v] >= kAmbiguous || starts[v] != 1) ok = false;
      if (hole_next[v] >= kAmbiguous) break;
      v = hole_next[v];
    }
    if (ok && loop.size() >= 3) loops.push_back(std::move(loop));
  }
  return loops;
}

Status FillSmallHoles(Mesh& mesh, const HoleFillOptions& options, HoleFillReport* report) {
  PB_RETURN_IF_ERROR(Validate(mesh));
  if (options.max_edges < 0 || !(options.max_perimeter_m >= 0) || !(options.max_reach_m >= 0) ||
      !(options.max_component_fraction >= 0)) {
    return Status::Invalid(
        "hole filling: need max_edges, max_perimeter_m, max_reach_m and max_component_fraction "
        ">= 0");
  }
  HoleFillReport local;
  HoleFillReport& r = report ? *report : local;
  r = HoleFillReport();
  const std::vector<std::vector<uint32_t>> loops = BoundaryLoops(mesh);
  r.loops = loops.size();
  if (options.max_edges == 0 && options.max_perimeter_m == 0) return Status::Ok();

  // Only the loops small enough are filled; only edges between their
  // vertices can clash with a patch, and only their sides need the face
  // opposite, so the maps below hold those alone.
  const auto perimeter_of = [&](const std::vector<uint32_t>& loop) {
    double perimeter = 0;
    for (size_t i = 0; i < loop.size(); ++i) {
      perimeter += EdgeLength(mesh, loop[i], loop[(i + 1) % loop.size()]);
    }
    return perimeter;
  };
  const auto is_small = [&](const std::vector<uint32_t>& loop) {
    return (options.max_edges > 0 && loop.size() <= static_cast<size_t>(options.max_edges)) ||
           (options.max_perimeter_m > 0 && perimeter_of(loop) <= options.max_perimeter_m);
  };
  std::vector<uint8_t> on_small_loop(mesh.vertex_count(), 0);
  std::vector<const std::vector<uint32_t>*> small_loops;
  for (const std::vector<uint32_t>& loop : loops) {
    if (!is_small(loop)) continue;
    small_loops.push_back(&loop);
    for (const uint32_t v : loop) on_small_loop[v] = 1;
  }
  std::unordered_set<uint64_t> edges;
  std::unordered_map<uint64_t, uint32_t> opposite;  // directed side -> opposite corner
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3];
      if (!on_small_loop[a] || !on_small_loop[b]) continue;
      edges.insert(EdgeKey(a, b));
      opposite.emplace((static_cast<uint64_t>(a) << 32) | b, t[(k + 2) % 3]);
    }
  }
  const std::vector<double> component_area =  // before any patch
      options.max_component_fraction > 0 && !small_loops.empty() ? ComponentAreaOfVertices(mesh)
                                                                 : std::vector<double>();
  for (const std::vector<uint32_t>* small_loop : small_loops) {
    const std::vector<uint32_t>& loop = *small_loop;
    const size_t n = loop.size();
    std::vector<double> points(3 * n), third(3 * n);
    for (size_t i = 0; i < n; ++i) {
      for (int c = 0; c < 3; ++c) points[3 * i + c] = mesh.positions[3 * size_t{loop[i]} + c];
      // The face on hole edge loop[i] -> loop[i+1] runs it loop[i+1] -> loop[i].
      const auto face = opposite.find((static_cast<uint64_t>(loop[(i + 1) % n]) << 32) | loop[i]);
      const uint32_t o = face != opposite.end() ? face->second : loop[i];
      for (int c = 0; c < 3; ++c) third[3 * i + c] = mesh.positions[3 * size_t{o} + c];
    }
    std::vector<std::array<uint32_t, 3>> patch = TriangulateHoleLoop(points, third);
    bool valid = patch.size() == n - 2;
    std::unordered_set<uint64_t> inner;
    for (const auto& t : patch) {
      for (int k = 0; k < 3 && valid; ++k) {
        const uint32_t a = t[k], b = t[(k + 1) % 3];
        if ((b == a + 1) || (a == n - 1 && b == 0)) continue;  // a loop edge, run forward
        if ((a == b + 1) || (b == n - 1 && a == 0)) valid = false;  // a loop edge run backward
        const uint64_t key = EdgeKey(loop[a], loop[b]);
        if (edges.count(key)) valid = false;  // would make a non-manifold edge
        inner.insert(key);
      }
    }
    if (!valid) {
      ++r.holes_rejected;
      continue;
    }
    if (options.max_reach_m > 0 &&
        PatchReach(points, patch, options.max_reach_m) > options.max_reach_m) {
      ++r.holes_too_wide;
      continue;
    }
    if (options.max_component_fraction > 0) {
      double patch_area = 0;
      for (const auto& t : patch) {
        patch_area +=
            TriangleArea(PointAt(points, t[0]), PointAt(points, t[1]), PointAt(points, t[2]));
      }
      if (patch_area > options.max_component_fraction * component_area[loop[0]]) {
        ++r.outlines_kept;
        continue;
      }
    }
    if (options.keep_open) {
      std::vector<std::array<double, 9>> triangles;
      triangles.reserve(patch.size());
      for (const auto& t : patch) {
        std::array<double, 9> corners;
        for (int k = 0; k < 3; ++k) {
          for (int c = 0; c < 3; ++c) corners[3 * k + c] = points[3 * size_t{t[k]} + c];
        }
        triangles.push_back(corners);
      }
      if (options.keep_open(triangles)) {
        ++r.holes_kept_open;
        continue;
      }
    }
    // The hole runs against the faces around it and the patch runs the
    // hole forward, so the patch is wound like the faces around it.
    for (const auto& t : patch) {
      mesh.indices.insert(mesh.indices.end(), {loop[t[0]], loop[t[1]], loop[t[2]]});
    }
    edges.insert(inner.begin(), inner.end());
    for (size_t i = 0; i < n; ++i) edges.insert(EdgeKey(loop[i], loop[(i + 1) % n]));
    ++r.holes_filled;
    r.faces_added += patch.size();
  }
  return Status::Ok();
}

}  // namespace pb
