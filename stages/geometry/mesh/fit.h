// Fitting a mesh to its scan: moves the vertices of a (low) mesh along their
// normals (or, with free_directions, in any direction) so that the surface
// passes through the scan's points instead of being inscribed in a smoothed
// surface.
//
// Why: a decimated mesh's vertices sit on the surface it was decimated from
// (here a Poisson surface), so its chords cut inside every convex part (a
// pipe of radius r drawn with edges of length e loses up to e^2 / 8r), and a
// coarse Poisson solve rounds thin parts inward on its own. Seen from the
// side, the mesh's outline lies a pixel or two inside the outermost scan
// points: hole pixels on the scan's footprint (docs/real-scans.md, item 5).
//
// The fit, for `iterations` rounds:
//  * Each supported scan point p is assigned to its nearest face f (exact
//    point-triangle distance, TriangleBvh::Nearest; ties to the lowest face)
//    with closest point q and its barycentric coordinates (b0, b1, b2) in f.
//    Supported: |p - q| <= max(support_spacings x the point's local spacing
//    (points/spacing.h LocalSpacing), support_edges x the mesh's mean edge
//    length), and, when the cloud has normals, n_p . n_f >= min_normal_cosine
//    (a point seen from the other side of a thin part does not pull).
//  * The point's signed distance d = (p - q) . n_f, n_f the face's unit
//    normal (positive: the point lies outside the surface).
//  * Per round, the displacements u along the vertex normals solve the
//    weighted least-squares problem
//      sum over points of w_p (b0 u_0 + b1 u_1 + b2 u_2 - d)^2
//        + lambda W sum over edges (u_i - u_j)^2
//    (the face moves by the barycentric blend of its corners' moves; W the
//    mean diagonal data weight of the vertices with points, lambda =
//    `smoothness`) by `sweeps` Gauss-Seidel sweeps in vertex order from
//    u = 0. w_p = 2 `outside_weight` for a point outside the surface of
//    the round (d > 0), 2 (1 - `outside_weight`) inside: rounds of this
//    reweighting converge to the asymmetric least-squares (expectile) fit.
//    0.5 is plain least squares, whose surface runs through the middle of
//    the points, so the outer half of the samples along a silhouette lies
//    outside the model's outline (hole pixels, a pixel wide); the default
//    0.75 (a point outside weighs 3 inside ones) puts the surface towards
//    the outer side of the points' spread, a fraction of its width
//    (docs/mesh-real-scans.md: hole pixels on the samples of curved
//    objects 2-3x fewer, texture comparisons within 0.001). The smoothness term acts on the displacement, not on the
//    positions (a Laplacian on positions would shrink the mesh, which is the
//    very error being corrected); vertices without points follow their
//    neighbours. (The coupled problem rather than each vertex's own
//    barycentric-weighted mean distance: that estimate does not see a
//    checkerboard of moves, a vertex up and its neighbours down, which
//    leaves its weighted mean residual at zero.)
//  * Step: v += damping x clamp(u_v, +-max_step_edges x the mean length of v's
//    edges in the input) x n_v, n_v the area-weighted vertex normal, and v
//    never ends farther than max_offset_edges of that length from its input
//    position (a chord's sagitta is a fraction of an edge; a vertex pulled
//    farther is pulled by another surface's points). Border vertices move
//    the same way, along the normal only, in the rounds.
//  * Free directions (`free_directions`, the stage's default since its
//    version 4): the displacement D_v is a vector instead of u_v n_v; a
//    point's distance changes by n_f . sum_k b_k D_k, so each sweep solves
//    a 3 x 3 block per vertex, and the smoothness acts on D's component
//    along n_v with weight lambda W and across it with `tangent_weight` of
//    that, plus a tie of the same weight holding the tangential part at the
//    vertex's place. Why: a coarse Poisson solve rounds a crease (a plinth's
//    edge, a wall's corner) and the decimation keeps the rounding as a
//    chamfer whose two rows of vertices sit on the two faces; moving them
//    along their diagonal normals bends both faces, so the fit left them
//    where they were, the model's outline a pixel inside the box's corner.
//    Free, each slides along its own face out to the crease. Only a vertex
//    with a face turned more than `crease_deg` from its normal moves freely
//    (elsewhere the points pull along the normals anyway, and a free vertex
//    drifts along the surface with the noise: on the statue stand-in of
//    docs/mesh-real-scans.md every vertex free moved them 1.7 mm on
//    average, against 1.2 mm along the normals); border vertices keep moving
//    along their normals (the border pass moves them after the rounds):
//    with half their neighbours missing, the faces' diagonals along a rim
//    twist a free one by millimetres. A vertex held to its normal takes the
//    block's minimizer along it, (N . r) / (N^T A N) (the stage's version 5;
//    version 4 projected the 3 x 3 solution onto N).
//  * No face may turn by more than `max_turn_deg` from its normal before the
//    step or in the input, nor lose its area: the steps of the vertices of
//    such faces are halved (up to 6 times, then dropped) until none does.
// Borders (version 3 of the stage): after the rounds, a border pass moves
// border vertices outward in their faces' planes so that the model's
// outline reaches the scan's. mesh.decimate may cut a border up to half an
// output edge into the scanned surface (`boundary_erosion`), and the
// outermost points beyond it are hole pixels at the outline
// (docs/mesh-real-scans.md, "Borders out to the scan's outline"). Twice:
//  * every supported point whose closest point lies on a border edge (its
//    barycentric coordinate of the opposite corner is 0), outside it in the
//    face's plane by t >= 0, and off that plane by at most t + 2 s (the
//    surface continuing, within 45 degrees give or take the noise; a wall
//    behind the border or a mixed return along the ray at a depth step is
//    farther off), asks the edge's line to move outward by
//    t + border_margin_spacings x s at its place along the edge, s the
//    point's local spacing but at most the cloud's median (a sparse flying
//    pixel's inflated spacing buys no tolerance);
//  * per edge, the end offsets (m_a, m_b) >= 0 whose line (1 - s) m_a +
//    s m_b passes over every such goal with the least m_a + m_b: the upper
//    convex hull of the goals and of (0, 0) and (1, 0), read at s = 1/2;
//  * a border vertex with exactly two border edges moves by the shortest
//    vector in the span of their outward directions that meets both ends'
//    offsets, at most border_reach_edges of its input mean edge from where
//    the pass found it; the face-turn guard below halves the moves as in
//    the rounds. Interior vertices, and vertices where borders meet, stay.
// Faces, vertex order and every attribute but positions and normals are
// kept; normals, when present, are the input's turned by the rotation that
// takes the vertex's area-weighted face normal before the fit to the one
// after (recomputing them from the faces would show every facet of a
// decimated mesh in the lighting, where the input's normals are the
// smoother surface's); uvs are not touched: it runs before unwrapping. Deterministic
// for any thread count: every point's assignment is independent, and the
// sums run in point order.
#pragma once

#include <cstddef>
#include <cstdint>

#include "base/status.h"
#include "stages/geometry/core/mesh.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

struct FitOptions {
  int iterations = 12;              // assignment + step rounds, >= 1
  double support_spacings = 3.0;    // support distance in local spacings, >= 0
  double support_edges = 0.5;       // ... floored by this many mean edge lengths, >= 0
  double min_normal_cosine = 0.0;   // point normal vs face normal (cloud with normals), [-1, 1]
  double smoothness = 0.25;         // lambda of the displacement smoothing, >= 0
  double outside_weight = 0.75;     // weight of a point outside vs inside: w, 1 - w; (0, 1), 0.5 least squares
  int sweeps = 20;                  // Gauss-Seidel sweeps of the solve per round, >= 1
  double damping = 0.8;             // fraction of the solved step taken, (0, 1]
  double max_step_edges = 0.25;     // step clamp per round, in mean incident edge lengths, > 0
  double max_offset_edges = 0.5;    // farthest a vertex ends from its input position, same unit, > 0
  double max_turn_deg = 60.0;       // largest turn of a face normal, (0, 180)
  int spacing_neighbors = 8;        // k of the local spacing, >= 1
  double border_reach_edges = 0.5;  // farthest a border vertex moves outward, in its mean edges; 0: off
  double border_margin_spacings = 0.5;  // border this many local spacings past the outermost points, >= 0
  bool free_directions = true;      // vertices move in 3-D (crease-aware); false: along normals (v3)
  double tangent_weight = 0.1;      // free_directions: smoothness across the normal, of lambda's; > 0
  double crease_deg = 20.0;         // free_directions: only where a face turns more from the vertex normal
  int threads = 0;                  // 0: TBB's default (all cores)
};

struct FitReport {
  uint64_t points = 0;              // scan points
  uint64_t supported_before = 0;    // points within support of the input mesh
  uint64_t supported_after = 0;     // ... of the output mesh (same test)
  double mean_abs_distance_before_m = 0;  // mean |d| of the points supported before
  double mean_abs_distance_after_m = 0;   // the same points, against the output
  double mean_signed_distance_before_m = 0;
  double mean_signed_distance_after_m = 0;
  double outside_fraction_before = 0;  // of the points supported before, the share with d > 0
  double outside_fraction_after = 0;   // the same points, against the output
  uint64_t vertices_moved = 0;      // vertices whose position changed
  double max_move_m = 0;            // largest displacement of a vertex, input to output
  double mean_move_m = 0;           // over all vertices
  uint64_t steps_halved = 0;        // vertex steps halved by the face-turn guard, all rounds
  uint64_t border_vertices_moved = 0;  // border vertices moved outward by the border pass
  double mean_edge_m = 0;
  double median_spacing_m = 0;      // of the points' local spacings
};

// The fitted mesh. The mesh and the points may have different origins.
// Status::Invalid if either fails Validate, the mesh has no faces, the cloud
// has at most spacing_neighbors points or a non-finite coordinate, or an
// option is out of range. `report` may be null.
Expected<Mesh> FitMeshToPoints(const Mesh& mesh, const PointCloud& points,
                               const FitOptions& options, FitReport* report);

}  // namespace pb
