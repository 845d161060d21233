// uv.unwrap: cuts a mesh into charts and packs them into one square UV atlas
// (stages/geometry/uv/atlas.h).
#include <string>
#include <utility>

#include "engine/stage.h"
#include "stages/mesh_io.h"
#include "stages/geometry/uv/atlas.h"
#include "stages/params.h"
#include "stages/builtin.h"

namespace pb {
namespace {

constexpr const char* kId = "uv.unwrap";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "method": {
      "type": "string",
      "enum": ["charts", "conformal", "per_triangle", "auto"],
      "default": "conformal",
      "description": "auto: charts, or conformal (with a warning) when the planar charts do not fit the atlas (a curved high mesh: a statue's 430,000 faces made 187,935 planar charts, too many for 2048 texels). charts: grow charts of faces with similar normals (Blender Smart UV Project's criterion), project each on its plane, pack their bounding boxes. conformal: charts that follow curved surfaces (grown by normal cone, cut at creases), flattened by least-squares conformal maps, split where they stretch, packed by shape with quarter turns; for scanned organic or carved surfaces. per_triangle: every face its own right-isosceles chart in a grid (MeshLab's trivial parametrization; a baseline)."
    },
    "size": {
      "type": "integer",
      "minimum": 64,
      "maximum": 16384,
      "default": 4096,
      "description": "Width and height of the square texture the atlas is packed for, in texels; gutters are measured at this size."
    },
    "gutter": {
      "type": "integer",
      "minimum": 0,
      "maximum": 64,
      "default": 4,
      "description": "Empty texels between charts and at the atlas border, for texture dilation and mipmapping."
    },
    "max_angle_deg": {
      "type": "number",
      "exclusiveMinimum": 0,
      "exclusiveMaximum": 90,
      "default": 66,
      "description": "charts: a face joins a chart only if its normal is within this angle of the chart's mean normal (Blender's Smart UV Project angle limit, 66 by default)."
    },
    "cone_deg": {
      "type": "number",
      "exclusiveMinimum": 0,
      "exclusiveMaximum": 90,
      "default": 45,
      "description": "conformal: a chart grows over faces whose normals are within this angle of its mean normal, and never across an edge folding more than this (a crease)."
    },
    "max_chart_stretch": {
      "type": "number",
      "exclusiveMinimum": 1,
      "default": 1.03,
      "description": "conformal: a chart whose conformal map has an L2 texture stretch (Sander et al. 2001, 1 = no distortion) above this is split in two."
    },
    "max_stretch": {
      "type": "number",
      "minimum": 1,
      "default": 1.25,
      "description": "charts: a face joins a chart only if the chart's planar projection stretches it at most this much (1/cos of its angle to the chart's normal; 1.25 = 36.9 degrees). The tighter of this and max_angle_deg applies; a large value leaves max_angle_deg alone, as Blender does."
    }
  }
})";

Status Run(StageContext& ctx) {
  UnwrapOptions options;
  PB_ASSIGN_OR_RETURN(const std::string method, StringParam(ctx, kId, "method"));
  if (method == "charts" || method == "auto") {
    options.method = UnwrapMethod::kCharts;
  } else if (method == "conformal") {
    options.method = UnwrapMethod::kConformal;
  } else if (method == "per_triangle") {
    options.method = UnwrapMethod::kPerTriangle;
  } else {
    return Status::Invalid(std::string(kId) + ": parameter 'method' must be 'charts', " +
                           "'conformal', 'per_triangle' or 'auto', got '" + method + "'");
  }
  PB_ASSIGN_OR_RETURN(const int64_t size, IntegerParam(ctx, kId, "size", {64, 16384}));
  PB_ASSIGN_OR_RETURN(const int64_t gutter, IntegerParam(ctx, kId, "gutter", {0, 64}));
  PB_ASSIGN_OR_RETURN(options.max_angle_deg, NumberParam(ctx, kId, "max_angle_deg"));
  PB_ASSIGN_OR_RETURN(options.max_stretch, NumberParam(ctx, kId, "max_stretch"));
  PB_ASSIGN_OR_RETURN(options.cone_deg, NumberParam(ctx, kId, "cone_deg"));
  PB_ASSIGN_OR_RETURN(options.max_chart_stretch, NumberParam(ctx, kId, "max_chart_stretch"));
  if (!(options.cone_deg > 0 && options.cone_deg < 90)) {
    return Status::Invalid(std::string(kId) + ": parameter 'cone_deg' must be in (0, 90), got " +
                           std::to_string(options.cone_deg));
  }
  if (!(options.max_chart_stretch > 1)) {
    return Status::Invalid(std::string(kId) +
                           ": parameter 'max_chart_stretch' must be > 1, got " +
                           std::to_string(options.max_chart_stretch));
  }
  if (!(options.max_angle_deg > 0 && options.max_angle_deg < 90)) {
    return Status::Invalid(std::string(kId) +
                           ": parameter 'max_angle_deg' must be in (0, 90), got " +
                           std::to_string(options.max_angle_deg));
  }
  if (!(options.max_stretch >= 1)) {
    return Status::Invalid(std::string(kId) + ": parameter 'max_stretch' must be >= 1, got " +
                           std::to_string(options.max_stretch));
  }
  options.size_texels = static_cast<int>(size);
  options.gutter_texels = static_cast<int>(gutter);
  options.threads = ctx.threads();

  PB_ASSIGN_OR_RETURN(InputMesh input, ReadInputMesh(ctx, kId, 0.2));
  const Mesh& mesh = input.mesh;
  double reported = 0.2;  // the progress so far: a fallback goes on from it
  options.progress = [&ctx, &reported](double fraction) {
    reported = 0.2 + 0.7 * fraction;
    ctx.progress(reported);
  };
  AtlasReport report;
  Mesh output;
  std::string used = method == "auto" ? "charts" : method;
  {
    PB_PHASE(ctx, "compute");
    auto unwrapped = UnwrapMesh(mesh, options, &report);
    if (!unwrapped.ok() && method == "auto") {
      // Planar charts fragment on curved surfaces; conformal charts follow
      // them, far fewer.
      const Status planar = unwrapped.status();
      options.method = UnwrapMethod::kConformal;
      options.progress = [&ctx, from = reported](double fraction) { ctx.progress(from + (0.9 - from) * fraction); };
      report = AtlasReport();
      unwrapped = UnwrapMesh(mesh, options, &report);
      if (!unwrapped.ok()) {
        return Status::Invalid(std::string(kId) + ": method auto: planar charts failed (" + planar.message() +
                               "), and conformal charts failed too (" + unwrapped.status().message() + ")")
            .WithContext(input.path);
      }
      used = "conformal";
      ctx.warning(std::string(kId) + ": planar charts failed (" + planar.message() + "); unwrapped with " +
                  std::to_string(report.charts) + " conformal charts instead");
    }
    if (!unwrapped.ok()) return unwrapped.status().WithContext(input.path);
    output = std::move(*unwrapped);
  }
  ctx.counter("charts", static_cast<double>(report.charts));
  ctx.counter("coverage", report.coverage);
  ctx.counter("stretch_l2", report.stretch_l2);
  ctx.counter("stretch_linf", report.stretch_linf);
  ctx.counter("seam_length_m", report.seam_length_m);
  ctx.counter("vertices_out", static_cast<double>(output.vertex_count()));
  ctx.counter("texels_per_meter", report.texels_per_meter);
  if (method == "auto") ctx.counter("conformal_fallback", used == "conformal" ? 1.0 : 0.0);
  PB_RETURN_IF_ERROR(WriteOutputMesh(
      ctx, output,
      InputMeshMetaWith(ctx, output,
              {{"uv",
                {{"method", used},
                 {"method_asked", method},
                 {"size", size},
                 {"gutter", gutter},
                 {"max_angle_deg", options.max_angle_deg},
                 {"max_stretch", options.max_stretch},
                 {"cone_deg", options.cone_deg},
                 {"max_chart_stretch", options.max_chart_stretch},
                 {"charts", report.charts},
                 {"coverage", report.coverage},
                 {"stretch_l2", report.stretch_l2},
                 {"stretch_linf", report.stretch_linf},
                 {"seam_length_m", report.seam_length_m},
                 {"texels_per_meter", report.texels_per_meter}}}})));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType UnwrapStage() {
  StageType type;
  type.id = kId;
  type.version = 9;  // 9: method auto, meta method_asked;
                     // 8: LSCM solved in complex form (same charts, UVs within rounding);
                     // 7: the scale search's second pair aimed lower when the first
                     // pair's fitting trial is nearly full (bunny 10^5: 4 trials, not 6);
                     // 6: LSCM ordered by vertices (same charts and packing, UVs within
                     // a float ulp); 5: few irregular charts also try 30/15-degree turns
  type.summary =
      "UV atlas: conformal charts that follow the surface (or planar ones), one square texture";
  type.doc =
      "Gives the mesh per-vertex UVs in [0,1]^2 for one `size` x `size` texture. `charts` "
      "grows charts across manifold edges while face normals stay within "
      "`max_angle_deg` of the chart's mean normal and within `max_stretch` of planar "
      "projection, projects each chart on its plane, splits charts whose projection folds or "
      "overlaps, rotates each to its minimal bounding rectangle and packs all at one texel "
      "density (skyline packer, scale found by bisection) with `gutter` texels between charts "
      "and at the border. `conformal` (default) grows charts by normal cone (`cone_deg`) over "
      "smooth surface, cuts them at creases, flattens each by a least-squares conformal map, "
      "splits any whose L2 stretch exceeds `max_chart_stretch` (or that folds or overlaps "
      "itself), and packs the chart shapes (not their boxes) with quarter turns at one texel "
      "density. `per_triangle` gives every face its own cell (MeshLab's trivial "
      "parametrization). `auto` is `charts`, or `conformal` with a warning when the planar "
      "charts cannot be packed (on a curved high mesh they fragment into too many for the "
      "atlas). Vertices are split along seams, copying normals and colors; faces "
      "keep their order and winding and are counter-clockwise in UV (no mirrored charts). "
      "Non-manifold edges are treated as seams, so uncleaned meshes work too. Deterministic "
      "whatever the thread count. Fails with a clear message when the charts cannot fit at "
      "`size` with `gutter`.\n\n"
      "Counters: `charts`, `coverage` (fraction of the atlas covered by triangles), "
      "`stretch_l2` and `stretch_linf` (Sander et al. 2001 texture stretch, normalized so 1 "
      "is no distortion), `seam_length_m`, `vertices_out`, `texels_per_meter`, "
      "`conformal_fallback` (auto: 1 when the conformal charts were used). The output "
      "meta's `uv` object has the parameters and these figures (`method` the method used, "
      "`method_asked` the one asked).";
  type.params_schema = kSchema;
  type.inputs = {
      {"mesh", "mesh", "The mesh to unwrap (mesh.ply); existing UVs are replaced.", false}};
  type.outputs = {
      {"mesh", "mesh", "The same surface with UVs, vertices split at seams (mesh.ply).", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
