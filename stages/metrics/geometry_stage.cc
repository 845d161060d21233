// metrics.geometry: distance between a mesh and the ground truth, sampled both
// ways (stages/geometry/mesh/distance.h), written as a table; the same
// comparisons at the mesh's vertices written as error maps (errors.vtp for
// ParaView, errors.ply with a `quality` property for MeshLab/CloudCompare).
#include "stages/builtin.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <optional>

#include "stages/geometry/mesh/distance.h"
#include "stages/geometry/mesh/scan_agreement.h"
#include "stages/geometry/points/knn.h"
#include "stages/geometry/points/spacing.h"
#include "stages/geometry/points/strays.h"
#include "stages/points_io.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/io/vtp.h"
#include "stages/geometry/synth/scene.h"
#include "stages/geometry/core/table.h"
#include "stages/params.h"

namespace pb {
namespace {

constexpr const char* kId = "metrics.geometry";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "samples": {
      "type": "integer",
      "minimum": 1,
      "default": 200000,
      "description": "Points sampled per direction, uniformly by area; the mean's noise falls as 1/sqrt(samples)."
    },
    "k": {
      "type": "integer",
      "minimum": 1,
      "maximum": 64,
      "default": 8,
      "description": "With `points`: a scan point's local spacing is r_k sqrt(pi / k), r_k the distance to its k-th nearest other point (points/spacing.h LocalSpacing; mesh.trim and render.splats use the same)."
    },
    "stray_cluster_points": {
      "type": "integer",
      "minimum": 0,
      "default": 50,
      "description": "With `points`: scan points in clusters of fewer samples are strays (points/strays.h, as render.splats leaves them out of the scan's frames: a return in the air, floating dust; since version 7 also the points in the air, sparse and on no plane), which missing surface does not count. 0 counts every point."
    },
    "stray_spacing_ratio": {
      "type": "number",
      "minimum": 1,
      "default": 3,
      "description": "Two neighbours link within 2 of the larger of their local spacings when those differ by at most this factor, else within 2 of the smaller (points/strays.h): a sparse row beside denser sampling (a wall's top seen at grazing angle, the ceiling above a tripod scanner) stays, a return far off a surface, whose spacing is its distance to it, does not. 1: the smaller always."
    },
    "spacing_factor": {
      "type": "number",
      "exclusiveMinimum": 0,
      "default": 3,
      "description": "With `points`: mesh surface farther than max(spacing_factor local spacings, the mesh's mean edge) from every scan point is invented; scan points farther than spacing_factor local spacings from the mesh are missing."
    },
    "seed": {
      "type": "integer",
      "minimum": 0,
      "default": 1,
      "description": "Seed of the sampling sequence (the same inputs and seed give the same table)."
    }
  }
})";

Expected<Mesh> ReadMeshInput(StageContext& ctx, const char* port, double progress_begin,
                             double progress_end) {
  PB_ASSIGN_OR_RETURN(const std::string path, InputFilePath(ctx, kId, port, "mesh.ply"));
  PlyReadOptions options;
  options.progress = [&](double f) {
    ctx.progress(progress_begin + (progress_end - progress_begin) * f);
  };
  PB_ASSIGN_OR_RETURN(PlyMesh read, ReadPlyMesh(path, options));
  return std::move(read.mesh);
}

std::vector<TableValue> Row(const char* direction, const DistanceStats& s, const char* method,
                            TableValue beyond_fraction, double boundary_edges_per_1000_faces) {
  return {std::string(direction), static_cast<int64_t>(s.samples), s.mean_m, s.rms_m, s.p95_m, s.max_m,
          std::string(method), beyond_fraction, boundary_edges_per_1000_faces};
}

// The comparisons at the mesh's vertices (empty: not measured).
struct ErrorFields {
  std::vector<float> distance_to_truth_m;
  std::string truth;  // "analytic" or "mesh"
  std::vector<float> distance_to_scan_m;
  std::vector<uint8_t> invented;
};

// Output `errors`: errors.vtp (every field; active scalars the first) and
// errors.ply: `quality`, a copy of the first field (MeshLab keeps one
// quality per vertex), then every field as `scalar_NAME`, the prefix
// CloudCompare loads as a scalar field NAME without asking (checked with
// CloudCompare 2.11.3: unprefixed extra properties are not loaded). Both
// files hold the mesh's positions, normals and colors, not its uvs and
// tangents: a map is looked at, not textured, and CloudCompare 2.11.3 drops
// every scalar field of a PLY with tangent properties (checked).
Status WriteErrorMaps(StageContext& ctx, const Mesh& evaluated, const ErrorFields& fields) {
  Mesh mesh;
  mesh.origin = evaluated.origin;
  mesh.positions = evaluated.positions;
  mesh.normals = evaluated.normals;
  mesh.colors = evaluated.colors;
  mesh.indices = evaluated.indices;
  std::vector<float> invented_float(fields.invented.begin(), fields.invented.end());
  VtpWriteOptions vtp;
  std::vector<PlyVertexScalar> ply;
  if (!fields.distance_to_truth_m.empty()) {
    vtp.point_arrays.push_back({"distance_to_truth_m", 1, fields.distance_to_truth_m, {}});
    vtp.field_data.push_back({"truth", fields.truth});
  }
  if (!fields.distance_to_scan_m.empty()) {
    vtp.point_arrays.push_back({"distance_to_scan_m", 1, fields.distance_to_scan_m, {}});
    vtp.point_arrays.push_back({"invented", 1, {}, fields.invented});
  }
  const VtpPointArray& first = vtp.point_arrays.front();
  vtp.active_scalars = first.name;
  vtp.field_data.push_back({"quality", first.name});
  vtp.field_data.push_back({"units", "meters (distances); invented: 1 = no scan point explains the vertex"});
  ply.push_back({"quality", first.float32});
  for (const VtpPointArray& a : vtp.point_arrays)
    ply.push_back({"scalar_" + a.name, a.float32.empty() ? std::span<const float>(invented_float) : a.float32});
  const std::string vtp_path = ctx.output_path("errors", "errors.vtp");
  const std::string ply_path = ctx.output_path("errors", "errors.ply");
  if (Status s = WriteVtp(vtp_path, mesh, vtp); !s.ok()) return s.WithContext(kId);
  if (Status s = WritePlyMeshWithScalars(ply_path, mesh, ply); !s.ok()) return s.WithContext(kId);
  ctx.set_output_meta("errors", {{"kind", "error_maps"},
                                 {"quality", first.name},
                                 {"arrays", [&] {
                                    nlohmann::json names = nlohmann::json::array();
                                    for (const VtpPointArray& a : vtp.point_arrays) names.push_back(a.name);
                                    return names;
                                  }()}});
  return Status::Ok();
}

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const int64_t samples, IntegerParam(ctx, kId, "samples", {1}));
  PB_ASSIGN_OR_RETURN(const int64_t seed, IntegerParam(ctx, kId, "seed", {0}));
  PB_ASSIGN_OR_RETURN(const int64_t k, IntegerParam(ctx, kId, "k", {1, 64}));
  PB_ASSIGN_OR_RETURN(const int64_t stray_cluster_points, IntegerParam(ctx, kId, "stray_cluster_points", {0}));
  PB_ASSIGN_OR_RETURN(const double stray_spacing_ratio, NumberParam(ctx, kId, "stray_spacing_ratio"));
  if (!(stray_spacing_ratio >= 1)) return Status::Invalid(std::string(kId) + ": 'stray_spacing_ratio' must be >= 1");
  PB_ASSIGN_OR_RETURN(const double spacing_factor, NumberParam(ctx, kId, "spacing_factor"));
  if (!(spacing_factor > 0)) return Status::Invalid(std::string(kId) + ": 'spacing_factor' must be > 0");
  const bool has_truth = ctx.has_input("truth"), has_points = ctx.has_input("points");
  if (!has_truth && !has_points)
    return Status::Invalid(std::string(kId) + ": connect 'truth' (ground truth) or 'points' (the scan), or both");
  Mesh mesh, truth;
  std::optional<SynthScene> scene;
  ErrorFields fields;
  std::optional<InputPoints> scan;
  {
    PB_PHASE(ctx, "io");
    PB_ASSIGN_OR_RETURN(mesh, ReadMeshInput(ctx, "mesh", 0, 0.1));
    if (has_truth) {
      PB_ASSIGN_OR_RETURN(truth, ReadMeshInput(ctx, "truth", 0.1, 0.2));
      const ArtifactView& truth_input = ctx.input("truth");
      if (truth_input.files.count("scene.json") > 0) {
        PB_ASSIGN_OR_RETURN(scene, ReadSynthScene(truth_input.files.at("scene.json")));
      }
    }
  }
  if (has_points) {
    PB_ASSIGN_OR_RETURN(scan, ReadInputPoints(ctx, kId, 0.2));
  }
  ctx.progress(0.2);
  const double boundary_per_kface =
      mesh.face_count() ? 1000.0 * double(CountBoundaryEdges(mesh)) / double(mesh.face_count()) : 0.0;
  Table table;
  table.columns = {"direction", "samples", "mean_m", "rms_m", "p95_m", "hausdorff_m", "truth",
                   "beyond_fraction", "boundary_edges_per_1000_faces"};
  tbb::task_arena arena(std::max(1, ctx.threads()));
  nlohmann::json meta = {{"kind", "geometry_metrics"}, {"samples", samples}};
  if (has_truth) {
    PB_PHASE(ctx, "compute");
    MeshDistanceOptions options;
    options.samples = static_cast<size_t>(samples);
    options.seed = static_cast<uint64_t>(seed);
    const double end = has_points ? 0.55 : 0.95;
    options.progress = [&ctx, end](double f) { ctx.progress(0.2 + (end - 0.2) * f); };
    Expected<MeshDistanceResult> measured = Status::Internal("not run");
    arena.execute(
        [&] { measured = MeasureMeshDistance(mesh, truth, scene ? &*scene : nullptr, options); });
    if (!measured.ok()) return measured.status().WithContext(kId);
    const MeshDistanceResult& result = *measured;
    const char* forward_method = result.analytic_mesh_to_truth ? "analytic" : "mesh";
    table.rows.push_back(Row("mesh_to_truth", result.mesh_to_truth, forward_method, {}, boundary_per_kface));
    table.rows.push_back(Row("truth_to_mesh", result.truth_to_mesh, "mesh", {}, boundary_per_kface));
    table.rows.push_back(Row("symmetric", result.symmetric, forward_method, {}, boundary_per_kface));
    Expected<std::vector<float>> at_vertices = Status::Internal("not run");
    arena.execute([&] { at_vertices = VertexDistanceToTruth(mesh, truth, scene ? &*scene : nullptr); });
    if (!at_vertices.ok()) return at_vertices.status().WithContext(kId);
    fields.distance_to_truth_m = std::move(*at_vertices);
    fields.truth = forward_method;
    ctx.counter("truth_faces", static_cast<double>(truth.face_count()));
    ctx.counter("mean_m", result.symmetric.mean_m);
    ctx.counter("hausdorff_m", result.symmetric.max_m);
    meta["analytic_truth"] = result.analytic_mesh_to_truth;
  }
  if (has_points) {
    PB_PHASE(ctx, "scan");
    Expected<ScanAgreement> agreement = Status::Internal("not run");
    Expected<VertexScanAgreement> at_vertices = Status::Internal("not run");
    std::vector<uint8_t> strays;
    size_t air_points = 0, seen_through = 0;
    arena.execute([&] {
      // One index of the scan for the spacing and both measures.
      Expected<KnnIndex> index = KnnIndex::Build(scan->cloud.positions);
      if (!index.ok()) {
        agreement = index.status();
        return;
      }
      Expected<SpacingAndStrays> local =
          LocalSpacingAndStrays(*index, {.k = int(k), .max_spacing_ratio = stray_spacing_ratio,
                                         .min_cluster_points = size_t(stray_cluster_points)},
                                &scan->cloud);
      if (!local.ok()) {
        agreement = local.status();
        return;
      }
      strays = std::move(local->stray);
      air_points = local->air;
      seen_through = local->seen_through;
      const std::vector<float>& spacing = local->spacing;
      ScanAgreementOptions options;
      options.strays = strays;
      options.spacing_factor = spacing_factor;
      options.samples = static_cast<size_t>(samples);
      options.seed = static_cast<uint64_t>(seed);
      agreement = MeasureScanAgreement(mesh, scan->cloud, *index, spacing, options);
      if (agreement.ok()) at_vertices = MeasureVertexScanAgreement(mesh, scan->cloud, *index, spacing, options);
    });
    if (!agreement.ok())
      return agreement.status().WithContext(std::string(kId) + ": input 'points' (" + scan->path + ")");
    if (!at_vertices.ok())
      return at_vertices.status().WithContext(std::string(kId) + ": input 'points' (" + scan->path + ")");
    fields.distance_to_scan_m = std::move(at_vertices->distance_to_scan_m);
    fields.invented = std::move(at_vertices->invented);
    ctx.counter("invented_vertices",
                static_cast<double>(std::count(fields.invented.begin(), fields.invented.end(), uint8_t{1})));
    table.rows.push_back(Row("mesh_to_scan", agreement->mesh_to_scan, "scan", agreement->invented_area_fraction,
                             boundary_per_kface));
    table.rows.push_back(Row("scan_to_mesh", agreement->scan_to_mesh, "scan", agreement->missing_fraction,
                             boundary_per_kface));
    ctx.counter("invented_area_fraction", agreement->invented_area_fraction);
    ctx.counter("missing_fraction", agreement->missing_fraction);
    ctx.counter("scan_points", static_cast<double>(scan->cloud.size()));
    ctx.counter("stray_points", static_cast<double>(agreement->stray_points));
    ctx.counter("air_points", static_cast<double>(air_points));
    ctx.counter("seen_through_points", static_cast<double>(seen_through));
    meta["median_spacing_m"] = agreement->median_spacing_m;
    meta["mean_edge_m"] = agreement->mean_edge_m;
  }
  ctx.counter("mesh_faces", static_cast<double>(mesh.face_count()));
  ctx.counter("samples", static_cast<double>(samples));
  ctx.counter("boundary_edges_per_1000_faces", boundary_per_kface);
  {
    PB_PHASE(ctx, "io");
    PB_RETURN_IF_ERROR(WriteTable(ctx.output_path("table", "table.json"), table));
    PB_RETURN_IF_ERROR(WriteErrorMaps(ctx, mesh, fields));
  }
  ctx.set_output_meta("table", std::move(meta));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType GeometryMetricsStage() {
  StageType type;
  type.id = kId;
  // 3: the 'errors' output (per-vertex error maps); 4: local spacing r_k sqrt(pi / k), as mesh.trim
  // (was r_k); 5: UV seams are no boundary edges; 6: stray scan points are not
  // missing surface (`stray_cluster_points`).
  // 7: points in the air are strays (points/strays.h, AirPoints); 8: their
  // plane test allows the scan's noise (AirOptions::noise_tolerance); 9: the
  // points another station saw through are strays (points/seen_through.h).
  type.version = 9;
  type.summary =
      "Mesh accuracy against ground truth (mean, RMS, 95th percentile, Hausdorff) and, without truth, "
      "against the scan: invented area, missing surface, boundary edges";
  type.doc =
      "Samples `samples` points uniformly by area on each mesh (fixed `seed`) and measures "
      "distances both ways, in meters: mesh -> truth (surface that should not be there) and "
      "truth -> mesh (truth that is missing, e.g. holes; one direction alone hides the "
      "other's failures). truth -> mesh uses the exact point-triangle distance to the "
      "evaluated mesh (BVH). When the truth artifact has scene.json (synth.scan), mesh -> "
      "truth uses the analytic scene's signed distance, exact for the true displaced "
      "surface (column `truth` = \"analytic\"); otherwise the distance to the truth mesh.ply "
      "(\"mesh\").\n\n"
      "With `points` (the scan; no truth needed; stages/geometry/mesh/scan_agreement.h): a scan "
      "point's local spacing is r_k sqrt(pi / k), r_k the distance to its `k`-th nearest other point "
      "(an estimate of the distance between neighbouring samples, as mesh.trim's); the invented area is "
      "the fraction of `samples` mesh points (uniform by area, `seed`) farther than "
      "max(`spacing_factor` x local spacing, the mesh's mean edge) from each of their 16 nearest scan "
      "points (surface the scanner never saw); missing surface is the fraction of scan points "
      "(at most `samples`, evenly picked) farther than `spacing_factor` x their local spacing from "
      "the mesh (what the scanner saw and the model lost), stray points (clusters of fewer than "
      "`stray_cluster_points` linked samples, points/strays.h) left out. Connect `truth`, `points` "
      "or both.\n\n"
      "Output table columns: `direction` (mesh_to_truth, truth_to_mesh, symmetric with `truth`; "
      "mesh_to_scan, scan_to_mesh with `points`), `samples`, `mean_m`, `rms_m`, `p95_m`, "
      "`hausdorff_m`, `truth` (analytic, mesh or scan), `beyond_fraction` (mesh_to_scan: the invented "
      "area fraction; scan_to_mesh: the missing fraction; null for the truth rows), "
      "`boundary_edges_per_1000_faces` (edges with one face, per 1000 faces of `mesh`, vertices at one position counting as one so that UV seams are not counted; every row). "
      "The symmetric row has the larger Hausdorff distance, the mean of the two means, and RMS / "
      "95th percentile over both directions' samples pooled. mesh_to_scan distances go to the "
      "nearest scan point.\n\n"
      "Output `errors`: the same comparisons at the mesh's vertices, as error maps to look at "
      "(docs/metrics.md, \"Error maps\"): errors.vtp (VTK XML PolyData for ParaView: absolute "
      "double coordinates, the mesh's normals and colors, and per-vertex arrays `distance_to_truth_m` "
      "with `truth`, `distance_to_scan_m` (to the nearest scan point) and `invented` (1 where the "
      "invented-area rule fires at the vertex) with `points`) and errors.ply (the mesh with "
      "`quality` = the first of those arrays, which MeshLab colors by, and each array as a float "
      "vertex property `scalar_NAME`, which CloudCompare loads as scalar field NAME).\n\n"
      "Counters: `mesh_faces`, `samples`, `boundary_edges_per_1000_faces`; with truth `truth_faces`, "
      "`mean_m`, `hausdorff_m` (symmetric); with points `scan_points`, `stray_points`, `air_points` (of the strays, points in the air), `seen_through_points` (of those, points another station saw through), `invented_area_fraction`, "
      "`missing_fraction`, `invented_vertices`. Phases: `io`, `compute` (truth), `scan` (points).";
  type.params_schema = kSchema;
  type.inputs = {{"mesh", "mesh", "The mesh to evaluate (mesh.ply).", false},
                 {"truth", "mesh",
                  "Ground truth: mesh.ply, plus scene.json for the analytic distance (synth.scan "
                  "output 'truth').",
                  true},
                 {"points", "points", "The scan the mesh was built from (points.ply), for the truth-free figures.",
                  true}};
  type.outputs = {{"table", "table", "Distance statistics and fractions, one row per direction.", false},
                  {"errors", "model",
                   "Per-vertex error maps: errors.vtp (ParaView) and errors.ply with `quality` (MeshLab, "
                   "CloudCompare).",
                   false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
