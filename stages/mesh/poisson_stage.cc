// mesh.poisson: screened Poisson reconstruction from oriented points
// (stages/geometry/mesh/poisson.h), optionally trimmed by density.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "engine/stage.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/mesh/poisson.h"
#include "stages/builtin.h"
#include "stages/params.h"
#include "stages/points_io.h"

namespace pb {
namespace {

constexpr const char* kId = "mesh.poisson";
// Without depth or target_faces (the description of `depth` says so).
constexpr int kDefaultDepth = 8;

// The depth probed to calibrate target_faces: cheap (a 64^3 grid) yet deep
// enough for the surface to be resolved on building-sized scans.
constexpr int kProbeDepth = 6;

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "depth": {
      "type": "integer",
      "minimum": 3,
      "maximum": 14,
      "description": "Octree depth: the solve grid has at most 2^depth cells along the scan's largest extent. Each level adds about 4x the faces, time and memory. The paper used 8 for low meshes and 10 for high ones; keep the finest cell larger than the scan's noise (else the noise band fills with small closed bubbles). Default 8 when `target_faces` is not given; give one of the two."
    },
    "target_faces": {
      "type": "integer",
      "minimum": 100,
      "description": "Pick the depth whose face count lands nearest this (in ratio) instead of giving `depth`: a depth-6 probe run and the points' cell occupancy per level predict the faces per depth. The chosen depth is reported in the output's meta and counters. Depths are ~4x apart in faces, so follow with mesh.decimate for an exact budget."
    },
    "trim": {
      "type": "number",
      "minimum": 0,
      "maximum": 0.5,
      "default": 0,
      "description": "Density-quantile trimming: remove the vertices whose Poisson density (how well the points support them) is below this quantile of all densities, with their faces. Poisson closes every hole, open doors and windows included; 0.01-0.02 removes such false surfaces on the synthetic scenes while 0.05 and above also cut sparse real surface (docs/poisson.md). 0 keeps the closed surface. The quantile is global, so on one-station real scans it cuts pin-holes in distant surface and leaves membranes across unscanned space: the shipped workflows keep 0 here and follow with mesh.trim (docs/mesh-real-scans.md)."
    },
    "scale": {
      "type": "number",
      "minimum": 1,
      "maximum": 4,
      "default": 1.1,
      "description": "Ratio of the reconstruction cube to the points' bounding cube (Open3D/PoissonRecon `scale`)."
    },
    "linear_fit": {
      "type": "boolean",
      "default": false,
      "description": "Place iso-surface vertices by linear interpolation of the implicit function (PoissonRecon --linearFit) instead of at the cell-edge midpoint of the sign change."
    },
    "implementation": {
      "type": "string",
      "enum": ["open3d", "pcl"],
      "default": "open3d",
      "description": "Whose solver runs: 'open3d' (Open3D 0.16, pointbake-poisson-open3d.so) or 'pcl' (PCL 1.13's pcl::Poisson, an older PoissonRecon, point weight 4 and samples per node 1.5, pointbake-pcl.so). PCL's gives no densities (so `trim` must be 0: use mesh.trim) and no vertex attributes: its normals and colors are those of the nearest 4 points, distance-weighted. docs/poisson.md and docs/implementations.md compare them."
    },
    "threads": {
      "type": "integer",
      "minimum": 0,
      "default": 1,
      "description": "Threads for the solver. 1 (the default) gives the same bytes on every run; with more, Open3D's parallel sums move a few vertices in the last digits from run to run (and the speed-up is small: 6.7 s -> 6.0 s with 2 threads on 10^6 points at depth 8). 0 takes the engine's --threads."
    }
  },
  "not": {"required": ["depth", "target_faces"]}
})";

Status Run(StageContext& ctx) {
  const auto given = [&ctx](const char* name) {
    return ctx.params().contains(name) && !ctx.params()[name].is_null();
  };
  const bool has_depth = given("depth");
  const bool has_target = given("target_faces");
  if (has_depth && has_target) {
    return Status::Invalid(std::string(kId) + ": give 'depth' or 'target_faces', not both");
  }
  PoissonOptions options;
  PB_ASSIGN_OR_RETURN(options.scale, NumberParam(ctx, kId, "scale"));
  PB_ASSIGN_OR_RETURN(options.linear_fit, BoolParam(ctx, kId, "linear_fit"));
  PB_ASSIGN_OR_RETURN(const int64_t threads, IntegerParam(ctx, kId, "threads", {0}));
  options.threads = threads > 0 ? static_cast<int>(threads) : ctx.threads();
  PB_ASSIGN_OR_RETURN(const std::string implementation, StringParam(ctx, kId, "implementation"));
  if (implementation == "pcl") {
    options.implementation = PoissonImplementation::kPcl;
  } else if (implementation != "open3d") {
    return Status::Invalid(std::string(kId) + ": parameter 'implementation' must be 'open3d' or "
                           "'pcl', got '" + implementation + "'");
  }
  PB_ASSIGN_OR_RETURN(const double trim, NumberParam(ctx, kId, "trim"));
  if (implementation == "pcl" && trim > 0) {
    return Status::Invalid(std::string(kId) + ": 'trim' needs the solver's densities, which "
                           "implementation 'pcl' does not give; set trim: 0 and follow with "
                           "mesh.trim");
  }
  if (implementation == "pcl" && options.linear_fit) {
    return Status::Invalid(std::string(kId) + ": 'linear_fit' is an Open3D option; "
                           "implementation 'pcl' has none");
  }
  if (!(trim >= 0 && trim <= 0.5)) {
    return Status::Invalid(std::string(kId) + ": parameter 'trim' must be in [0, 0.5], got " +
                           std::to_string(trim));
  }
  int64_t target = 0;
  if (has_target) {
    PB_ASSIGN_OR_RETURN(target, IntegerParam(ctx, kId, "target_faces", {100}));
  } else if (has_depth) {
    PB_ASSIGN_OR_RETURN(const int64_t depth,
                        IntegerParam(ctx, kId, "depth", {kPoissonMinDepth, kPoissonMaxDepth}));
    options.depth = static_cast<int>(depth);
  } else {
    // Not a schema default: one there would always clash with target_faces.
    options.depth = kDefaultDepth;
  }

  PB_ASSIGN_OR_RETURN(InputPoints input, ReadInputPoints(ctx, kId, 0.1));
  const PointCloud& cloud = input.cloud;

  nlohmann::json poisson_meta = {{"implementation", implementation == "pcl"
                                                        ? "PCL 1.13 (pcl::Poisson)"
                                                        : "Open3D 0.16 (PoissonRecon)"},
                                 {"scale", options.scale},
                                 {"linear_fit", options.linear_fit},
                                 {"trim", trim}};
  if (has_target) {
    PB_PHASE(ctx, "compute");
    PoissonOptions probe = options;
    probe.depth = kProbeDepth;
    auto probed = ReconstructPoisson(cloud, probe);
    if (!probed.ok()) return probed.status().WithContext(input.path);
    const std::vector<uint64_t> occupied =
        OccupiedCellsPerDepth(cloud, options.scale, kPoissonMaxDepth);
    const DepthChoice choice = ChooseDepthForFaces(static_cast<uint64_t>(target), kProbeDepth,
                                                   probed->mesh.face_count(), occupied);
    options.depth = choice.depth;
    poisson_meta["target_faces"] = target;
    poisson_meta["predicted_faces"] = static_cast<uint64_t>(choice.predicted_faces);
    poisson_meta["probe"] = {{"depth", kProbeDepth}, {"faces", probed->mesh.face_count()}};
    std::fprintf(stderr, "%s: target_faces %lld -> depth %d (predicted %.0f faces)\n", kId,
                 static_cast<long long>(target), choice.depth, choice.predicted_faces);
    ctx.progress(0.2);
  }

  // The finest cell against the scan's spacing: finer cells resolve noise,
  // not surface (closed bubbles, non-manifold edges).
  const std::array<double, 3> extent = BoundsOf(cloud.positions).extent_m();
  const double cell_m =
      std::max({extent[0], extent[1], extent[2]}) * options.scale / std::ldexp(1.0, options.depth);
  poisson_meta["cell_m"] = cell_m;
  if (const double spacing = InputPointsSpacing(ctx); spacing > 0) {
    if (cell_m < spacing) {
      char text[320];
      std::snprintf(text, sizeof text,
                    "depth %d makes %.1f mm cells, finer than the points' spacing %.1f mm: "
                    "expect small closed bubbles and non-manifold edges (mesh.clean removes "
                    "them); a lower depth fits this scan better",
                    options.depth, cell_m * 1e3, spacing * 1e3);
      ctx.warning(text);
    }
  }

  PoissonOutput out;
  {
    PB_PHASE(ctx, "compute");
    auto result = ReconstructPoisson(cloud, options);
    if (!result.ok()) return result.status().WithContext(input.path);
    out = std::move(*result);
  }
  ctx.progress(0.85);
  const size_t faces_solved = out.mesh.face_count();
  TrimReport trimmed;
  Mesh mesh = TrimByDensity(std::move(out.mesh), out.densities, trim, &trimmed);
  out = PoissonOutput();

  ctx.counter("depth", options.depth);
  ctx.counter("faces_solved", static_cast<double>(faces_solved));
  ctx.counter("faces_out", static_cast<double>(mesh.face_count()));
  {
    PB_PHASE(ctx, "io");
    PB_RETURN_IF_ERROR(WritePlyMesh(ctx.output_path("mesh", "mesh.ply"), mesh));
  }
  poisson_meta.update({{"depth", options.depth},
                       {"faces_solved", faces_solved},
                       {"density_threshold", trimmed.threshold},
                       {"faces_trimmed", trimmed.faces_removed}});
  nlohmann::json meta = nlohmann::json::object();
  const nlohmann::json& points_meta = ctx.input("points").meta;
  for (const char* key : {"spacing_m", "scene", "source"}) {
    if (points_meta.is_object() && points_meta.contains(key)) meta[key] = points_meta[key];
  }
  meta.update({{"origin", mesh.origin},
               {"vertices", mesh.vertex_count()},
               {"faces", mesh.face_count()},
               {"has_normals", mesh.has_normals()},
               {"has_colors", mesh.has_colors()},
               {"poisson", poisson_meta}});
  ctx.set_output_meta("mesh", std::move(meta));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType PoissonStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Screened Poisson surface reconstruction from oriented points (Open3D 0.16 or PCL)";
  type.doc =
      "Screened Poisson reconstruction (Kazhdan & Hoppe 2013) through Open3D 0.16, chosen over "
      "PCL's with the evidence in docs/poisson.md. Needs oriented normals (points.normals). "
      "Give `depth` (default 8) or `target_faces`; the output has per-vertex normals and, when "
      "the points have colors, colors, both interpolated from the points, and triangles wound "
      "counter-clockwise seen from the side the normals face, in a canonical order. `trim` "
      "removes the surface the points do not support (closed doors and windows). One thread "
      "(the default) makes the output reproducible to the byte. Open3D 0.16 fixes the screening "
      "weight (2) and samples per node (1.5); its C++ API does not take them. At depths whose "
      "cell is finer than the scan's noise the output fills with small closed bubbles and "
      "non-manifold edges: follow with mesh.clean before UV unwrapping.\n\n"
      "Counters: `depth`, `faces_solved` (before trimming), `faces_out`. The solver runs in a "
      "module, pointbake-poisson-open3d.so, loaded on first use; `implementation: pcl` runs "
      "PCL's pcl::Poisson from pointbake-pcl.so instead, for campaigns that compare "
      "implementations.";
  type.params_schema = kSchema;
  type.inputs = {{"points", "points", "Oriented points (points.ply with normals).", false}};
  type.outputs = {{"mesh", "mesh", "The reconstructed mesh (mesh.ply).", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
