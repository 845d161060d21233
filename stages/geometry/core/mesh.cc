#include "stages/geometry/core/mesh.h"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <utility>
#include <string>
#include <vector>

namespace pb {

Bounds LocalBounds(const Mesh& mesh) { return BoundsOf(mesh.positions); }

Bounds AbsoluteBounds(const Mesh& mesh) {
  Bounds bounds = LocalBounds(mesh);
  if (bounds.empty()) return bounds;
  for (int axis = 0; axis < 3; ++axis) {
    bounds.min_m[axis] += mesh.origin[axis];
    bounds.max_m[axis] += mesh.origin[axis];
  }
  return bounds;
}

namespace {

Status CheckAttribute(const char* name, size_t values, size_t per_vertex, size_t vertices) {
  if (values == 0 || values == per_vertex * vertices) return Status::Ok();
  return Status::Invalid("mesh: " + std::to_string(values) + " " + name + " values for " +
                         std::to_string(vertices) + " vertices (expected " +
                         std::to_string(per_vertex) + " per vertex)");
}

// Keeps the entries of the vertices with a new index, in order.
template <typename T>
void Compact(const std::vector<uint32_t>& new_index, size_t width, std::vector<T>& values) {
  if (values.empty()) return;
  size_t out = 0;
  for (size_t v = 0; v < new_index.size(); ++v) {
    if (new_index[v] == UINT32_MAX) continue;
    for (size_t a = 0; a < width; ++a) values[width * out + a] = values[width * v + a];
    ++out;
  }
  values.resize(width * out);
}

}  // namespace

size_t DropUnreferencedVertices(Mesh& mesh) {
  std::vector<uint32_t> new_index(mesh.vertex_count(), UINT32_MAX);
  for (const uint32_t v : mesh.indices) new_index[v] = 0;
  uint32_t next = 0;
  size_t dropped = 0;
  for (uint32_t& n : new_index) {
    if (n == UINT32_MAX) {
      ++dropped;
    } else {
      n = next++;
    }
  }
  if (dropped == 0) return 0;
  for (uint32_t& v : mesh.indices) v = new_index[v];
  Compact(new_index, 3, mesh.positions);
  Compact(new_index, 3, mesh.normals);
  Compact(new_index, 3, mesh.colors);
  Compact(new_index, 2, mesh.uvs);
  Compact(new_index, 4, mesh.tangents);
  return dropped;
}

Status Validate(const Mesh& mesh) {
  if (mesh.positions.size() % 3 != 0) {
    return Status::Invalid("mesh: positions hold " + std::to_string(mesh.positions.size()) +
                           " floats, not a multiple of 3");
  }
  const size_t n = mesh.vertex_count();
  PB_RETURN_IF_ERROR(CheckAttribute("normal", mesh.normals.size(), 3, n));
  PB_RETURN_IF_ERROR(CheckAttribute("color", mesh.colors.size(), 3, n));
  PB_RETURN_IF_ERROR(CheckAttribute("uv", mesh.uvs.size(), 2, n));
  PB_RETURN_IF_ERROR(CheckAttribute("tangent", mesh.tangents.size(), 4, n));
  if (mesh.indices.size() % 3 != 0) {
    return Status::Invalid("mesh: " + std::to_string(mesh.indices.size()) +
                           " indices, not a multiple of 3");
  }
  for (size_t i = 0; i < mesh.indices.size(); ++i) {
    if (mesh.indices[i] >= n) {
      return Status::Invalid("mesh: face " + std::to_string(i / 3) + " refers to vertex " +
                             std::to_string(mesh.indices[i]) + " but the mesh has " +
                             std::to_string(n) + " vertices");
    }
  }
  return Status::Ok();
}

std::vector<uint32_t> WeldedVertices(const Mesh& mesh) {
  const size_t nv = mesh.vertex_count();
  std::vector<uint32_t> order(nv);
  std::iota(order.begin(), order.end(), 0u);
  const auto position = [&](uint32_t v) {
    return std::array<float, 3>{mesh.positions[3 * size_t{v}], mesh.positions[3 * size_t{v} + 1],
                                mesh.positions[3 * size_t{v} + 2]};
  };
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    const auto pa = position(a), pb = position(b);
    return pa != pb ? pa < pb : a < b;
  });
  std::vector<uint32_t> welded(nv);
  for (size_t i = 0; i < nv; ++i) {
    welded[order[i]] = i > 0 && position(order[i]) == position(order[i - 1]) ? welded[order[i - 1]] : order[i];
  }
  return welded;
}

std::vector<uint32_t> EdgePartners(const Mesh& mesh, std::span<const uint32_t> welded) {
  std::vector<uint32_t> partner(mesh.indices.size(), kNoPartner);
  std::vector<std::pair<uint64_t, uint32_t>> edges;  // (edge key, half-edge)
  edges.reserve(mesh.indices.size());
  for (size_t e = 0; e < mesh.indices.size(); ++e) {
    const uint32_t a = welded[mesh.indices[e]];
    const uint32_t b = welded[mesh.indices[e - e % 3 + (e + 1) % 3]];
    if (a != b) edges.push_back({EdgeKey(a, b), static_cast<uint32_t>(e)});
  }
  std::sort(edges.begin(), edges.end());
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    if (j - i == 1) {
      partner[edges[i].second] = kBorderEdge;
    } else if (j - i == 2 && edges[i].second / 3 != edges[i + 1].second / 3) {
      partner[edges[i].second] = edges[i + 1].second;
      partner[edges[i + 1].second] = edges[i].second;
    }
    i = j;
  }
  return partner;
}

}  // namespace pb
