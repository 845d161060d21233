// mesh.decimate: quadric edge collapse to a face budget
// (stages/geometry/mesh/decimate.h).
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>

#include "engine/stage.h"
#include "stages/geometry/mesh/decimate.h"
#include "stages/geometry/mesh/sight.h"
#include "stages/mesh_io.h"
#include "stages/params.h"
#include "stages/points_io.h"

namespace pb {
namespace {

constexpr const char* kId = "mesh.decimate";

// Exactly one of target_faces and ratio: a budget in faces suits a device
// profile, a ratio suits inputs of unknown size.
constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "target_faces": {
      "type": "integer",
      "minimum": 1,
      "description": "Face budget of the output: collapse edges until at most this many triangles remain. Give this or `ratio`, not both."
    },
    "ratio": {
      "type": "number",
      "exclusiveMinimum": 0,
      "maximum": 1,
      "description": "Face budget as a fraction of the input's faces, e.g. 0.1 keeps a tenth. Give this or `target_faces`, not both."
    },
    "boundary_weight": {
      "type": "number",
      "minimum": 0,
      "default": 1000,
      "description": "How strongly open borders (holes, openings, sheet edges) keep their shape, relative to the surface error; 0 lets them erode."
    },
    "boundary_tolerance": {
      "type": "number",
      "minimum": 0,
      "default": 0.2,
      "description": "Border constraints run along the border simplified to within this fraction of the output's mean edge length (Douglas-Peucker chords; corners and larger bends stay), instead of through every input edge, so a border cut face by face (a staircase) or wavering by a fraction of a cell keeps about as many edges as the output's resolution needs (docs/mesh.md). The border moves by at most about this much. 0: planes through the input's own border edges."
    },
    "boundary_erosion": {
      "type": "number",
      "minimum": 0,
      "maximum": 1,
      "default": 0.5,
      "description": "The part of `boundary_tolerance` by which the simplified border may cut into the surface (a border vertex outside its chord is cut off); bridging a notch takes the whole tolerance. 1: symmetric; 0: the border only grows."
    },
    "min_normal_dot": {
      "type": "number",
      "minimum": -1,
      "maximum": 1,
      "default": 0.2,
      "description": "Reject a collapse that turns a face normal so that its cosine to the normal before (or in the input) drops below this; 0.2 allows about 78 degrees."
    },
    "fill_hole_output_edges": {
      "type": "number",
      "minimum": 0,
      "default": 8,
      "description": "First fill the holes (boundary loops) whose perimeter is at most this many output mean edge lengths and whose patch stays within `fill_hole_reach` of the hole's rim, without new vertices (CGAL's hole triangulation, as mesh.clean): the output cannot draw such a hole, and held by the border planes it would end as a hole of a few low-poly triangles that a coarser surface of the same budget (a low-depth Poisson mesh) closes. A longer hole, even a narrow one (a window slit, a gap the scanner saw through), has enough border edges to be drawn, and stays. 0 fills nothing."
    },
    "fill_hole_reach": {
      "type": "number",
      "minimum": 0,
      "default": 1,
      "description": "A hole within `fill_hole_output_edges` is filled when every point of its patch lies within this many output mean edge lengths of the hole's rim (a round hole of perimeter 2 pi; an oval of perimeter 8 less than two edges wide): metrics.geometry counts no invented area within one output edge of the scan. 0: every hole within the perimeter is filled (version 4, whose default perimeter was 6)."
    },
    "seen_through_points": {
      "type": "integer",
      "minimum": 0,
      "default": 3,
      "description": "With the scan on the `points` input and its scanner stations known: a hole is not filled when at least this many lines of sight (station to point) cross its patch `seen_through_clearance` or more before their point, and they outnumber the lines ending on the patch (within that clearance). The scanner saw through it: free space or a surface behind, which a patch would hide (invented surface). At least a few, so that one stray return does not decide; the majority, so that a few mixed returns behind a depth step (an RGB-D camera's flying pixels) do not open a hole the scanner mostly saw as surface. 0: no test."
    },
    "seen_through_clearance": {
      "type": "number",
      "minimum": 0,
      "default": 0.25,
      "description": "How far before its point a line of sight must cross a patch to count, in output mean edge lengths: a point just behind a patch over its own hole's rim is that surface, not seen through it."
    }
  },
  "oneOf": [{"required": ["target_faces"]}, {"required": ["ratio"]}]
})";

Status Run(StageContext& ctx) {
  const bool has_target =
      ctx.params().contains("target_faces") && !ctx.params()["target_faces"].is_null();
  const bool has_ratio = ctx.params().contains("ratio") && !ctx.params()["ratio"].is_null();
  if (has_target == has_ratio) {
    return Status::Invalid(std::string(kId) + ": give exactly one of 'target_faces' and 'ratio'");
  }
  DecimateOptions options;
  PB_ASSIGN_OR_RETURN(options.boundary_weight, NumberParam(ctx, kId, "boundary_weight"));
  PB_ASSIGN_OR_RETURN(options.boundary_tolerance, NumberParam(ctx, kId, "boundary_tolerance"));
  PB_ASSIGN_OR_RETURN(options.boundary_erosion, NumberParam(ctx, kId, "boundary_erosion"));
  PB_ASSIGN_OR_RETURN(options.min_normal_dot, NumberParam(ctx, kId, "min_normal_dot"));
  PB_ASSIGN_OR_RETURN(options.fill_hole_output_edges,
                      NumberParam(ctx, kId, "fill_hole_output_edges"));
  PB_ASSIGN_OR_RETURN(options.fill_hole_reach, NumberParam(ctx, kId, "fill_hole_reach"));
  double ratio = 0;
  int64_t target = 0;
  if (has_ratio) {
    PB_ASSIGN_OR_RETURN(ratio, NumberParam(ctx, kId, "ratio"));
    if (!(ratio > 0 && ratio <= 1)) {
      return Status::Invalid(std::string(kId) + ": parameter 'ratio' must be in (0, 1], got " +
                             std::to_string(ratio));
    }
  } else {
    PB_ASSIGN_OR_RETURN(target, IntegerParam(ctx, kId, "target_faces", {1}));
  }

  PB_ASSIGN_OR_RETURN(InputMesh input, ReadInputMesh(ctx, kId, 0.2));
  const Mesh& mesh = input.mesh;
  if (has_ratio) target = std::llround(ratio * static_cast<double>(mesh.face_count()));
  options.target_faces = static_cast<size_t>(target);
  if (mesh.face_count() <= options.target_faces) {
    // A budget above the input is met by doing nothing, which in a workflow
    // usually means the mesh before was smaller than planned.
    ctx.warning("the input has " + std::to_string(mesh.face_count()) +
                " faces, within the budget of " + std::to_string(options.target_faces) +
                ": unchanged");
  }
  // The scan's lines of sight, for the holes the scanner saw through. Read
  // when the first hole the size tests would fill asks (most decimations
  // have none, and the scan can be much larger than the mesh).
  PB_ASSIGN_OR_RETURN(const int64_t seen_through,
                      IntegerParam(ctx, kId, "seen_through_points", {0}));
  PB_ASSIGN_OR_RETURN(const double clearance, NumberParam(ctx, kId, "seen_through_clearance"));
  std::optional<LinesOfSight> sight;
  bool read = false, without_stations = false;
  Status sight_status = Status::Ok();
  if (ctx.has_input("points") && seen_through > 0) {
    options.keep_hole_open = [&](const std::vector<std::array<double, 9>>& patch,
                                 double output_edge) {
      if (!read) {
        read = true;
        Expected<InputPoints> points = ReadInputPoints(ctx, kId, 0.2);
        if (!points.ok()) {
          sight_status = points.status();
        } else if (!points->cloud.has_stations()) {
          without_stations = true;
        } else {
          Expected<LinesOfSight> built = LinesOfSight::Build(points->cloud, mesh.origin);
          if (built.ok()) {
            sight = std::move(*built);
          } else {
            sight_status = built.status().WithContext(points->path);
          }
        }
      }
      if (!sight) return false;
      size_t behind = 0, near = 0;
      for (const auto& t : patch) {
        const LinesOfSight::Counts counts = sight->Through(
            {t[0], t[1], t[2]}, {t[3], t[4], t[5]}, {t[6], t[7], t[8]}, clearance * output_edge);
        behind += counts.behind;
        near += counts.near;
      }
      return behind >= static_cast<size_t>(seen_through) && behind > near;
    };
  }
  options.progress = [&ctx](double fraction) { ctx.progress(0.2 + 0.7 * fraction); };
  DecimateReport report;
  Mesh output;
  {
    PB_PHASE(ctx, "compute");
    auto decimated = DecimateMesh(mesh, options, &report);
    if (!sight_status.ok()) return sight_status;
    if (!decimated.ok()) return decimated.status().WithContext(input.path);
    output = std::move(*decimated);
  }
  ctx.counter("faces_in", static_cast<double>(report.faces_in));
  ctx.counter("faces_out", static_cast<double>(report.faces_out));
  ctx.counter("holes_filled", static_cast<double>(report.holes_filled));
  ctx.counter("hole_faces", static_cast<double>(report.hole_faces));
  ctx.counter("holes_too_wide", static_cast<double>(report.holes_too_wide));
  ctx.counter("outlines_kept", static_cast<double>(report.outlines_kept));
  ctx.counter("holes_seen_through", static_cast<double>(report.holes_seen_through));
  if (without_stations && report.holes_filled > 0) {
    ctx.warning("the scan has no scanner stations: " + std::to_string(report.holes_filled) +
                " holes filled without the lines-of-sight test (seen_through_points)");
  }
  PB_RETURN_IF_ERROR(WriteOutputMesh(
      ctx, output,
      InputMeshMetaWith(ctx, output,
                        {{"decimate",
                          {{"target_faces", options.target_faces},
                           {"collapses", report.collapses},
                           {"rejected_link", report.rejected_link},
                           {"rejected_flip", report.rejected_flip},
                           {"rejected_degenerate", report.rejected_degenerate},
                           {"holes_filled", report.holes_filled},
                           {"hole_faces", report.hole_faces},
                           {"holes_too_wide", report.holes_too_wide},
                           {"outlines_kept", report.outlines_kept},
                           {"holes_seen_through", report.holes_seen_through}}}})));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType DecimateStage() {
  StageType type;
  type.id = kId;
  type.version = 6;  // 2: smooth_boundary; 3: boundary_tolerance (chords) replaces it;
                    // 4: fill_hole_output_edges; 5: fill_hole_reach, perimeter 6 -> 8;
                    // 6: seen_through_points (the `points` input)
  type.summary = "Quadric edge-collapse decimation to a face budget, keeping the mesh manifold";
  type.doc =
      "Collapses edges in order of quadric error (Garland & Heckbert 1997) until the face count "
      "is at most `target_faces` (or `ratio` times the input's faces; give exactly one). Each "
      "vertex moves to the point minimizing the merged quadric (or the best of the endpoints "
      "and the midpoint on flat regions). A collapse is skipped when it would make the mesh "
      "non-manifold (link condition), flip or degenerate a face; open borders are held by "
      "constraint planes (`boundary_weight`) along the border simplified to the output's "
      "resolution (`boundary_tolerance`). Colors, normals, uvs and tangents are "
      "interpolated along the collapsed edge. Deterministic: equal inputs give equal outputs. "
      "The budget can be missed when every remaining collapse is rejected.\n\n"
      "Counters: `faces_in`, `faces_out`, `holes_filled`, `hole_faces`, `holes_too_wide` "
      "(`fill_hole_output_edges`, `fill_hole_reach`), `outlines_kept` (loops not filled because "
      "the patch would be over a quarter of its connected surface's area: the outline of an "
      "open sheet, which it would close into a shell), `holes_seen_through` (not filled: "
      "`seen_through_points` lines of sight of the scan on `points` cross the patch).";
  type.params_schema = kSchema;
  type.inputs = {
      {"mesh", "mesh", "The mesh to decimate (mesh.ply; a synth truth works too).", false},
      {"points", "points",
       "Optional: the scan (points.ply). With its scanner stations, a hole the scanner saw "
       "through is not filled (`seen_through_points`).",
       true}};
  type.outputs = {{"mesh", "mesh", "The decimated mesh (mesh.ply).", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
