#include "stages/geometry/mesh.h"

#include <string>

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

}  // namespace

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

PointCloud VerticesAsPoints(const Mesh& mesh) {
  PointCloud cloud;
  cloud.origin = mesh.origin;
  cloud.positions = mesh.positions;
  cloud.normals = mesh.normals;
  cloud.colors = mesh.colors;
  return cloud;
}

}  // namespace pb
