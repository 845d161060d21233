// Trimming by support: removes the surface a reconstruction invented where
// the scan has no points, judged by distance to the points in units of the
// *local* point spacing, and by connected regions, never by single vertices.
//
// Why not Poisson's density quantile (TrimByDensity in poisson.h): the
// quantile is global, so on a one-station scan, whose density falls with the
// square of the range, it cuts isolated low-density vertices inside well
// sampled but distant surface (pin-holes that decimation then grows into
// holes the size of a low-poly triangle) while leaving large membranes
// across unscanned space whose density is above the quantile.
//
// The test, per face:
//  * Local spacing s(p) of each scan point p: LocalSpacing of
//    points/spacing.h, s = r_k * sqrt(pi / k) with r_k the distance to its
//    k-th nearest other point, the definition metrics.geometry and
//    render.splats use too. It follows the density of one-station scans,
//    which changes with range and incidence.
//  * The distance of a mesh point x from the scan: |x - p| to the nearest
//    scan point p; x is unsupported at level t when that distance exceeds
//    t * max(spacings * s(p), edges * mean edge length of the mesh) (the
//    edge term because a coarse Poisson surface rounds off corners by about
//    a cell, which is real surface, not invention).
//  * A face's distance is the smallest over its centroid and its corners,
//    so a face touching supported surface is never a core face.
//  * Hysteresis on connected regions: "core" faces are unsupported at level
//    1; "weak" faces at level `grow_fraction`. A connected region (faces
//    sharing edges) of weak faces is removed when it contains a core face,
//    so the fringe of a membrane where it meets real surface goes with it,
//    while a weak face alone (a low-density vertex, a slightly noisy patch)
//    never opens a hole.
//  * A removed region must also have at least `min_region_faces` faces
//    (gaps of a few faces are what the hole filler of mesh.clean would
//    close again).
//  * The cut is then smoothed for `smooth_passes` passes: a face with two
//    or three of its edge neighbours on the other side of the cut flips
//    (kept spurs go, removed notches that are not core faces come back), so
//    the border does not zigzag at the size of a face, which decimation,
//    holding borders, would have to keep.
// Vertices no kept face uses are dropped; kept faces keep their order, so
// the result does not depend on the thread count.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/mesh.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

struct TrimOptions {
  double max_distance_spacings = 3.0;  // core: farther than this many local spacings ...
  double max_distance_edges = 1.0;     // ... and this many mean edge lengths
  double grow_fraction = 0.5;          // weak faces: farther than this x the core distance
  int64_t min_region_faces = 8;        // smaller unsupported regions stay
  int smooth_passes = 4;               // border smoothing passes (majority of neighbours)
  int spacing_neighbors = 8;           // k of the local spacing
  int threads = 0;                     // 0: TBB's default (all cores)
};

struct SupportTrimReport {
  uint64_t faces_in = 0;
  uint64_t core_faces = 0;     // unsupported at level 1
  uint64_t weak_faces = 0;     // unsupported at level grow_fraction (cores included)
  uint64_t regions_removed = 0;
  uint64_t smoothed_faces = 0;  // flipped by border smoothing, over all passes
  uint64_t faces_removed = 0;
  uint64_t vertices_removed = 0;
  double mean_edge_m = 0;
  double median_spacing_m = 0;  // of the points' local spacings
};

// The mesh without its unsupported regions. The mesh and the points may
// have different origins. Status::Invalid if either fails Validate, the
// cloud has fewer than spacing_neighbors + 1 points or a non-finite
// coordinate, or an option is out of range (distances < 0, grow_fraction
// outside (0, 1], spacing_neighbors < 1, min_region_faces < 0,
// smooth_passes < 0). `report` may
// be null.
Expected<Mesh> TrimUnsupported(const Mesh& mesh, const PointCloud& points,
                               const TrimOptions& options, SupportTrimReport* report);

// How much of a mesh the points support, by the measure of issue 15:
// the mesh is sampled uniformly by area (about `samples` points, a
// deterministic stratified pattern per face) and a sample is "invented" when
// it is farther than max(spacings * s(p), edges * mean edge length) from
// every scan point, with s(p) the local spacing of its nearest point p as
// above. Also counts boundary edges (edges of exactly one face).
struct SupportOptions {
  double spacings = 3.0;
  double edges = 1.0;
  size_t samples = 200000;
  int spacing_neighbors = 8;
  int threads = 0;
};
struct SupportReport {
  double area_m2 = 0;
  double invented_area_m2 = 0;
  double invented_fraction = 0;  // invented_area_m2 / area_m2
  uint64_t faces = 0;
  uint64_t boundary_edges = 0;
  double boundary_edges_per_1000_faces = 0;
  double mean_edge_m = 0;
};
Expected<SupportReport> MeasureSupport(const Mesh& mesh, const PointCloud& points,
                                       const SupportOptions& options);

// Edges used by exactly one face, vertices at the same position counting as
// one (the copies uv.unwrap makes along its seams), so a UV seam is no border.
uint64_t CountBoundaryEdges(const Mesh& mesh);

// Mean length of the faces' sides (meters; 0 without faces).
double MeanEdgeLength(const Mesh& mesh);

}  // namespace pb
