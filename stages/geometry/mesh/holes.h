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

#include <array>
#include <cstdint>
#include <functional>
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

// Per face side (3 f + k: from corner k to corner k + 1 of face f), 1 when
// no other face has that undirected edge: a border side, its face inside.
std::vector<uint8_t> BorderSides(const Mesh& mesh);

struct HoleFillOptions {
  // A loop is filled when it has at most max_edges edges or its perimeter
  // is at most max_perimeter_m (either test; 0 disables it).
  int64_t max_edges = 0;
  double max_perimeter_m = 0;
  // When > 0, a loop small enough by the tests above is filled only if its
  // patch stays within this distance of the loop: every point of every
  // patch triangle (sampled on a barycentric grid of step 1/8) is at most
  // this far from the nearest loop edge. A round hole of perimeter P
  // reaches P / (2 pi) from its rim; a slit reaches half its width however
  // long it is.
  double max_reach_m = 0;
  // When > 0, a patch is kept only if its area is at most this fraction of
  // the area of the connected faces around the loop. The loop of an open
  // sheet (a thin fragment scanned from one side) is its outline, not a
  // hole: its patch, about as large as the sheet, would close it into a
  // shell.
  double max_component_fraction = 0;
  // When set, asked last for each patch the tests above let through, with
  // its triangles' corners (mesh frame); true keeps the hole open. E.g. the
  // scan's lines of sight (sight.h): a hole the scanner saw through is
  // free space, not missing surface.
  std::function<bool(const std::vector<std::array<double, 9>>& triangles)> keep_open;
};

struct HoleFillReport {
  uint64_t loops = 0;           // boundary loops found
  uint64_t holes_filled = 0;
  uint64_t faces_added = 0;
  uint64_t holes_rejected = 0;  // small enough, but no valid patch
  uint64_t holes_too_wide = 0;  // small enough, but the patch reaches past max_reach_m
  uint64_t outlines_kept = 0;   // small enough, but an outline (max_component_fraction)
  uint64_t holes_kept_open = 0; // small enough, but keep_open said so
};

// Appends the patches of the small holes' loops to `mesh` (existing faces
// keep their order; no vertex is added). `report` may be null.
Status FillSmallHoles(Mesh& mesh, const HoleFillOptions& options, HoleFillReport* report);

}  // namespace pb
