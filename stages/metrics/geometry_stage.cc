// metrics.geometry: distance between a mesh and the ground truth, sampled both
// ways (stages/geometry/mesh/distance.h), written as a table.
#include "stages/builtin.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <optional>

#include "stages/geometry/mesh/distance.h"
#include "stages/geometry/io/ply.h"
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

std::vector<TableValue> Row(const char* direction, const DistanceStats& s, const char* method) {
  return {
      std::string(direction), static_cast<int64_t>(s.samples), s.mean_m, s.rms_m, s.p95_m, s.max_m,
      std::string(method)};
}

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const int64_t samples, IntegerParam(ctx, kId, "samples", {1}));
  PB_ASSIGN_OR_RETURN(const int64_t seed, IntegerParam(ctx, kId, "seed", {0}));
  Mesh mesh, truth;
  std::optional<SynthScene> scene;
  {
    PB_PHASE(ctx, "io");
    PB_ASSIGN_OR_RETURN(mesh, ReadMeshInput(ctx, "mesh", 0, 0.1));
    PB_ASSIGN_OR_RETURN(truth, ReadMeshInput(ctx, "truth", 0.1, 0.2));
    const ArtifactView& truth_input = ctx.input("truth");
    if (truth_input.files.count("scene.json") > 0) {
      PB_ASSIGN_OR_RETURN(scene, ReadSynthScene(truth_input.files.at("scene.json")));
    }
  }
  ctx.progress(0.2);
  MeshDistanceResult result;
  {
    PB_PHASE(ctx, "compute");
    MeshDistanceOptions options;
    options.samples = static_cast<size_t>(samples);
    options.seed = static_cast<uint64_t>(seed);
    options.progress = [&ctx](double f) { ctx.progress(0.2 + 0.75 * f); };
    tbb::task_arena arena(std::max(1, ctx.threads()));
    Expected<MeshDistanceResult> measured = Status::Internal("not run");
    arena.execute(
        [&] { measured = MeasureMeshDistance(mesh, truth, scene ? &*scene : nullptr, options); });
    if (!measured.ok()) return measured.status().WithContext(kId);
    result = std::move(measured).value();
  }
  const char* forward_method = result.analytic_mesh_to_truth ? "analytic" : "mesh";
  Table table;
  table.columns = {"direction", "samples", "mean_m", "rms_m", "p95_m", "hausdorff_m", "truth"};
  table.rows = {Row("mesh_to_truth", result.mesh_to_truth, forward_method),
                Row("truth_to_mesh", result.truth_to_mesh, "mesh"),
                Row("symmetric", result.symmetric, forward_method)};
  ctx.counter("mesh_faces", static_cast<double>(mesh.face_count()));
  ctx.counter("truth_faces", static_cast<double>(truth.face_count()));
  ctx.counter("samples", static_cast<double>(samples));
  ctx.counter("mean_m", result.symmetric.mean_m);
  ctx.counter("hausdorff_m", result.symmetric.max_m);
  {
    PB_PHASE(ctx, "io");
    PB_RETURN_IF_ERROR(WriteTable(ctx.output_path("table", "table.json"), table));
  }
  ctx.set_output_meta("table", {{"kind", "geometry_metrics"},
                                {"samples", samples},
                                {"analytic_truth", result.analytic_mesh_to_truth}});
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType GeometryMetricsStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Mesh accuracy against ground truth: mean, RMS, 95th percentile, Hausdorff";
  type.doc =
      "Samples `samples` points uniformly by area on each mesh (fixed `seed`) and measures "
      "distances both ways, in meters: mesh -> truth (surface that should not be there) and "
      "truth -> mesh (truth that is missing, e.g. holes; one direction alone hides the "
      "other's failures). truth -> mesh uses the exact point-triangle distance to the "
      "evaluated mesh (BVH). When the truth artifact has scene.json (synth.scan), mesh -> "
      "truth uses the analytic scene's signed distance, exact for the true displaced "
      "surface (column `truth` = \"analytic\"); otherwise the distance to the truth mesh.ply "
      "(\"mesh\").\n\n"
      "Output table columns: `direction` (mesh_to_truth, truth_to_mesh, symmetric), "
      "`samples`, `mean_m`, `rms_m`, `p95_m`, `hausdorff_m`, `truth`. The symmetric row has "
      "the larger Hausdorff distance, the mean of the two means, and RMS / 95th percentile "
      "over both directions' samples pooled.\n\n"
      "Counters: `mesh_faces`, `truth_faces`, `samples`, `mean_m`, `hausdorff_m` "
      "(symmetric). Phases: `io`, `compute`.";
  type.params_schema = kSchema;
  type.inputs = {{"mesh", "mesh", "The mesh to evaluate (mesh.ply).", false},
                 {"truth", "mesh",
                  "Ground truth: mesh.ply, plus scene.json for the analytic distance (synth.scan "
                  "output 'truth').",
                  false}};
  type.outputs = {{"table", "table", "Distance statistics, one row per direction.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
