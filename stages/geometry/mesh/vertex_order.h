// Vertex-cache and vertex-fetch ordering for GPUs (meshoptimizer,
// Kapoulkine; Debian libmeshoptimizer-dev): the same triangles, reordered so
// that a mobile GPU's post-transform cache hits more often
// (meshopt_optimizeVertexCache, Forsyth-style) and vertices are fetched in
// the order triangles first use them (meshopt_optimizeVertexFetchRemap).
// Topology is unchanged: every triangle keeps its three vertices and its
// winding (rotations of a triangle's corners may change), every vertex keeps
// all its attributes; only the order of triangles and of vertices changes.
#pragma once

#include <cstddef>

#include "stages/geometry/core/mesh.h"

namespace pb {

struct VertexOrderReport {
  // Average cache miss ratio, transformed vertices per triangle, for a
  // 16-entry FIFO cache (0.5 is the ideal for large regular meshes, 3 the
  // worst), before and after.
  double acmr_before = 0;
  double acmr_after = 0;
  // Bytes fetched over bytes used, for the mesh's attributes as one
  // interleaved vertex and meshoptimizer's model of a GPU's vertex fetch cache
  // (64-byte lines; 1 is ideal), before and after.
  double overfetch_before = 0;
  double overfetch_after = 0;
};

// Reorders `mesh`'s triangles for the vertex cache, then its vertices for
// fetch locality; unreferenced vertices are dropped (they would never be
// fetched). The mesh must pass Validate. `report` (optional) gets the
// figures meshoptimizer's analyzers give before and after.
void OptimizeVertexOrder(Mesh& mesh, VertexOrderReport* report = nullptr);

}  // namespace pb
