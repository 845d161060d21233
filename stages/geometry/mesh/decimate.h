// Mesh decimation by quadric edge collapse (Garland & Heckbert, "Surface
// Simplification Using Quadric Error Metrics", SIGGRAPH 1997), restricted to
// collapses that keep a 2-manifold mesh manifold.
//
// Input and output are triangle meshes (stages/geometry/core/mesh.h); the output
// has the same origin and the same set of attributes as the input.
//
//  * Cost: each vertex carries the sum of the area-weighted plane quadrics of
//    its faces; an edge's cost is the error of the merged quadric at the
//    optimal point (3x3 solve; when singular or far from the edge, the best
//    of the midpoint and the two endpoints, the midpoint winning ties, or
//    the minimizer nearest the midpoint if that halves the error), plus
//    1e-6 * length^4 so that on flat regions, where every error is zero,
//    short edges go first and triangles stay well shaped.
//  * Boundaries: every boundary edge (one face) adds a plane along the edge,
//    perpendicular to its face, weighted by `boundary_weight` times the edge
//    length squared, so boundary vertices stay on the boundary line and
//    corners stay put. The planes run along the border simplified to the
//    output's resolution (`boundary_tolerance`, Douglas-Peucker chords that
//    cut less into the surface than they bridge: `boundary_erosion`)
//    instead of through every input edge: a border cut face by face
//    (mesh.trim) is a staircase at the input's resolution, and on a
//    marching-cubes mesh every border vertex wavers by a fraction of a cell
//    besides; planes through every step or waver held them all, so a finer
//    mesh decimated to a budget kept more border edges than a coarser one
//    (a synthetic sculpture: 2.6x; version 2's Laplacian-smoothed planes
//    straightened staircases but not the waver). Where the minimizers of an
//    edge's quadric form a line or a plane, the collapse goes to the point
//    of it nearest the edge's midpoint, so vertices move onto their chord.
//  * Manifoldness: a collapse is rejected when it fails the link condition
//    (the common neighbors of the two endpoints must be exactly the opposite
//    vertices of the edge's faces, and no edge may be in both links: this
//    keeps a tetrahedron and a lone triangle as they are; an interior edge
//    joining two boundary vertices is rejected, as it would pinch the
//    boundary), when it would turn any surviving face by more than
//    acos(min_normal_dot) against its current or its original normal, or
//    when it would make a face degenerate (twice its area under 1e-6 times
//    its longest edge squared). Edges of more than two faces (non-manifold
//    input) are never collapsed.
//  * Attributes: normals, colors, uvs and tangents of the kept vertex are
//    interpolated between the edge's endpoints at the parameter of the new
//    position projected on the edge (clamped to [0,1]); normals and tangent
//    xyz are renormalized, tangent w is taken from the nearer endpoint. UVs
//    are interpolated as they are: across a texture seam they smear, so
//    decimate before unwrapping.
//  * Determinism: single-threaded; the heap orders by cost, then by the
//    edge's (smaller, larger) vertex index, so equal inputs give identical
//    outputs.
//
// Memory: about 150 bytes per input face besides the input (quadrics,
// adjacency, heap). Measured: 4.8e6 -> 2.5e5 faces in 8.5 s (synth room) and
// 5.2e6 -> 2.5e5 in 17 s (icosphere, poor vertex locality), one core.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/mesh.h"

namespace pb {

struct DecimateOptions {
  // Stop when the face count is at most this. Reached unless the remaining
  // collapses are all rejected (the report then shows more faces out).
  size_t target_faces = 0;
  // Weight of the boundary constraint planes relative to the face planes
  // (both scale with length squared, so this is unitless). 0 frees the
  // boundary.
  double boundary_weight = 1000.0;
  // Boundary planes run along the border simplified to within this
  // fraction of the output's mean edge length (sqrt(4 area / (sqrt(3)
  // target_faces))): each simple course of the border (closed loops, and
  // stretches between vertices where several borders meet) is replaced by
  // Douglas-Peucker chords that pass within the tolerance of its vertices,
  // measured across the border in the surface, and every border edge's
  // plane runs through its chord. Corners and bends larger than the
  // tolerance are chord ends and stay put. Only the planes move, then the
  // collapses: the border moves by at most about the tolerance. 0: planes
  // through the input's own edges (version 1).
  double boundary_tolerance = 0.2;
  // The part of boundary_tolerance by which a chord may cut into the surface
  // (a vertex outside its chord is cut off when the collapses move it
  // there); bridging a notch (a vertex inside its chord) takes the whole
  // tolerance. 1: symmetric; 0: the border only grows.
  double boundary_erosion = 0.5;
  // Reject a collapse that makes a face's unit normal have a dot product
  // below this with its normal before the collapse or in the input.
  double min_normal_dot = 0.2;
  // Before collapsing, fill the holes (boundary loops) whose perimeter is
  // at most `fill_hole_output_edges` output mean edge lengths and whose
  // patch (FillSmallHoles, holes.h; no new vertices) stays within
  // `fill_hole_reach` output edges of the hole's rim. The output cannot
  // draw such a hole: held by the boundary planes it ends as a hole of a
  // few low-poly triangles, which a coarser surface of the same budget (a
  // low-depth Poisson mesh) would have closed. A longer hole has border
  // edges enough to be drawn, however narrow (a window slit stays open).
  // The reach keeps a patch within one output edge of the rim, where
  // metrics.geometry counts no invented area: a round hole of reach 1 has
  // a perimeter of 2 pi output edges, an oval of perimeter 8 is filled when
  // it is less than about two edges wide. 0 fills nothing; a reach of 0
  // fills every hole up to the perimeter (version 4, with a perimeter of 6).
  double fill_hole_output_edges = 0;
  double fill_hole_reach = 0;
  // A patch larger than this fraction of its connected surface's area is
  // not filled: that loop is the outline of an open sheet (a thin fragment
  // seen from one side), which a patch would close into a shell.
  double fill_hole_max_component_fraction = 0.25;
  // When set, asked for each hole the tests above would fill, with its
  // patch's triangles (mesh frame) and the output's mean edge length; true
  // keeps it open (the stage passes the scan's lines of sight, sight.h: a
  // hole the scanner saw through is no surface to fill).
  std::function<bool(const std::vector<std::array<double, 9>>& patch, double output_edge_m)>
      keep_hole_open;
  // Called with the fraction of the work done, in [0,1], every few thousand
  // collapses.
  std::function<void(double fraction)> progress;
};

struct DecimateReport {
  uint64_t faces_in = 0;
  uint64_t faces_out = 0;
  uint64_t vertices_in = 0;
  uint64_t vertices_out = 0;  // referenced vertices only: unused ones are dropped
  uint64_t collapses = 0;
  uint64_t rejected_link = 0;        // link condition or non-manifold edge
  uint64_t rejected_flip = 0;        // a face normal would turn too far
  uint64_t rejected_degenerate = 0;  // a face would get (near) zero area
  uint64_t holes_filled = 0;         // fill_hole_output_edges
  uint64_t hole_faces = 0;           // faces the filled holes added
  uint64_t holes_too_wide = 0;       // within the perimeter, past the reach
  uint64_t outlines_kept = 0;        // open sheets' outlines, not filled
  uint64_t holes_seen_through = 0;   // kept open by keep_hole_open
};

// Decimates `mesh` to about `options.target_faces` triangles. Status::Invalid
// if the mesh fails Validate(), has a non-finite coordinate or a face with a
// repeated vertex index, or the options are out of range.
// `report` may be null.
Expected<Mesh> DecimateMesh(const Mesh& mesh, const DecimateOptions& options,
                            DecimateReport* report);

}  // namespace pb
