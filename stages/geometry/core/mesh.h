// Mesh: the `mesh` artifact in memory, a triangle mesh with optional
// per-vertex attributes (structure of arrays, like PointCloud):
//   positions: 3 floats per vertex, meters, relative to `origin`
//   normals:   empty or 3 floats per vertex (unit length)
//   colors:    empty or 3 bytes per vertex (r, g, b; sRGB 0..255)
//   uvs:       empty or 2 floats per vertex (u right, v up; [0,1] on the atlas)
//   tangents:  empty or 4 floats per vertex (xyz unit tangent along +u, w = ±1
//              handedness: bitangent = w * cross(normal, tangent), glTF style)
//   indices:   3 vertex indices per triangle, counter-clockwise = front
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

struct Mesh {
  std::array<double, 3> origin{};  // meters
  std::vector<float> positions;    // xyz per vertex, meters, relative to origin
  std::vector<float> normals;      // empty or 3 per vertex
  std::vector<uint8_t> colors;     // empty or 3 per vertex
  std::vector<float> uvs;          // empty or 2 per vertex
  std::vector<float> tangents;     // empty or 4 per vertex
  std::vector<uint32_t> indices;   // 3 per triangle

  size_t vertex_count() const { return positions.size() / 3; }
  size_t face_count() const { return indices.size() / 3; }
  bool has_normals() const { return !normals.empty(); }
  bool has_colors() const { return !colors.empty(); }
  bool has_uvs() const { return !uvs.empty(); }
  bool has_tangents() const { return !tangents.empty(); }
};

// The key of the undirected edge {a, b}: the smaller index in the high half.
inline uint64_t EdgeKey(uint32_t a, uint32_t b) {
  return (static_cast<uint64_t>(a < b ? a : b) << 32) | (a < b ? b : a);
}

Bounds LocalBounds(const Mesh& mesh);
Bounds AbsoluteBounds(const Mesh& mesh);

// Checks attribute sizes against the vertex count and that every index names
// a vertex; Status::Invalid naming the first problem otherwise.
Status Validate(const Mesh& mesh);

// Drops the vertices no face uses (the others keep their order and every
// attribute) and renumbers the indices. Returns how many were dropped.
size_t DropUnreferencedVertices(Mesh& mesh);

// Vertex v's position in double precision (meters, relative to origin).
inline std::array<double, 3> VertexPosition(const Mesh& mesh, size_t v) {
  return {mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
}

// For every vertex, the smallest index among the vertices at exactly its
// position: the copies uv.unwrap makes along its seams weld back into one.
std::vector<uint32_t> WeldedVertices(const Mesh& mesh);

// Half-edge 3 f + k runs from corner k of face f to corner (k + 1) % 3.
// EdgePartners gives, for each, over the welded vertices (WeldedVertices):
// the half-edge of the one other face with the same two end points, in
// either direction; kBorderEdge if no other half-edge has them; kNoPartner
// if more than two do, if the other is in the same face, or if the two end
// points weld into one.
inline constexpr uint32_t kBorderEdge = 0xffffffffu;
inline constexpr uint32_t kNoPartner = 0xfffffffeu;
std::vector<uint32_t> EdgePartners(const Mesh& mesh, std::span<const uint32_t> welded);

}  // namespace pb
