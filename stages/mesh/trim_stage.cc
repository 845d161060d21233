// mesh.trim: removes the connected regions of a reconstructed mesh that the
// scan's points do not support (stages/geometry/mesh/trim.h). A stage of its
// own rather than a mode of mesh.poisson: it needs the points, works on any
// mesh (Poisson at any depth, another reconstructor's output), and the
// solve stays cached while the trimming parameters are tuned.
#include "stages/builtin.h"

#include "stages/geometry/mesh/trim.h"
#include "stages/mesh_io.h"
#include "stages/params.h"
#include "stages/points_io.h"

namespace pb {
namespace {

constexpr const char* kId = "mesh.trim";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "max_distance_spacings": {
      "type": "number",
      "minimum": 0,
      "default": 3,
      "description": "A face is unsupported when its centroid and corners are all farther from every scan point than this many local point spacings (the spacing of the nearest point, from its k nearest neighbours) and than `max_distance_edges` mean edge lengths."
    },
    "max_distance_edges": {
      "type": "number",
      "minimum": 0,
      "default": 1,
      "description": "The distance floor in mean edge lengths of the mesh: a coarse Poisson surface rounds corners off by about a cell, which is real surface."
    },
    "grow_fraction": {
      "type": "number",
      "exclusiveMinimum": 0,
      "maximum": 1,
      "default": 0.5,
      "description": "Hysteresis: faces farther than this fraction of the unsupported distance join a removed region when they touch it through edges (the fringe where a membrane meets real surface); alone they stay."
    },
    "min_region_faces": {
      "type": "integer",
      "minimum": 0,
      "default": 8,
      "description": "A connected unsupported region with fewer faces stays (mesh.clean would fill its hole again)."
    },
    "smooth_passes": {
      "type": "integer",
      "minimum": 0,
      "maximum": 100,
      "default": 4,
      "description": "Passes of border smoothing: a face with two or three edge neighbours on the other side of the cut flips (spurs go, notches come back unless beyond the full distance), so borders do not zigzag face by face; mesh.decimate holds borders and would spend faces on every zigzag. 0 keeps the raw cut."
    },
    "spacing_neighbors": {
      "type": "integer",
      "minimum": 1,
      "maximum": 64,
      "default": 8,
      "description": "k of the local spacing: spacing = r_k * sqrt(pi / k), r_k the distance to the k-th nearest other point."
    },
    "threads": {
      "type": "integer",
      "minimum": 0,
      "default": 0,
      "x-affects-output": false,
      "description": "Worker threads; 0 takes the engine's --threads. The output does not depend on it."
    }
  }
})";

Status Run(StageContext& ctx) {
  TrimOptions options;
  PB_ASSIGN_OR_RETURN(options.max_distance_spacings,
                      NumberParam(ctx, kId, "max_distance_spacings"));
  PB_ASSIGN_OR_RETURN(options.max_distance_edges, NumberParam(ctx, kId, "max_distance_edges"));
  PB_ASSIGN_OR_RETURN(options.grow_fraction, NumberParam(ctx, kId, "grow_fraction"));
  PB_ASSIGN_OR_RETURN(options.min_region_faces,
                      IntegerParam(ctx, kId, "min_region_faces", {0}));
  PB_ASSIGN_OR_RETURN(const int64_t smooth_passes,
                      IntegerParam(ctx, kId, "smooth_passes", {0, 100}));
  options.smooth_passes = static_cast<int>(smooth_passes);
  PB_ASSIGN_OR_RETURN(const int64_t neighbors,
                      IntegerParam(ctx, kId, "spacing_neighbors", {1, 64}));
  options.spacing_neighbors = static_cast<int>(neighbors);
  PB_ASSIGN_OR_RETURN(const int64_t threads, IntegerParam(ctx, kId, "threads", {0}));
  options.threads = threads > 0 ? static_cast<int>(threads) : ctx.threads();

  PB_ASSIGN_OR_RETURN(InputMesh input, ReadInputMesh(ctx, kId, 0.2));
  PB_ASSIGN_OR_RETURN(InputPoints points, ReadInputPoints(ctx, kId, 0.4));
  SupportTrimReport report;
  Mesh trimmed;
  {
    PB_PHASE(ctx, "compute");
    Expected<Mesh> result = TrimUnsupported(input.mesh, points.cloud, options, &report);
    if (!result.ok()) {
      return result.status().WithContext(input.path + " with " + points.path);
    }
    trimmed = std::move(result).value();
  }
  ctx.progress(0.9);
  ctx.counter("faces_in", static_cast<double>(report.faces_in));
  ctx.counter("faces_removed", static_cast<double>(report.faces_removed));
  ctx.counter("regions_removed", static_cast<double>(report.regions_removed));
  ctx.counter("faces_out", static_cast<double>(trimmed.face_count()));
  nlohmann::json changes = {{"trim",
                          {{"core_faces", report.core_faces},
                           {"weak_faces", report.weak_faces},
                           {"regions_removed", report.regions_removed},
                           {"smoothed_faces", report.smoothed_faces},
                           {"faces_removed", report.faces_removed},
                           {"vertices_removed", report.vertices_removed},
                           {"mean_edge_m", report.mean_edge_m},
                           {"median_local_spacing_m", report.median_spacing_m}}}};
  // Later stages (mesh.clean's hole sizes) measure in spacings: pass on the
  // points' own when the mesh meta has none.
  const nlohmann::json& mesh_meta = ctx.input("mesh").meta;
  if (!(mesh_meta.is_object() && mesh_meta.contains("spacing_m"))) {
    const double points_spacing = InputPointsSpacing(ctx);
    changes["spacing_m"] = points_spacing > 0 ? points_spacing : report.median_spacing_m;
  }
  PB_RETURN_IF_ERROR(WriteOutputMesh(ctx, trimmed, InputMeshMetaWith(ctx, trimmed, changes)));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType TrimStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Removes the regions of a mesh that the scan's points do not support";
  type.doc =
      "Removes the surface a reconstruction invented where the scan has no points (Poisson's "
      "membranes across unscanned space, blobs beyond the scan's borders), judged face by face "
      "by the distance of its centroid and corners to the nearest scan point, in units of that "
      "point's local spacing (`max_distance_spacings`, floored by `max_distance_edges` mean "
      "edge lengths). Faces are removed by connected regions, with hysteresis: a region of "
      "faces farther than `grow_fraction` of that distance goes when it holds at least one face "
      "beyond the full distance and has at least `min_region_faces` faces; a single weakly "
      "supported face or vertex never opens a hole. The cut is smoothed (`smooth_passes`) so borders do not zigzag face by face. Unlike mesh.poisson's density-quantile "
      "`trim`, the measure is local, so it suits one-station scans whose density falls with "
      "range. Follow with mesh.clean (manifold, small holes filled). Deterministic for any "
      "thread count.\n\n"
      "Counters: `faces_in`, `faces_removed`, `regions_removed`, `faces_out`. Phases: `io`, "
      "`compute`.";
  type.params_schema = kSchema;
  type.inputs = {{"mesh", "mesh", "The reconstructed mesh (mesh.ply).", false},
                 {"points", "points", "The scan it was reconstructed from (points.ply).", false}};
  type.outputs = {{"mesh", "mesh", "The mesh without its unsupported regions.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
