// bake.from_mesh: color and normal maps of a low mesh with uvs from a high
// mesh with vertex colors, by ray casting (stages/geometry/bake/from_mesh.h).
#include <string>
#include <utility>

#include "engine/stage.h"
#include "stages/bake/bake_io.h"
#include "stages/builtin.h"
#include "stages/geometry/bake/from_mesh.h"
#include "stages/geometry/io/ply.h"
#include "stages/mesh_io.h"
#include "stages/params.h"

namespace pb {
namespace {

constexpr const char* kId = "bake.from_mesh";

std::string Schema() {
  return std::string(R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {)") +
         BakeCommonSchemaProperties() + R"(,
    "cage": {
      "type": "number",
      "exclusiveMinimum": 0,
      "default": 0.05,
      "description": "How far rays search for the source surface, in meters, forwards and backwards along the target's interpolated normal from each texel's point; the nearer hit wins. Texels with no hit within this distance keep the target's own vertex colors and a flat normal. Larger than the largest gap between the two surfaces, smaller than the thickness of thin parts (a larger cage can hit the far side)."
    }
  }
})";
}

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(BakeOptions options, ReadBakeOptions(ctx, kId));
  FromMeshOptions from_mesh;
  PB_ASSIGN_OR_RETURN(from_mesh.cage_m, NumberParam(ctx, kId, "cage"));
  if (!(from_mesh.cage_m > 0)) {
    return Status::Invalid(std::string(kId) + ": parameter 'cage' must be > 0 meters, got " +
                           std::to_string(from_mesh.cage_m));
  }
  PB_ASSIGN_OR_RETURN(const std::string source_path,
                      InputFilePath(ctx, kId, "source", "mesh.ply"));

  PB_ASSIGN_OR_RETURN(InputMesh input, ReadInputMesh(ctx, kId, 0.1));
  Mesh source;
  {
    PB_PHASE(ctx, "io");
    PlyReadOptions read;
    read.progress = [&ctx](double fraction) { ctx.progress(0.1 + 0.2 * fraction); };
    PB_ASSIGN_OR_RETURN(PlyMesh ply, ReadPlyMesh(source_path, read));
    source = std::move(ply.mesh);
  }

  options.progress = [&ctx](double fraction) { ctx.progress(0.3 + 0.6 * fraction); };
  FromMeshReport report;
  BakeResult result;
  {
    PB_PHASE(ctx, "compute");
    auto baked = BakeFromMesh(std::move(input.mesh), source, options, from_mesh, &report);
    if (!baked.ok()) {
      return baked.status().WithContext(std::string(kId) + " (mesh " + input.path + ", source " +
                                        source_path + ")");
    }
    result = std::move(*baked);
  }
  source = Mesh();  // not needed for writing: free it first

  ctx.counter("texels_hit", static_cast<double>(report.texels_hit));
  ctx.counter("texels_fallback", static_cast<double>(report.texels_fallback));
  PB_RETURN_IF_ERROR(WriteBakeOutputs(ctx, kId, result,
                                      {{"cage_m", from_mesh.cage_m},
                                       {"texels_hit", report.texels_hit},
                                       {"texels_fallback", report.texels_fallback},
                                       {"mean_hit_distance_m", report.mean_hit_distance_m}}));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType FromMeshBakeStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary =
      "Color and normal maps of a low mesh from a high mesh with vertex colors, by ray casting";
  type.doc =
      "Blender's \"selected to active\" bake, the paper's Remeshing workflow. For every texel "
      "of the `mesh` input's atlas, two rays leave the texel's point on the low surface along "
      "its interpolated normal, forwards and backwards, up to `cage` meters; the nearer hit "
      "on `source` (forwards on a tie) gives the color (the hit triangle's vertex colors, "
      "interpolated) and the normal (its vertex normals, computed when the source has none), "
      "stored in the texel's tangent frame. Texels without a hit keep the low mesh's own "
      "interpolated vertex colors (black without) and a flat normal. Then `gutter` rings of "
      "dilation. The two meshes may have different origins. Rays are cast with Embree; the "
      "maps are the same whatever the thread count. The source needs vertex colors.\n\n"
      "Counters: `texels_hit`, `texels_fallback` (covered texels with no hit within the "
      "cage), `covered_texels`, `edge_texels`, `gutter_texels`. The output meta's `bake` "
      "object adds `cage_m`, `texels_hit`, `texels_fallback` and `mean_hit_distance_m`.";
  type.params_schema = Schema();
  type.inputs = {
      {"mesh", "mesh", "The low mesh to bake onto, with uvs (mesh.ply).", false},
      {"source", "mesh", "The high mesh with vertex colors the rays hit (mesh.ply).", false}};
  type.outputs = BakeOutputPorts();
  type.run = &Run;
  return type;
}

}  // namespace pb
