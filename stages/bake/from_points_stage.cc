// bake.from_points: the paper's point-based detail transfer
// (stages/geometry/bake/from_points.h).
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "engine/stage.h"
#include "stages/bake/bake_io.h"
#include "stages/builtin.h"
#include "stages/geometry/bake/from_points.h"
#include "stages/geometry/points/spacing.h"
#include "stages/mesh_io.h"
#include "stages/params.h"
#include "stages/points_io.h"

namespace pb {
namespace {

constexpr const char* kId = "bake.from_points";

constexpr const char* kOwnProperties = R"(,
    "interpolation": {
      "type": "string",
      "enum": ["delaunay", "nearest", "idw", "splat"],
      "default": "delaunay",
      "description": "How a face's texels are filled from its corners and the points mapped onto it. delaunay (the paper): 2-D Delaunay triangulation of corners + points, linear interpolation. nearest: the nearest sample. idw: inverse-distance weighting of the idw_neighbors nearest. splat: Gaussian footprints of splat_sigma spacings, pull-push filling of uncovered texels."
    },
    "max_distance": {
      "type": "number",
      "exclusiveMinimum": 0,
      "default": 4,
      "description": "A point is assigned to the nearest face within this distance, in multiples of the points' spacing (spacing_m of the points' meta, else measured). The paper's 4.0."
    },
    "max_angle_deg": {
      "type": "number",
      "exclusiveMinimum": 0,
      "maximum": 180,
      "default": 90,
      "description": "...and whose face normal is within this angle of the point's normal (the paper: 120; the authors' code: 45 against vertex normals). 180 turns the test off."
    },
    "idw_neighbors": {
      "type": "integer",
      "minimum": 1,
      "maximum": 64,
      "default": 4,
      "description": "idw: how many nearest samples are weighted (by 1 / distance^2)."
    },
    "neighbors": {
      "type": "boolean",
      "default": true,
      "description": "true (version 2): a face with points of its own also takes the points of the faces across its edges near the shared edge, unfolded into its UV plane, and its corners are samples only where it has fewer than three points of its own. false (the paper, version 1): from its own points and its corners, the mesh's smooth vertex colors, which draw slivers of their color from every vertex and along every edge where the points are sparse against the texels."
    },
    "splat_sigma": {
      "type": "number",
      "exclusiveMinimum": 0,
      "default": 1,
      "description": "splat: Gaussian sigma of a point's footprint, in multiples of the points' spacing (cut at 2 sigma)."
    })";

Expected<TexelInterpolation> ParseInterpolation(const std::string& name) {
  if (name == "delaunay") return TexelInterpolation::kDelaunay;
  if (name == "nearest") return TexelInterpolation::kNearest;
  if (name == "idw") return TexelInterpolation::kIdw;
  if (name == "splat") return TexelInterpolation::kSplat;
  return Status::Invalid(std::string(kId) +
                         ": parameter 'interpolation' must be delaunay, nearest, idw or splat, "
                         "got '" + name + "'");
}

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(BakeOptions options, ReadBakeOptions(ctx, kId));
  FromPointsOptions from_points;
  PB_ASSIGN_OR_RETURN(const std::string interpolation, StringParam(ctx, kId, "interpolation"));
  PB_ASSIGN_OR_RETURN(from_points.interpolation.mode, ParseInterpolation(interpolation));
  PB_ASSIGN_OR_RETURN(const double max_distance, NumberParam(ctx, kId, "max_distance"));
  PB_ASSIGN_OR_RETURN(from_points.max_angle_deg, NumberParam(ctx, kId, "max_angle_deg"));
  PB_ASSIGN_OR_RETURN(const int64_t neighbors, IntegerParam(ctx, kId, "idw_neighbors", {1, 64}));
  PB_ASSIGN_OR_RETURN(const double splat_sigma, NumberParam(ctx, kId, "splat_sigma"));
  if (!(max_distance > 0) || !(splat_sigma > 0) ||
      !(from_points.max_angle_deg > 0 && from_points.max_angle_deg <= 180)) {
    return Status::Invalid(std::string(kId) +
                           ": max_distance and splat_sigma must be > 0 and max_angle_deg in (0, 180]");
  }
  from_points.interpolation.idw_neighbors = static_cast<int>(neighbors);
  PB_ASSIGN_OR_RETURN(from_points.neighbors, BoolParam(ctx, kId, "neighbors"));

  PB_ASSIGN_OR_RETURN(InputMesh input, ReadInputMesh(ctx, kId, 0.05));
  PB_ASSIGN_OR_RETURN(InputPoints points, ReadInputPoints(ctx, kId, 0.25));
  if (!points.cloud.has_colors()) {
    return Status::Invalid(points.path + ": " + kId +
                           " needs a colored point cloud (io.read_points paints an uncolored "
                           "scan grey unless `uncolored: none`)");
  }
  double spacing_m = InputPointsSpacing(ctx);
  std::string spacing_source = "meta";
  if (spacing_m == 0) {
    PB_PHASE(ctx, "spacing");
    auto measured = MedianSpacing(points.cloud);
    if (!measured.ok()) return measured.status().WithContext(points.path);
    spacing_m = *measured;
    spacing_source = "measured";
  }
  from_points.max_distance_m = max_distance * spacing_m;
  from_points.splat_sigma_m = splat_sigma * spacing_m;
  const size_t point_count = points.cloud.size();
  options.progress = [&ctx](double fraction) { ctx.progress(0.25 + 0.6 * fraction); };

  FromPointsReport report;
  BakeResult result;
  {
    PB_PHASE(ctx, "compute");
    auto baked = BakeFromPoints(std::move(input.mesh), std::move(points.cloud), options, from_points, &report);
    if (!baked.ok()) return baked.status().WithContext(input.path);
    result = std::move(*baked);
  }
  const AssignReport& assign = report.assign;
  if (assign.assigned == 0) {
    char text[320];
    std::snprintf(text, sizeof text,
                  "no point lies within %.1f mm and %.0f degrees of the mesh: the maps come "
                  "from the vertex colors alone (does the mesh belong to these points?)",
                  from_points.max_distance_m * 1e3, from_points.max_angle_deg);
    ctx.warning(text);
  }
  ctx.counter("points", static_cast<double>(point_count));
  ctx.counter("points_assigned", static_cast<double>(assign.assigned));
  ctx.counter("points_too_far", static_cast<double>(assign.too_far));
  ctx.counter("points_wrong_angle", static_cast<double>(assign.wrong_angle));
  ctx.counter("faces_from_corners", static_cast<double>(report.faces_from_corners));
  ctx.counter("points_borrowed", static_cast<double>(report.points_borrowed));
  PB_RETURN_IF_ERROR(WriteBakeOutputs(
      ctx, kId, result,
      {{"interpolation", interpolation},
       {"neighbors", from_points.neighbors},
       {"spacing_m", spacing_m},
       {"spacing_source", spacing_source},
       {"max_distance_m", from_points.max_distance_m},
       {"max_angle_deg", from_points.max_angle_deg},
       {"points", point_count},
       {"points_assigned", assign.assigned},
       {"points_too_far", assign.too_far},
       {"points_wrong_angle", assign.wrong_angle},
       {"mean_distance_m", assign.mean_distance_m},
       {"faces_with_points", report.faces_with_points},
       {"faces_from_corners", report.faces_from_corners},
       {"points_borrowed", report.points_borrowed}}));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType FromPointsBakeStage() {
  StageType type;
  type.id = kId;
  type.version = 2;
  type.summary = "Color and normal maps straight from the point cloud (the paper's detail transfer)";
  type.doc =
      "The paper's point-based detail transfer. Every point is assigned to the nearest face of "
      "the mesh within `max_distance` spacings whose normal is within `max_angle_deg` of the "
      "point's, at the nearest point of that face; its barycentric coordinates there place it "
      "in the face's UV triangle. Each face's texels are then filled from its points plus, with "
      "`neighbors` (the default, version 2), the points of the faces across its edges that lie "
      "within about two spacings of the shared edge, unfolded into its UV plane; its three "
      "corners (the mesh's vertex colors and normals) are samples too without `neighbors` (the "
      "paper) or where the face has fewer than three points of its own. By `interpolation`. "
      "Point normals go into the normal map in the output mesh's tangent frames; faces no point "
      "reached are filled from their corners as bake.vertex_colors would. Then `gutter` passes "
      "of dilation. Distances are in multiples of the points' spacing (`spacing_m` in their "
      "meta, from synth.scan or points.spacing; measured here otherwise). Deterministic "
      "whatever the thread count.\n\n"
      "Counters: `points`, `points_assigned`, `points_too_far`, `points_wrong_angle`, "
      "`faces_from_corners` (faces with no point of their own), `points_borrowed` "
      "(points used by a face across an edge), `covered_texels`, `edge_texels`, `gutter_texels`.";
  type.params_schema = std::string(R"({"type": "object", "additionalProperties": false, "properties": {)") +
                       BakeCommonSchemaProperties() + kOwnProperties + "}}";
  type.inputs = {{"mesh", "mesh", "The low mesh, with uvs (and vertex colors for the corners) (mesh.ply).", false},
                 {"points", "points", "The colored scan, with normals for the angle test and the normal map (points.ply).", false}};
  type.outputs = BakeOutputPorts();
  type.run = Run;
  return type;
}

}  // namespace pb
