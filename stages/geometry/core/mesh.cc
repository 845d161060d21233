#include "stages/geometry/core/mesh.h"

#include <cstdint>
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

}  // namespace pb
