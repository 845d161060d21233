// bake.from_mesh: color and normal maps of a low mesh from a high mesh by ray
// casting (Blender's "selected to active" bake; the paper's Remeshing
// workflow). Embree 3 for the rays (includes stay in the .cc).
#pragma once

#include <cstddef>

#include "base/status.h"
#include "stages/geometry/bake/bake.h"
#include "stages/geometry/core/mesh.h"

namespace pb {

struct FromMeshOptions {
  // Rays leave the low surface along its interpolated normal, forwards and
  // backwards, up to this distance (meters); the nearer hit wins.
  double cage_m = 0.05;
};

struct FromMeshReport {
  size_t texels_hit = 0;       // baked from the high mesh
  size_t texels_fallback = 0;  // no hit within the cage: low mesh's own colors
  double mean_hit_distance_m = 0;  // over the hits, |t| along the normal
  size_t rays_cast = 0;            // forward + backward, 2 per baked texel
  // Wall time and process CPU time (all threads), seconds, of building
  // Embree's BVH of `high` and of casting the rays: for measuring (the CPU
  // time stays meaningful on a loaded machine), never part of the output.
  double build_seconds = 0;
  double ray_seconds = 0;
  double build_cpu_seconds = 0;
  double ray_cpu_seconds = 0;
};

// For every texel of `low` (which needs uvs): the hit's interpolated vertex
// color and normal on `high` (which needs vertex colors; normals are computed
// when missing), the normal in the low texel's tangent frame; texels with no
// hit take the low mesh's interpolated vertex colors and a flat normal (and
// black if low has no colors). The meshes may have different origins.
// Status::Invalid when `low` has no uvs, `high` has no colors or no faces,
// either fails Validate, or cage_m is not > 0; Status::Internal with
// Embree's message when Embree fails. Threads: options.threads (0 = all) for
// the BVH build (Embree's "threads=N") and the rays; the output does not
// depend on the count.
Expected<BakeResult> BakeFromMesh(Mesh low, const Mesh& high, const BakeOptions& options,
                                  const FromMeshOptions& from_mesh, FromMeshReport* report = nullptr);

}  // namespace pb
