// mesh.fit: moves the vertices of a (low) mesh along their normals so the
// surface fits the scan's points instead of being inscribed in the smoothed
// surface it was decimated from (stages/geometry/mesh/fit.h).
#include "stages/builtin.h"

#include "stages/geometry/mesh/fit.h"
#include "stages/mesh_io.h"
#include "stages/params.h"
#include "stages/points_io.h"

namespace pb {
namespace {

constexpr const char* kId = "mesh.fit";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "iterations": {
      "type": "integer",
      "minimum": 1,
      "maximum": 100,
      "default": 12,
      "description": "Rounds of: assign each scan point to its nearest face, move the vertices."
    },
    "support_spacings": {
      "type": "number",
      "minimum": 0,
      "default": 3,
      "description": "A scan point pulls on its nearest face only within this many of its local spacings (the spacing of its k nearest neighbours) ..."
    },
    "support_edges": {
      "type": "number",
      "minimum": 0,
      "default": 0.5,
      "description": "... or within this many mean edge lengths of the mesh, whichever is larger: a coarse mesh's chords lie up to a fraction of an edge from the points."
    },
    "min_normal_cosine": {
      "type": "number",
      "minimum": -1,
      "maximum": 1,
      "default": 0,
      "description": "When the points have normals: a point pulls only on a face whose normal is within this cosine of its own (a point of the other side of a thin part does not)."
    },
    "smoothness": {
      "type": "number",
      "minimum": 0,
      "default": 0.25,
      "description": "Weight of the smoothness of the displacement (membrane energy, relative to a vertex's mean data weight): noise averages over neighbours; 0 fits the points alone."
    },
    "outside_weight": {
      "type": "number",
      "exclusiveMinimum": 0,
      "exclusiveMaximum": 1,
      "default": 0.75,
      "description": "Weight of a scan point outside the surface against one inside (w and 1 - w): 0.5 is plain least squares, whose surface runs through the middle of the points and leaves the outer half of the samples along every silhouette outside the model's outline; 0.75 (a point outside weighs three inside) moves the surface towards the outer side of the points' spread, by a fraction of its width. Larger covers more of the scan's outline and moves the surface farther out."
    },
    "sweeps": {
      "type": "integer",
      "minimum": 1,
      "maximum": 1000,
      "default": 20,
      "description": "Gauss-Seidel sweeps of the least-squares solve per round."
    },
    "damping": {
      "type": "number",
      "exclusiveMinimum": 0,
      "maximum": 1,
      "default": 0.8,
      "description": "Fraction of the solved displacement taken per round."
    },
    "max_step_edges": {
      "type": "number",
      "exclusiveMinimum": 0,
      "default": 0.25,
      "description": "Largest move of a vertex per round, in mean lengths of its edges."
    },
    "max_offset_edges": {
      "type": "number",
      "exclusiveMinimum": 0,
      "default": 0.5,
      "description": "Farthest a vertex may end from its input position, in mean lengths of its edges in the input: a chord's sagitta is a fraction of an edge, and a vertex pulled farther is pulled by the points of another surface."
    },
    "max_turn_deg": {
      "type": "number",
      "exclusiveMinimum": 0,
      "exclusiveMaximum": 180,
      "default": 60,
      "description": "No face may turn further than this from its normal in the input (or before the round): the moves of its vertices are halved until none does."
    },
    "spacing_neighbors": {
      "type": "integer",
      "minimum": 1,
      "maximum": 64,
      "default": 8,
      "description": "k of the local spacing: spacing = r_k * sqrt(pi / k), r_k the distance to the k-th nearest other point."
    },
    "border_reach_edges": {
      "type": "number",
      "minimum": 0,
      "default": 0.5,
      "description": "After the rounds, border vertices move outward in their faces' planes until every border edge passes `border_margin_spacings` beyond the scan points whose closest point on the mesh lies on it (points within 45 degrees of the face's plane), at most this many of the vertex's mean edge lengths: the decimation may cut its border up to half an output edge into the scanned surface (mesh.decimate `boundary_erosion`), and the model's outline then falls short of the scan's. 0 turns it off (version 2)."
    },
    "border_margin_spacings": {
      "type": "number",
      "minimum": 0,
      "default": 0.5,
      "description": "How far past the outermost scan points the border pass puts a border, in their local spacings (the scan's own render, render.splats, draws the surface up to one spacing past its last point)."
    },
    "directions": {
      "enum": ["normals", "free"],
      "default": "free",
      "description": "How a vertex may move: 'normals', along its normal only; 'free', in any direction the points ask (a 3 x 3 solve per vertex, sliding along its own tangent plane costing as much as the smoothness), so a vertex on a crease the coarse Poisson solve rounded off (a plinth's or a wall's edge) moves out to the crease instead of only along its diagonal normal (version 4; 'normals' is version 3's fit)."
    },
    "tangent_weight": {
      "type": "number",
      "exclusiveMinimum": 0,
      "default": 0.1,
      "description": "With directions 'free': the smoothness of the displacement across the vertex normal, as a fraction of `smoothness` (which then acts along the normal), with a tie of that weight to the vertex's place. Small lets a vertex slide to a crease; 1 smooths all three components alike."
    },
    "crease_deg": {
      "type": "number",
      "minimum": 0,
      "exclusiveMaximum": 180,
      "default": 20,
      "description": "With directions 'free': only a vertex with a face turned more than this from its normal (on a crease or a rounded edge) moves freely; the others, and border vertices, move along their normals. 0 frees every interior vertex."
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
  FitOptions options;
  PB_ASSIGN_OR_RETURN(const int64_t iterations, IntegerParam(ctx, kId, "iterations", {1, 100}));
  options.iterations = static_cast<int>(iterations);
  PB_ASSIGN_OR_RETURN(options.support_spacings, NumberParam(ctx, kId, "support_spacings"));
  PB_ASSIGN_OR_RETURN(options.support_edges, NumberParam(ctx, kId, "support_edges"));
  PB_ASSIGN_OR_RETURN(options.min_normal_cosine, NumberParam(ctx, kId, "min_normal_cosine"));
  PB_ASSIGN_OR_RETURN(options.smoothness, NumberParam(ctx, kId, "smoothness"));
  PB_ASSIGN_OR_RETURN(options.outside_weight, NumberParam(ctx, kId, "outside_weight"));
  PB_ASSIGN_OR_RETURN(const int64_t sweeps, IntegerParam(ctx, kId, "sweeps", {1, 1000}));
  options.sweeps = static_cast<int>(sweeps);
  PB_ASSIGN_OR_RETURN(options.damping, NumberParam(ctx, kId, "damping"));
  PB_ASSIGN_OR_RETURN(options.max_step_edges, NumberParam(ctx, kId, "max_step_edges"));
  PB_ASSIGN_OR_RETURN(options.max_offset_edges, NumberParam(ctx, kId, "max_offset_edges"));
  PB_ASSIGN_OR_RETURN(options.max_turn_deg, NumberParam(ctx, kId, "max_turn_deg"));
  PB_ASSIGN_OR_RETURN(const int64_t neighbors,
                      IntegerParam(ctx, kId, "spacing_neighbors", {1, 64}));
  options.spacing_neighbors = static_cast<int>(neighbors);
  PB_ASSIGN_OR_RETURN(options.border_reach_edges, NumberParam(ctx, kId, "border_reach_edges"));
  PB_ASSIGN_OR_RETURN(options.border_margin_spacings,
                      NumberParam(ctx, kId, "border_margin_spacings"));
  PB_ASSIGN_OR_RETURN(const std::string directions, StringParam(ctx, kId, "directions"));
  options.free_directions = directions == "free";
  PB_ASSIGN_OR_RETURN(options.tangent_weight, NumberParam(ctx, kId, "tangent_weight"));
  PB_ASSIGN_OR_RETURN(options.crease_deg, NumberParam(ctx, kId, "crease_deg"));
  PB_ASSIGN_OR_RETURN(const int64_t threads, IntegerParam(ctx, kId, "threads", {0}));
  options.threads = threads > 0 ? static_cast<int>(threads) : ctx.threads();

  PB_ASSIGN_OR_RETURN(InputMesh input, ReadInputMesh(ctx, kId, 0.2));
  PB_ASSIGN_OR_RETURN(InputPoints points, ReadInputPoints(ctx, kId, 0.4));
  FitReport report;
  Mesh fitted;
  {
    PB_PHASE(ctx, "compute");
    Expected<Mesh> result = FitMeshToPoints(input.mesh, points.cloud, options, &report);
    if (!result.ok()) return result.status().WithContext(input.path + " with " + points.path);
    fitted = std::move(result).value();
  }
  ctx.progress(0.9);
  ctx.counter("supported_points", static_cast<double>(report.supported_before));
  ctx.counter("mean_abs_distance_before_m", report.mean_abs_distance_before_m);
  ctx.counter("mean_abs_distance_after_m", report.mean_abs_distance_after_m);
  ctx.counter("mean_signed_distance_before_m", report.mean_signed_distance_before_m);
  ctx.counter("mean_signed_distance_after_m", report.mean_signed_distance_after_m);
  ctx.counter("outside_fraction_before", report.outside_fraction_before);
  ctx.counter("outside_fraction_after", report.outside_fraction_after);
  ctx.counter("vertices_moved", static_cast<double>(report.vertices_moved));
  ctx.counter("max_move_m", report.max_move_m);
  ctx.counter("mean_move_m", report.mean_move_m);
  ctx.counter("border_vertices_moved", static_cast<double>(report.border_vertices_moved));
  nlohmann::json changes = {{"fit",
                             {{"points", report.points},
                              {"supported_before", report.supported_before},
                              {"supported_after", report.supported_after},
                              {"mean_abs_distance_before_m", report.mean_abs_distance_before_m},
                              {"mean_abs_distance_after_m", report.mean_abs_distance_after_m},
                              {"mean_signed_distance_before_m", report.mean_signed_distance_before_m},
                              {"mean_signed_distance_after_m", report.mean_signed_distance_after_m},
                              {"outside_fraction_before", report.outside_fraction_before},
                              {"outside_fraction_after", report.outside_fraction_after},
                              {"vertices_moved", report.vertices_moved},
                              {"max_move_m", report.max_move_m},
                              {"mean_move_m", report.mean_move_m},
                              {"steps_halved", report.steps_halved},
                              {"border_vertices_moved", report.border_vertices_moved},
                              {"mean_edge_m", report.mean_edge_m},
                              {"median_local_spacing_m", report.median_spacing_m}}}};
  PB_RETURN_IF_ERROR(WriteOutputMesh(ctx, fitted, InputMeshMetaWith(ctx, fitted, changes)));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType FitStage() {
  StageType type;
  type.id = kId;
  // 2: outside_weight (0.75; version 1 was 0.5); 3: the border pass; 4: directions free;
  // 5: in free mode a vertex held to its normal takes the block's exact minimizer along it.
  type.version = 5;
  type.summary = "Moves a mesh's vertices so the surface fits the scan's points, out to its creases";
  type.doc =
      "A decimated mesh's vertices lie on the surface it was decimated from, so its chords cut "
      "inside every convex part (pipes), and a coarse Poisson solve rounds thin parts inward: "
      "seen from the side the outline lies a pixel or two inside the scan's outermost points. "
      "This stage fits the mesh to the points: each round, every scan point within "
      "`support_spacings` local spacings (or `support_edges` mean edges) of the mesh is assigned "
      "to its nearest face (exact point-triangle distance; with point normals, only a face "
      "facing the same side, `min_normal_cosine`) with its signed distance along the face "
      "normal, and the vertices' displacements along their normals solve the least-squares "
      "problem of those distances (the face moving by the barycentric blend of its corners; a "
      "point outside the surface weighs `outside_weight`, one inside 1 - `outside_weight`, so "
      "the surface settles towards the outer side of the points and its outline covers the "
      "scan's) "
      "plus `smoothness` times the membrane energy of the displacement (`sweeps` Gauss-Seidel "
      "sweeps; the displacement is smoothed, not the positions, so the mesh does not "
      "shrink), and each vertex moves along its normal by `damping` of it, at most "
      "`max_step_edges` of its mean edge per round and at most `max_offset_edges` from where it "
      "started. Version 4 (`directions: free`, the default) moves each vertex in any direction: "
      "its displacement is a vector, solved as a 3 x 3 block per vertex, the smoothness acting "
      "along the vertex normal and, `tangent_weight` of it, across, so a vertex on a crease "
      "(a face turned more than `crease_deg` from its normal) "
      "that the coarse Poisson solve rounded off (a plinth's edge) moves out to the crease, "
      "where moving along its diagonal normal bent both faces (version 3, `directions: "
      "normals`, left the low mesh's outline a pixel inside a box's corners). Other vertices "
      "and border vertices move along their normals (version 5: by the block's exact minimizer "
      "along the normal). A move that would turn a face by more than `max_turn_deg` (from the "
      "input or the round before) or collapse it is halved until none does. Then (version 3) "
      "a border pass moves border vertices outward in their faces' planes until each border "
      "edge passes `border_margin_spacings` local spacings beyond the points whose closest "
      "point lies on it (points within 45 degrees of the face's plane, give or take two "
      "spacings of noise), each edge's two ends by the least offsets whose line clears every "
      "such point, each vertex at most `border_reach_edges` of its mean edge: the decimation "
      "may cut a border up to half an output edge into the scanned surface, and the model's "
      "outline then falls short of the scan's (hole pixels at the outline). Faces, vertex "
      "order, colors and uvs are kept; normals, when present, are the input's turned by the "
      "rotation of each vertex's face normal (recomputing them would light every facet of a "
      "decimated mesh). Place it after the low mesh's decimation, before uv.unwrap. Deterministic "
      "for any thread count.\n\n"
      "Counters: `supported_points`, `mean_abs_distance_before_m`, `mean_abs_distance_after_m` "
      "(mean |signed distance| of the supported points to the input and to the output), "
      "`mean_signed_distance_before_m`, `mean_signed_distance_after_m` (positive: points "
      "outside), `outside_fraction_before`, `outside_fraction_after` (share of those points "
      "outside the surface), `vertices_moved`, `max_move_m`, `mean_move_m`, "
      "`border_vertices_moved` (by the border pass). Phases: `io`, "
      "`compute`.";
  type.params_schema = kSchema;
  type.inputs = {{"mesh", "mesh", "The mesh to fit (mesh.ply), e.g. the decimated low mesh.", false},
                 {"points", "points", "The scan (points.ply; normals used when present).", false}};
  type.outputs = {{"mesh", "mesh", "The mesh with its vertices moved onto the points.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
