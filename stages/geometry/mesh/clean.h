// Mesh cleaning: turns a triangle soup from reconstruction into a
// 2-manifold mesh that UV unwrapping and decimation can rely on.
//
// Steps, in this order (each sees the result of the previous ones):
//   1. degenerate faces: a repeated vertex index, or area < min_area_m2;
//   2. duplicate faces: the same vertex set as an earlier face (either
//      orientation); the first one is kept;
//   3. non-manifold edges: where an edge has more than two faces, faces are
//      accepted greedily by decreasing area (ties: lower face index) and a
//      face is dropped if one of its edges already has two accepted faces, so
//      each such edge keeps its two largest faces;
//   3b. misoriented edges: where the two faces of an edge run it the same
//      way, the smaller face is dropped (mesh.decimate would treat the edge
//      as two border edges);
//   4. small connected components (faces connected through shared edges):
//      fewer than min_component_faces faces, or fewer than
//      min_component_fraction times the largest component's face count, AND
//      an area below min_component_area_m2 (a decimated planar wall can be a
//      2-face component; noise specks are both few-faced and tiny);
//   5. non-manifold vertices: a vertex whose faces form several fans (groups
//      connected through edges at that vertex) is split into one vertex per
//      fan; the new vertices copy every attribute of the original;
//   6. small holes: boundary loops of at most hole_max_edges edges or of a
//      perimeter of at most hole_max_perimeter_m are filled without new
//      vertices (FillSmallHoles in holes.h; 0 disables a test);
//   7. unreferenced vertices are dropped (the survivors keep their order).
// The result has every edge in at most two faces and every vertex in exactly
// one fan (see CheckManifold). Face order is preserved among the kept faces;
// the faces filling holes come after them.
#pragma once

#include <cstdint>

#include "base/status.h"
#include "stages/geometry/core/mesh.h"

namespace pb {

struct CleanOptions {
  double min_area_m2 = 1e-10;         // faces below this area are degenerate
  int64_t min_component_faces = 50;   // components with fewer faces are removed
  double min_component_fraction = 0;  // ... or fewer than this x the largest one
  double min_component_area_m2 = 0.01;  // ... and smaller than this area
  int64_t hole_max_edges = 0;           // fill boundary loops with at most this many edges
  double hole_max_perimeter_m = 0;      // ... or at most this perimeter
};

// What CleanMesh removed or added; face counts per step.
struct CleanReport {
  uint64_t faces_in = 0;
  uint64_t vertices_in = 0;
  uint64_t degenerate_faces = 0;
  uint64_t duplicate_faces = 0;
  uint64_t nonmanifold_edge_faces = 0;  // faces dropped to make edges manifold
  uint64_t misoriented_faces = 0;       // faces dropped at misoriented edges
  uint64_t small_components = 0;
  uint64_t small_component_faces = 0;
  uint64_t split_vertices = 0;         // vertices added by splitting fans
  uint64_t boundary_loops = 0;         // before filling
  uint64_t holes_filled = 0;
  uint64_t hole_faces = 0;             // faces added filling them
  uint64_t unreferenced_vertices = 0;  // vertices dropped (incl. orphaned by steps 1-4)
  uint64_t faces_out = 0;
  uint64_t vertices_out = 0;
};

// Status::Invalid if `mesh` fails Validate or the options are out of range
// (min_area_m2 < 0, min_component_faces < 0, fraction outside [0, 1],
// hole_max_edges < 0, hole_max_perimeter_m < 0).
// `report` may be null.
Expected<Mesh> CleanMesh(const Mesh& mesh, const CleanOptions& options, CleanReport* report);

// Ok if every edge lies in at most two faces and the faces around every
// vertex form a single fan; otherwise Status::Invalid naming the first
// offending edge or vertex.
Status CheckManifold(const Mesh& mesh);

}  // namespace pb
