// Boundary loops of a mesh and filling the small ones.
//
// Small holes are where decimation goes wrong: mesh.decimate holds every
// open border in place (boundary_weight), so a pin-hole of a dense mesh
// (a face mesh.clean dropped at a non-manifold edge, a gap of a few missing
// scan points) keeps its boundary vertices while the surface around it is
// simplified, and ends as a hole the size of a low-poly triangle. Filling
// them before decimation leaves the boundary constraint to real borders.
//
// A loop is filled with TriangulateHoleLoop (hole_triangulation.h; CGAL,
// Liepa 2003), without new vertices, wound like the faces around it. A
// patch is rejected (the hole stays) when one of its inner edges already
// exists in the mesh, which would make that edge non-manifold.
#pragma once

#include <cstdint>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/mesh.h"

namespace pb {

// Closed loops of boundary edges (edges of one face), each as vertex indices
// in the hole's direction (against the winding of the faces around it),
// starting at its smallest index; loops sorted by that index. Needs a
// manifold mesh with consistent winding (CheckManifold in clean.h); a loop
// through a vertex where this fails (two boundary edges start or end there)
// is left out.
std::vector<std::vector<uint32_t>> BoundaryLoops(const Mesh& mesh);

struct HoleFillOptions {
  // A loop is filled when it has at most max_edges edges or its perimeter
  // is at most max_perimeter_m (either test; 0 disables it).
  int64_t max_edges = 0;
  double max_perimeter_m = 0;
};

struct HoleFillReport {
  uint64_t loops = 0;           // boundary loops found
  uint64_t holes_filled = 0;
  uint64_t faces_added = 0;
  uint64_t holes_rejected = 0;  // small enough, but no valid patch
};

// Appends the patches of the small holes' loops to `mesh` (existing faces
// keep their order; no vertex is added). `report` may be null.
Status FillSmallHoles(Mesh& mesh, const HoleFillOptions& options, HoleFillReport* report);

}  // namespace pb
