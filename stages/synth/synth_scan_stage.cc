// synth.scan: a simulated laser scan of an analytic room plus its ground
// truth (stages/geometry/synth/scene.h, stages/geometry/synth/scanner.h).
#include <tbb/task_arena.h>

#include <cmath>

#include "stages/geometry/io/ply.h"
#include "stages/geometry/synth/scanner.h"
#include "stages/geometry/synth/scene.h"
#include "stages/params.h"
#include "stages/builtin.h"

namespace pb {
namespace {

constexpr const char* kId = "synth.scan";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "preset": {
      "enum": ["room", "tower", "vault", "facade", "sculpture"],
      "default": "room",
      "description": "Scene: 'room' (6 x 4.5 x 3.2 m, brick walls, stone floor, a door and two windows), 'tower' (round, radius 3 m, height 6 m, a door and slit windows), 'vault' (7 x 4.5 m room with a barrel-vaulted ceiling, crown at 4.85 m); open scenes: 'facade' (two brick facades meeting in a corner on a paved yard, open to the sky and the sides, with a pump, a bench and a fluted column; stations on an arc in front, at most 5: scan it with 1) or 'sculpture' (a carved, bumpy marble blob on a plinth; stations on a ring around it)."
    },
    "points": {
      "type": "integer",
      "minimum": 1000,
      "default": 2000000,
      "description": "Target number of points (valid returns of all stations); the angular step is chosen to land within a few percent of it. About 10^7 gives the ~2 mm spacing of the paper's castle scans."
    },
    "seed": {
      "type": "integer",
      "minimum": 0,
      "default": 1,
      "description": "Seed of the scene's colors and floor relief and of the scanner noise. Same seed, same bytes."
    },
    "noise_mm": {
      "type": "number",
      "minimum": 0,
      "default": 2,
      "description": "Range noise: standard deviation along the ray, millimeters."
    },
    "color_noise": {
      "type": "number",
      "minimum": 0,
      "maximum": 1,
      "default": 0.02,
      "description": "Color sensor noise: standard deviation per channel, as a fraction of full scale."
    },
    "stations": {
      "type": "integer",
      "minimum": 1,
      "maximum": 16,
      "default": 3,
      "description": "Number of scanner stations, placed deterministically inside the room at about 1.5 m height (open scenes: on their arc or ring)."
    },
    "size_m": {
      "type": "array",
      "items": {"type": "number", "exclusiveMinimum": 0},
      "minItems": 3,
      "maxItems": 3,
      "description": "Optional [width, depth, height] in meters overriding the preset's (tower: width = depth = diameter; vault: height is the crown; not for the open scenes facade and sculpture)."
    },
    "truth_cell_mm": {
      "type": "number",
      "exclusiveMinimum": 0,
      "default": 10,
      "description": "Grid cell of the ground-truth mesh (output 'truth'), millimeters."
    }
  }
})";

// A whole number; its range is checked with the others in Run.
Expected<int64_t> WholeNumberParam(const StageContext& ctx, const char* name) {
  PB_ASSIGN_OR_RETURN(const double value, NumberParam(ctx, kId, name));
  if (value != std::floor(value)) {
    return Status::Invalid(std::string(kId) + ": parameter '" + name + "' must be an integer");
  }
  return static_cast<int64_t>(value);
}

Expected<std::optional<Vec3>> SizeParam(const StageContext& ctx) {
  const nlohmann::json& params = ctx.params();
  if (!params.is_object() || !params.contains("size_m") || params["size_m"].is_null()) {
    return std::optional<Vec3>();
  }
  const nlohmann::json& size = params["size_m"];
  if (!size.is_array() || size.size() != 3) {
    return Status::Invalid(std::string(kId) + ": parameter 'size_m' must be [width, depth, height], got " +
                           size.dump());
  }
  Vec3 out;
  for (int a = 0; a < 3; ++a) {
    if (!size[a].is_number() || !(size[a].get<double>() > 0)) {
      return Status::Invalid(std::string(kId) + ": parameter 'size_m' must hold 3 positive numbers, got " +
                             size.dump());
    }
    out[a] = size[a].get<double>();
  }
  return std::optional<Vec3>(out);
}

Status WriteSceneJson(const std::string& path, const SynthScene& scene) {
  return Env::Default()->WriteFileAtomic(path, ToJson(scene).dump(2) + "\n");
}

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const std::string preset, StringParam(ctx, kId, "preset"));
  PB_ASSIGN_OR_RETURN(const int64_t points, WholeNumberParam(ctx, "points"));
  PB_ASSIGN_OR_RETURN(const int64_t seed, WholeNumberParam(ctx, "seed"));
  PB_ASSIGN_OR_RETURN(const double noise_mm, NumberParam(ctx, kId, "noise_mm"));
  PB_ASSIGN_OR_RETURN(const double color_noise, NumberParam(ctx, kId, "color_noise"));
  PB_ASSIGN_OR_RETURN(const int64_t stations, WholeNumberParam(ctx, "stations"));
  PB_ASSIGN_OR_RETURN(const double truth_cell_mm, NumberParam(ctx, kId, "truth_cell_mm"));
  PB_ASSIGN_OR_RETURN(const std::optional<Vec3> size_m, SizeParam(ctx));
  if (points < 1000 || seed < 0 || stations < 1 || stations > 16 || !(noise_mm >= 0) ||
      !(color_noise >= 0 && color_noise <= 1) || !(truth_cell_mm > 0)) {
    return Status::Invalid(std::string(kId) +
                           ": parameters out of range (points >= 1000, seed >= 0, stations 1..16, "
                           "noise_mm >= 0, color_noise in [0, 1], truth_cell_mm > 0)");
  }
  Expected<SynthScene> made = MakeSynthScene(preset, static_cast<uint64_t>(seed), size_m);
  if (!made.ok()) return made.status().WithContext(kId);
  const SynthScene& scene = made.value();

  // The scanner and the truth mesh use TBB; keep them within --threads.
  tbb::task_arena arena(std::max(1, ctx.threads()));
  SynthScanResult scan;
  Status status;
  {
    PB_PHASE(ctx, "scan");
    SynthScanOptions options;
    options.target_points = static_cast<uint64_t>(points);
    options.seed = static_cast<uint64_t>(seed);
    options.stations = static_cast<int>(stations);
    options.noise_m = noise_mm / 1000;
    options.color_noise = color_noise;
    // Progress from the calling thread only (the scanner reports between its
    // parallel sweeps).
    options.progress = [&ctx](double f) { ctx.progress(0.6 * f); };
    arena.execute([&] {
      Expected<SynthScanResult> result = SimulateScan(scene, options);
      if (result.ok()) {
        scan = std::move(result).value();
      } else {
        status = result.status();
      }
    });
    if (!status.ok()) return status.WithContext(kId);
  }
  Mesh truth;
  {
    PB_PHASE(ctx, "truth");
    arena.execute([&] { truth = SynthTruthMesh(scene, truth_cell_mm / 1000); });
    ctx.progress(0.75);
  }
  ctx.counter("points", static_cast<double>(scan.cloud.size()));
  ctx.counter("stations", static_cast<double>(stations));
  ctx.counter("truth_faces", static_cast<double>(truth.face_count()));
  {
    PB_PHASE(ctx, "io");
    PB_RETURN_IF_ERROR(WritePlyPoints(ctx.output_path("points", "points.ply"), scan.cloud));
    ctx.progress(0.9);
    PB_RETURN_IF_ERROR(WritePlyMesh(ctx.output_path("truth", "mesh.ply"), truth));
    PB_RETURN_IF_ERROR(WriteSceneJson(ctx.output_path("truth", "scene.json"), scene));
  }
  ctx.set_output_meta("points", {{"origin", scan.cloud.origin},
                                 {"points", scan.cloud.size()},
                                 {"has_normals", false},
                                 {"has_colors", true},
                                 {"spacing_m", scan.median_spacing_m},
                                 {"stations", stations},
                                 {"preset", preset},
                                 {"angular_step_deg", scan.angular_step_rad * 180 / 3.141592653589793}});
  ctx.set_output_meta("truth", {{"kind", "synthetic_truth"},
                                {"preset", preset},
                                {"faces", truth.face_count()},
                                {"cell_m", truth_cell_mm / 1000}});
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType SynthScanStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Simulated laser scan of a synthetic brick room or open scene, with ground truth";
  type.doc =
      "Builds an analytic scene (preset room, tower or vault: brick walls in running bond with "
      "recessed mortar joints and per-brick colors, an uneven stone floor, plaster ceiling, "
      "doors and windows) and scans it with a simulated terrestrial laser scanner: `stations` "
      "positions about 1.5 m above the floor, a regular azimuth/elevation sweep whose step is "
      "chosen so that the valid returns total about `points`, Gaussian range noise `noise_mm` "
      "along each ray, colors from the true albedo plus `color_noise`. Rays through openings "
      "return nothing. The open presets `facade` (scanned from one side: unscanned space behind "
      "and under objects and beyond the open sides) and `sculpture` (curved, carved relief) are "
      "built from analytic elements (stages/geometry/synth/objects.h). Deterministic: the same parameters give the same bytes for any thread "
      "count.\n\n"
      "Outputs: `points` (points.ply with colors, station ids and station positions; meta "
      "`spacing_m` = median in-surface nearest-neighbor distance, `stations`, `preset`) and "
      "`truth` (mesh.ply: the true surface at `truth_cell_mm` with per-vertex albedo and "
      "normals; scene.json: the full analytic description, readable with ReadSynthScene, to "
      "evaluate albedo and distance exactly).\n\n"
      "Counters: `points`, `stations`, `truth_faces`. Phases: `scan`, `truth`, `io`.";
  type.params_schema = kSchema;
  type.outputs = {{"points", "points", "The simulated scan.", false},
                  {"truth", "mesh", "Ground-truth mesh (mesh.ply) and scene description (scene.json).", false}};
  // The cloud (17 bytes a point) dominates; the default 2e6 points plus the
  // truth mesh of a room stays under ~200 MB.
  type.declared_peak_bytes = 256ull << 20;
  type.run = &Run;
  return type;
}

}  // namespace pb
