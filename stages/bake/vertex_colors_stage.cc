// bake.vertex_colors: color map from the mesh's own vertex colors, flat
// normal map (the paper's HPM and LPM workflows; stages/geometry/bake/bake.h).
#include <string>
#include <utility>

#include "engine/stage.h"
#include "stages/bake/bake_io.h"
#include "stages/builtin.h"
#include "stages/geometry/bake/bake.h"
#include "stages/mesh_io.h"

namespace pb {
namespace {

constexpr const char* kId = "bake.vertex_colors";

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(BakeOptions options, ReadBakeOptions(ctx, kId));
  PB_ASSIGN_OR_RETURN(InputMesh input, ReadInputMesh(ctx, kId, 0.2));
  options.progress = [&ctx](double fraction) { ctx.progress(0.2 + 0.6 * fraction); };
  BakeResult result;
  {
    PB_PHASE(ctx, "compute");
    auto baked = BakeVertexColors(std::move(input.mesh), options);
    if (!baked.ok()) return baked.status().WithContext(input.path);
    result = std::move(*baked);
  }
  PB_RETURN_IF_ERROR(WriteBakeOutputs(ctx, kId, result, nlohmann::json::object()));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType VertexColorsBakeStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Color map from the mesh's vertex colors, flat normal map (HPM, LPM)";
  type.doc =
      "Rasterizes every face in UV space (texel centres; texels a face only touches sample the "
      "face's nearest point) and interpolates its vertex colors (sRGB values as stored) at each "
      "texel; the normal map is flat, (0, 0, 1) in tangent space, since the mesh has no detail "
      "finer than its vertices. Then `gutter` passes of dilation. The output mesh carries the "
      "tangent frames (computed from normals and uvs) the maps are meant for; export it with "
      "the maps. Deterministic whatever the thread count.\n\n"
      "Counters: `covered_texels`, `edge_texels` (of those, texels sampled at the face's "
      "nearest point), `gutter_texels`.";
  type.params_schema = std::string(R"({"type": "object", "additionalProperties": false, "properties": {)") +
                       BakeCommonSchemaProperties() + "}}";
  type.inputs = {{"mesh", "mesh", "The mesh to bake, with uvs and vertex colors (mesh.ply).", false}};
  type.outputs = BakeOutputPorts();
  type.run = Run;
  return type;
}

}  // namespace pb
