// Per-vertex normals and tangent frames of a triangle mesh, in the
// conventions of Mesh (mesh.h) and glTF 2.0:
//   tangent  t = unit 3-D direction of increasing u (xyz of Mesh::tangents)
//   w        = ±1 handedness; bitangent b = w * cross(n, t) points along
//              increasing v (our v points up in the image, as in Blender), so
//              a normal map whose green channel means "image up" renders the
//              same in a glTF viewer with the tangents unchanged: flipping v
//              for glTF's top-left texture origin moves texels, not frames.
//
// Method (Lengyel 2001, "Computing Tangent Space Basis Vectors for an
// Arbitrary Mesh"; corner-angle weights as in Mikkelsen's MikkTSpace):
// per triangle the tangent T = dP/du and bitangent B = dP/dv solve
// [dp1 dp2] = [T B] [du1 du2; dv1 dv2]; both are normalized and added to each
// corner's vertex weighted by the triangle's angle at that corner; then per
// vertex t = normalize(T - n (n·T)) (Gram–Schmidt) and
// w = sign(dot(cross(n, t), B)) (+1 on a tie). Departs from MikkTSpace in not
// splitting vertices: a vertex is one frame (vertices at UV seams are already
// separate in a unwrapped mesh), so results agree with MikkTSpace on meshes
// whose triangles meet at a vertex with consistent UV orientation.
//
// Degenerate cases (counted in TangentReport):
//   - a triangle whose UV area is below 1e-12 of its squared UV extent (or
//     zero), or whose 3-D area is zero, contributes nothing;
//   - a vertex with no contribution, or whose T is parallel to n, gets a
//     deterministic frame: t = the unit vector of the coordinate axis least
//     aligned with n, projected into the tangent plane, and w = +1.
#pragma once

#include <cstddef>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/mesh.h"

namespace pb {

// Area-weighted vertex normals: each vertex gets the normalized sum of the
// (unnormalized, i.e. area-weighted) face normals cross(b - a, c - a) of the
// triangles around it. 3 floats per vertex; a vertex on no triangle of
// nonzero area gets (0, 0, 1). Precondition: Validate(mesh) is ok.
std::vector<float> ComputeVertexNormals(const Mesh& mesh);

struct TangentReport {
  size_t degenerate_uv_faces = 0;  // triangles skipped (zero UV or 3-D area)
  size_t fallback_vertices = 0;    // vertices given the arbitrary frame
  size_t mirrored_vertices = 0;    // vertices with w = -1
};

// Tangent frames, 4 floats per vertex (xyz unit, orthogonal to the normal
// within float precision; w = ±1). Uses mesh.normals, or
// ComputeVertexNormals when the mesh has none (zero-length normals are
// treated the same way per vertex). Status::Invalid if the mesh has no uvs
// or fails Validate.
Expected<std::vector<float>> ComputeTangents(const Mesh& mesh, TangentReport* report = nullptr);

}  // namespace pb
