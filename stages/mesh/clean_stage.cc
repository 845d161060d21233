// mesh.clean: removes degenerate, duplicate and non-manifold faces, small
// components and unreferenced vertices, and splits non-manifold vertices
// (stages/geometry/mesh/clean.h), so that UV unwrapping gets manifold input.
#include "stages/builtin.h"

#include <cmath>

#include "stages/geometry/mesh/clean.h"
#include "stages/geometry/mesh/trim.h"
#include "stages/mesh_io.h"
#include "stages/params.h"

namespace pb {
namespace {

constexpr const char* kId = "mesh.clean";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "min_area_m2": {
      "type": "number",
      "minimum": 0,
      "default": 1e-10,
      "description": "Faces with a smaller area (square meters) are degenerate and removed; 1e-10 is a triangle about 10 micrometers across."
    },
    "min_component_faces": {
      "type": "integer",
      "minimum": 0,
      "default": 50,
      "description": "Connected components (faces joined by shared edges) with fewer faces are removed: floating specks from noise."
    },
    "min_component_fraction": {
      "type": "number",
      "minimum": 0,
      "maximum": 1,
      "default": 0,
      "description": "Also remove components with fewer faces than this fraction of the largest component's; 0 disables."
    },
    "min_component_area_m2": {
      "type": "number",
      "minimum": 0,
      "default": 0.01,
      "description": "A component is removed only if it is also smaller than this area (square meters): a decimated flat wall may have 2 faces, a noise speck is tiny."
    },
    "fill_hole_edges": {
      "type": "integer",
      "minimum": 0,
      "default": 8,
      "description": "Fill boundary loops (holes) of at most this many edges, without new vertices (CGAL's hole triangulation), so that mesh.decimate, which holds open borders, cannot grow them into holes the size of a low-poly triangle. 0 disables this test."
    },
    "fill_hole_spacings": {
      "type": "number",
      "minimum": 0,
      "default": 16,
      "description": "Also fill boundary loops whose perimeter is at most this many point spacings (the input's `spacing_m` meta, passed on from the points; without one, mean edge lengths of the mesh). Real borders (the edge of what a scanner saw, openings) are far longer. 0 disables this test."
    }
  }
})";

Status Run(StageContext& ctx) {
  CleanOptions options;
  PB_ASSIGN_OR_RETURN(options.min_area_m2, NumberParam(ctx, kId, "min_area_m2"));
  PB_ASSIGN_OR_RETURN(options.hole_max_edges, IntegerParam(ctx, kId, "fill_hole_edges", {0}));
  PB_ASSIGN_OR_RETURN(const double hole_spacings, NumberParam(ctx, kId, "fill_hole_spacings"));
  PB_ASSIGN_OR_RETURN(options.min_component_faces,
                      IntegerParam(ctx, kId, "min_component_faces", {0}));
  PB_ASSIGN_OR_RETURN(options.min_component_fraction,
                      NumberParam(ctx, kId, "min_component_fraction"));
  PB_ASSIGN_OR_RETURN(options.min_component_area_m2,
                      NumberParam(ctx, kId, "min_component_area_m2"));
  PB_ASSIGN_OR_RETURN(InputMesh input, ReadInputMesh(ctx, kId, 0.3));
  Mesh& mesh = input.mesh;
  ctx.progress(0.3);
  const nlohmann::json& meta = ctx.input("mesh").meta;
  double unit_m = 0;
  if (meta.is_object() && meta.contains("spacing_m") && meta["spacing_m"].is_number()) {
    unit_m = meta["spacing_m"].get<double>();
  }
  if (!(unit_m > 0 && std::isfinite(unit_m))) unit_m = MeanEdgeLength(mesh);
  options.hole_max_perimeter_m = hole_spacings * unit_m;
  CleanReport report;
  {
    PB_PHASE(ctx, "compute");
    Expected<Mesh> cleaned = CleanMesh(mesh, options, &report);
    if (!cleaned.ok()) return cleaned.status().WithContext(input.path);
    mesh = std::move(cleaned).value();
  }
  ctx.progress(0.7);
  ctx.counter("faces_in", static_cast<double>(report.faces_in));
  ctx.counter("vertices_in", static_cast<double>(report.vertices_in));
  ctx.counter("degenerate_faces", static_cast<double>(report.degenerate_faces));
  ctx.counter("duplicate_faces", static_cast<double>(report.duplicate_faces));
  ctx.counter("nonmanifold_edge_faces", static_cast<double>(report.nonmanifold_edge_faces));
  ctx.counter("misoriented_faces", static_cast<double>(report.misoriented_faces));
  ctx.counter("small_components", static_cast<double>(report.small_components));
  ctx.counter("small_component_faces", static_cast<double>(report.small_component_faces));
  ctx.counter("split_vertices", static_cast<double>(report.split_vertices));
  ctx.counter("boundary_loops", static_cast<double>(report.boundary_loops));
  ctx.counter("holes_filled", static_cast<double>(report.holes_filled));
  ctx.counter("hole_faces", static_cast<double>(report.hole_faces));
  ctx.counter("unreferenced_vertices", static_cast<double>(report.unreferenced_vertices));
  ctx.counter("faces_out", static_cast<double>(report.faces_out));
  ctx.counter("vertices_out", static_cast<double>(report.vertices_out));
  PB_RETURN_IF_ERROR(
      WriteOutputMesh(ctx, mesh, InputMeshMetaWith(ctx, mesh, {{"manifold", true}})));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType CleanStage() {
  StageType type;
  type.id = kId;
  // 2: small components must also be small in area; 3: input meta passed on;
  // 4: small holes filled, faces at misoriented edges dropped.
  type.version = 4;
  type.summary =
      "Mesh repair: degenerate/duplicate faces, specks, non-manifold edges and vertices, small "
      "holes";
  type.doc =
      "Makes a reconstructed mesh 2-manifold, in this order: removes faces with a repeated "
      "vertex or an area below `min_area_m2`; removes duplicate faces (same three vertices, "
      "either orientation; the first is kept); where an edge has more than two faces, keeps "
      "the two largest (faces are accepted by decreasing area, ties by index); where an edge's two faces run it the same way, drops the smaller; removes "
      "connected components with fewer faces than `min_component_faces` (or "
      "`min_component_fraction` of the largest) that are also smaller than "
      "`min_component_area_m2` (a decimated flat wall may be 2 faces); splits every vertex whose faces form several fans into one vertex per "
      "fan (attributes copied); fills the holes whose boundary loop has at most "
      "`fill_hole_edges` edges or a perimeter of at most `fill_hole_spacings` point spacings "
      "(CGAL's triangulation of the loop, no new vertices; a patch that would make an edge "
      "non-manifold is skipped); drops unreferenced vertices. Face order is kept (the patches "
      "come last), so the result is deterministic.\n\n"
      "Counters: `faces_in`, `vertices_in`, `degenerate_faces`, `duplicate_faces`, "
      "`nonmanifold_edge_faces`, `misoriented_faces`, `small_components`, `small_component_faces`, "
      "`split_vertices`, `boundary_loops`, `holes_filled`, `hole_faces`, `unreferenced_vertices`, `faces_out`, `vertices_out`. Phases: `io`, "
      "`compute`.";
  type.params_schema = kSchema;
  type.inputs = {{"mesh", "mesh", "The mesh to clean (mesh.ply).", false}};
  type.outputs = {{"mesh", "mesh", "The manifold mesh.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
