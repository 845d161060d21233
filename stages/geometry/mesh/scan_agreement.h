// How a mesh agrees with the scan it was built from, without ground truth:
// the figures that name what a person sees wrong in a real scan's model.
//  - Invented area: surface the scan never saw (Poisson closing an open side,
//    bridging a gap). A mesh point is invented when it is farther than its
//    threshold from every scan point, threshold = max(spacing_factor x the
//    point's local spacing, the mesh's mean edge length): a coarse mesh
//    cannot follow the scan closer than about one edge, so its own
//    resolution is not counted as invention. Measured on `samples` points
//    spread uniformly by area over the mesh (SampleMeshSurface, fixed seed),
//    each checked against its `neighbors` nearest scan points (exact k-NN,
//    points/knn.h); the figure is the fraction of those samples, an estimate
//    of the fraction of the mesh's area.
//  - Missing surface: scan points farther than spacing_factor x their local
//    spacing from the mesh (exact point-triangle distance, TriangleBvh): what
//    the scanner saw and the model lost (holes, trimmed or smoothed-away
//    parts). Over at most `samples` scan points, indices floor(j n / count)
//    (all when n <= samples), as a fraction of those.
//  - Boundary edges: edges with exactly one face, per 1000 faces (a closed
//    surface has none; holes and open borders add them).
// Local spacing comes from the caller (points/spacing.h LocalSpacing), one
// value per scan point, meters. Absolute coordinates: each side's origin is
// applied. Results do not depend on the thread count (run inside a
// tbb::task_arena to limit threads).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/mesh.h"
#include "stages/geometry/core/point_cloud.h"
#include "stages/geometry/mesh/distance.h"
#include "stages/geometry/mesh/trim.h"  // CountBoundaryEdges, MeanEdgeLength
#include "stages/geometry/points/knn.h"

namespace pb {

struct ScanAgreementOptions {
  double spacing_factor = 3;  // thresholds in local spacings, > 0
  size_t samples = 200000;    // mesh samples, and scan points measured at most
  uint64_t seed = 1;          // of the mesh samples
  int neighbors = 16;         // scan points checked per mesh sample, >= 1
  // Empty, or one flag per scan point: 1 for a stray (points/strays.h), which
  // missing surface leaves out (no model should have it).
  std::span<const uint8_t> strays;
};

struct ScanAgreement {
  double invented_area_fraction = 0;  // of the mesh's area, [0, 1]
  double missing_fraction = 0;        // of the scan's points, [0, 1]
  size_t boundary_edges = 0;
  double boundary_edges_per_1000_faces = 0;
  double mean_edge_m = 0;             // over the faces' three edges
  double median_spacing_m = 0;        // of the local spacings given
  size_t mesh_samples = 0;
  size_t scan_points_measured = 0;  // strays left out
  size_t stray_points = 0;          // of the scan, as flagged in the options
  // The distances behind the two fractions, meters: each mesh sample to its
  // nearest scan point, each measured scan point to the mesh.
  DistanceStats mesh_to_scan;
  DistanceStats scan_to_mesh;
};

// Status::Invalid: a mesh failing Validate or without faces of positive area,
// an empty cloud, local_spacing_m of the wrong length, or bad options.
Expected<ScanAgreement> MeasureScanAgreement(const Mesh& mesh, const PointCloud& scan,
                                             std::span<const float> local_spacing_m,
                                             const ScanAgreementOptions& options = {});
// The same with the caller's index of the scan's points (KnnIndex::Build of
// scan.positions), for a caller that measures several things against one scan.
Expected<ScanAgreement> MeasureScanAgreement(const Mesh& mesh, const PointCloud& scan, const KnnIndex& index,
                                             std::span<const float> local_spacing_m,
                                             const ScanAgreementOptions& options = {});

// The same tests at the mesh's vertices, for error maps (a .vtp or a PLY
// `quality` a person looks at): per vertex, the distance to the nearest scan
// point (meters) and 1 where the vertex is invented by the rule above (0
// otherwise). options.samples is not used. Same errors as
// MeasureScanAgreement.
struct VertexScanAgreement {
  std::vector<float> distance_to_scan_m;
  std::vector<uint8_t> invented;
};
Expected<VertexScanAgreement> MeasureVertexScanAgreement(const Mesh& mesh, const PointCloud& scan,
                                                         std::span<const float> local_spacing_m,
                                                         const ScanAgreementOptions& options = {});
Expected<VertexScanAgreement> MeasureVertexScanAgreement(const Mesh& mesh, const PointCloud& scan,
                                                         const KnnIndex& index,
                                                         std::span<const float> local_spacing_m,
                                                         const ScanAgreementOptions& options = {});

}  // namespace pb
