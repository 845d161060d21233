// Mesh cleaning (see mesh_clean.h). The non-manifold vertex split follows the
// usual corner-fan construction (Guéziec, Taubin, Lazarus, Horn, "Cutting and
// stitching: converting sets of polygons to manifold surfaces", IEEE TVCG
// 7(2), 2001): corners of a vertex are joined across each manifold edge, and
// each resulting class of corners becomes one vertex.
#include "stages/geometry/mesh/clean.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include "stages/geometry/core/union_find.h"
#include "stages/geometry/mesh/holes.h"

namespace pb {
namespace {

// One face side: the undirected edge key (low index << 32 | high index) and the
// corner (3 * face + k) where the edge starts.
struct EdgeUse {
  uint64_t key;
  uint32_t corner;
  bool operator<(const EdgeUse& o) const { return key != o.key ? key < o.key : corner < o.corner; }
};

// The edge uses of all faces in `indices`, sorted by edge.
std::vector<EdgeUse> SortedEdges(const std::vector<uint32_t>& indices) {
  std::vector<EdgeUse> edges;
  edges.reserve(indices.size());
  for (size_t c = 0; c < indices.size(); ++c) {
    const size_t next = c - c % 3 + (c % 3 + 1) % 3;
    edges.push_back({EdgeKey(indices[c], indices[next]), static_cast<uint32_t>(c)});
  }
  std::sort(edges.begin(), edges.end());
  return edges;
}

uint32_t NextCorner(uint32_t c) { return c - c % 3 + (c % 3 + 1) % 3; }

// Joins corners of the same vertex across every edge used by exactly two faces.
// Returns the union-find over corners.
UnionFind CornerFans(const std::vector<uint32_t>& indices, const std::vector<EdgeUse>& edges) {
  UnionFind fans(indices.size());
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].key == edges[i].key) ++j;
    if (j - i == 2) {
      const uint32_t c1 = edges[i].corner, c2 = edges[i + 1].corner;
      const uint32_t n1 = NextCorner(c1), n2 = NextCorner(c2);
      // Match corners by vertex: the second face may run the edge either way.
      if (indices[c1] == indices[c2]) {
        fans.Union(c1, c2);
        fans.Union(n1, n2);
      } else {
        fans.Union(c1, n2);
        fans.Union(n1, c2);
      }
    }
    i = j;
  }
  return fans;
}

double FaceArea(const Mesh& mesh, const uint32_t* f) {
  std::array<std::array<double, 3>, 3> p;
  for (int k = 0; k < 3; ++k) {
    for (int a = 0; a < 3; ++a) p[k][a] = mesh.positions[3 * size_t{f[k]} + a];
  }
  const std::array<double, 3> u = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
  const std::array<double, 3> v = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
  const double x = u[1] * v[2] - u[2] * v[1];
  const double y = u[2] * v[0] - u[0] * v[2];
  const double z = u[0] * v[1] - u[1] * v[0];
  return 0.5 * std::sqrt(x * x + y * y + z * z);
}

// Keeps the faces with keep[f] set, in order.
void KeepFaces(const std::vector<bool>& keep, std::vector<uint32_t>* indices) {
  size_t out = 0;
  for (size_t f = 0; f < keep.size(); ++f) {
    if (!keep[f]) continue;
    for (int k = 0; k < 3; ++k) (*indices)[3 * out + k] = (*indices)[3 * f + k];
    ++out;
  }
  indices->resize(3 * out);
}

template <typename T>
void AppendCopy(std::vector<T>* values, size_t width, uint32_t from) {
  if (values->empty()) return;
  for (size_t a = 0; a < width; ++a) values->push_back((*values)[width * from + a]);
}

}  // namespace

Expected<Mesh> CleanMesh(const Mesh& input, const CleanOptions& options, CleanReport* report) {
  PB_RETURN_IF_ERROR(Validate(input));
  if (!(options.min_area_m2 >= 0) || options.min_component_faces < 0 ||
      !(options.min_component_fraction >= 0 && options.min_component_fraction <= 1) ||
      !(options.min_component_area_m2 >= 0) || options.hole_max_edges < 0 ||
      !(options.hole_max_perimeter_m >= 0)) {
    return Status::Invalid(
        "mesh clean: need min_area_m2 >= 0, min_component_faces >= 0 and "
        "min_component_fraction in [0, 1], min_component_area_m2 >= 0, hole_max_edges >= 0 "
        "and hole_max_perimeter_m >= 0");
  }
  CleanReport local;
  CleanReport& r = report != nullptr ? *report : local;
  r = CleanReport{};
  r.faces_in = input.face_count();
  r.vertices_in = input.vertex_count();
  Mesh mesh = input;
  std::vector<uint32_t>& idx = mesh.indices;

  // 1. Degenerate faces.
  {
    std::vector<bool> keep(mesh.face_count());
    for (size_t f = 0; f < keep.size(); ++f) {
      const uint32_t* t = &idx[3 * f];
      keep[f] = t[0] != t[1] && t[1] != t[2] && t[0] != t[2] &&
                !(FaceArea(mesh, t) < options.min_area_m2);
      if (!keep[f]) ++r.degenerate_faces;
    }
    KeepFaces(keep, &idx);
  }

  // 2. Duplicate faces: sort faces by their sorted vertex triple.
  {
    const size_t n = mesh.face_count();
    std::vector<std::array<uint32_t, 4>> keys(n);  // sorted triple + face index
    for (size_t f = 0; f < n; ++f) {
      std::array<uint32_t, 3> t = {idx[3 * f], idx[3 * f + 1], idx[3 * f + 2]};
      std::sort(t.begin(), t.end());
      keys[f] = {t[0], t[1], t[2], static_cast<uint32_t>(f)};
    }
    std::sort(keys.begin(), keys.end());
    std::vector<bool> keep(n, true);
    for (size_t i = 1; i < n; ++i) {
      if (keys[i][0] == keys[i - 1][0] && keys[i][1] == keys[i - 1][1] &&
          keys[i][2] == keys[i - 1][2]) {
        keep[keys[i][3]] = false;  // a later face of the same set
        ++r.duplicate_faces;
      }
    }
    KeepFaces(keep, &idx);
  }

  // 3. Non-manifold edges: greedy acceptance by decreasing area.
  {
    const size_t n = mesh.face_count();
    std::vector<EdgeUse> edges = SortedEdges(idx);
    bool any = false;
    for (size_t i = 2; i < edges.size() && !any; ++i) any = edges[i].key == edges[i - 2].key;
    if (any) {
      std::vector<double> area(n);
      for (size_t f = 0; f < n; ++f) area[f] = FaceArea(mesh, &idx[3 * f]);
      std::vector<uint32_t> order(n);
      std::iota(order.begin(), order.end(), 0);
      std::stable_sort(order.begin(), order.end(),
                       [&](uint32_t a, uint32_t b) { return area[a] > area[b]; });
      // Accepted-face count per edge, indexed by the edge's first use in `edges`.
      std::vector<uint32_t> edge_of_corner(idx.size());
      std::vector<uint8_t> accepted(edges.size(), 0);
      for (size_t i = 0; i < edges.size();) {
        size_t j = i;
        while (j < edges.size() && edges[j].key == edges[i].key)
          edge_of_corner[edges[j++].corner] = i;
        i = j;
      }
      std::vector<bool> keep(n, false);
      for (uint32_t f : order) {
        bool ok = true;
        for (int k = 0; k < 3; ++k) ok = ok && accepted[edge_of_corner[3 * f + k]] < 2;
        if (!ok) {
          ++r.nonmanifold_edge_faces;
          continue;
        }
        keep[f] = true;
        for (int k = 0; k < 3; ++k) ++accepted[edge_of_corner[3 * f + k]];
      }
      KeepFaces(keep, &idx);
    }
  }

  // 3b. Edges whose two faces run them the same way (where step 3 kept one
  // face of each of two crossing sheets, or the input was folded): the
  // smaller face goes, so every kept edge is consistently oriented.
  // mesh.decimate takes such an edge for two border edges and opens holes
  // there; the hole left here is small and filled in step 6.
  {
    const size_t n = mesh.face_count();
    const std::vector<EdgeUse> edges = SortedEdges(idx);
    std::vector<bool> keep(n, true);
    bool any = false;
    for (size_t i = 1; i < edges.size(); ++i) {
      if (edges[i].key != edges[i - 1].key) continue;
      if (idx[edges[i].corner] != idx[edges[i - 1].corner]) continue;  // opposite: fine
      const uint32_t a = edges[i - 1].corner / 3, b = edges[i].corner / 3;
      if (!keep[a] || !keep[b]) continue;
      const double area_a = FaceArea(mesh, &idx[3 * size_t{a}]);
      const double area_b = FaceArea(mesh, &idx[3 * size_t{b}]);
      keep[area_b < area_a || (area_b == area_a && b > a) ? b : a] = false;
      ++r.misoriented_faces;
      any = true;
    }
    if (any) KeepFaces(keep, &idx);
  }

  // 4. Small components (faces joined through shared edges).
  {
    const size_t n = mesh.face_count();
    std::vector<EdgeUse> edges = SortedEdges(idx);
    UnionFind components(n);
    for (size_t i = 1; i < edges.size(); ++i) {
      if (edges[i].key == edges[i - 1].key) {
        components.Union(edges[i].corner / 3, edges[i - 1].corner / 3);
      }
    }
    std::vector<uint32_t> size(n, 0);
    std::vector<double> area(n, 0.0);
    for (size_t f = 0; f < n; ++f) {
      const uint32_t root = components.Find(f);
      ++size[root];
      area[root] += FaceArea(mesh, &idx[3 * f]);
    }
    const uint32_t largest = n == 0 ? 0 : *std::max_element(size.begin(), size.end());
    const double min_faces = std::max(static_cast<double>(options.min_component_faces),
                                      options.min_component_fraction * largest);
    std::vector<bool> keep(n);
    for (size_t f = 0; f < n; ++f) {
      const uint32_t root = components.Find(f);
      keep[f] = !(size[root] < min_faces && area[root] < options.min_component_area_m2);
      if (!keep[f]) {
        ++r.small_component_faces;
        if (root == f) ++r.small_components;
      }
    }
    KeepFaces(keep, &idx);
  }

  // 5. Non-manifold vertices: one vertex per fan of corners.
  {
    const std::vector<EdgeUse> edges = SortedEdges(idx);
    UnionFind fans = CornerFans(idx, edges);
    // The first fan (in corner order) of each vertex keeps the vertex.
    std::vector<uint32_t> owner(mesh.vertex_count(), UINT32_MAX);  // fan root owning v
    std::vector<uint32_t> root_vertex(idx.size(), UINT32_MAX);     // fan root -> vertex
    for (size_t c = 0; c < idx.size(); ++c) {
      const uint32_t v = idx[c];
      const uint32_t root = fans.Find(c);
      if (root_vertex[root] == UINT32_MAX) {
        if (owner[v] == UINT32_MAX) {
          owner[v] = root;
          root_vertex[root] = v;
        } else {
          const uint32_t copy = static_cast<uint32_t>(mesh.vertex_count());
          AppendCopy(&mesh.positions, 3, v);
          AppendCopy(&mesh.normals, 3, v);
          AppendCopy(&mesh.colors, 3, v);
          AppendCopy(&mesh.uvs, 2, v);
          AppendCopy(&mesh.tangents, 4, v);
          root_vertex[root] = copy;
          ++r.split_vertices;
        }
      }
      idx[c] = root_vertex[root];
    }
  }

  // 6. Small holes.
  {
    HoleFillReport holes;
    PB_RETURN_IF_ERROR(FillSmallHoles(
        mesh, {.max_edges = options.hole_max_edges, .max_perimeter_m = options.hole_max_perimeter_m},
        &holes));
    r.boundary_loops = holes.loops;
    r.holes_filled = holes.holes_filled;
    r.hole_faces = holes.faces_added;
  }

  // 7. Unreferenced vertices.
  r.unreferenced_vertices = DropUnreferencedVertices(mesh);
  r.faces_out = mesh.face_count();
  r.vertices_out = mesh.vertex_count();
  return mesh;
}

Status CheckManifold(const Mesh& mesh) {
  const std::vector<EdgeUse> edges = SortedEdges(mesh.indices);
  for (size_t i = 2; i < edges.size(); ++i) {
    if (edges[i].key == edges[i - 2].key) {
      return Status::Invalid("non-manifold edge " + std::to_string(edges[i].key >> 32) + "-" +
                             std::to_string(edges[i].key & 0xffffffffu) +
                             ": in more than two faces");
    }
  }
  UnionFind fans = CornerFans(mesh.indices, edges);
  std::vector<uint32_t> vertex_fan(mesh.vertex_count(), UINT32_MAX);
  for (size_t c = 0; c < mesh.indices.size(); ++c) {
    const uint32_t v = mesh.indices[c];
    const uint32_t root = fans.Find(c);
    if (vertex_fan[v] == UINT32_MAX) {
      vertex_fan[v] = root;
    } else if (vertex_fan[v] != root) {
      return Status::Invalid("non-manifold vertex " + std::to_string(v) +
                             ": its faces form more than one fan");
    }
  }
  return Status::Ok();
}

}  // namespace pb
