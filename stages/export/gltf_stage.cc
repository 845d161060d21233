// export.gltf: a mesh and its baked maps as binary glTF 2.0
// (stages/geometry/io/gltf.h).
#include <string>
#include <utility>

#include "engine/stage.h"
#include "stages/builtin.h"
#include "stages/export/export_io.h"
#include "stages/geometry/io/gltf.h"
#include "stages/params.h"

namespace pb {
namespace {

constexpr const char* kId = "export.gltf";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "name": {
      "type": "string",
      "minLength": 1,
      "default": "model",
      "description": "Name of the node, mesh and material inside the file (the file is always model.glb)."
    },
    "vertex_colors": {
      "type": "boolean",
      "default": true,
      "description": "Write the mesh's vertex colors as COLOR_0 when no `color` texture is connected. glTF multiplies COLOR_0 into the base color texture, so with a texture they are never written."
    }
  }
})";

Status Run(StageContext& ctx) {
  GltfWriteOptions options;
  PB_ASSIGN_OR_RETURN(options.name, StringParam(ctx, kId, "name", "model"));
  PB_ASSIGN_OR_RETURN(options.vertex_colors, BoolParam(ctx, kId, "vertex_colors", true));
  PB_ASSIGN_OR_RETURN(ExportInputs inputs, ReadExportInputs(ctx, kId));
  options.base_color_png = std::move(inputs.color_png);
  options.normal_png = std::move(inputs.normal_png);
  const Mesh& mesh = inputs.mesh;
  GltfWriteReport report;
  {
    PB_PHASE(ctx, "io");
    const Status status = WriteGlb(ctx.output_path("model", "model.glb"), mesh, options, &report);
    if (!status.ok()) return status.WithContext(kId);
  }
  ctx.counter("faces", static_cast<double>(mesh.face_count()));
  ctx.counter("vertices", static_cast<double>(mesh.vertex_count()));
  ctx.counter("bytes", static_cast<double>(report.bytes));
  nlohmann::json meta = ExportMetaWith(
      ctx, mesh, "glb", report.bytes,
      {{"color_texture", !options.base_color_png.empty()},
       {"normal_texture", !options.normal_png.empty()},
       {"vertex_colors", report.wrote_colors},
       {"normals", report.computed_normals ? "computed" : "mesh"},
       {"tangents", !report.wrote_tangents     ? "none"
                    : report.computed_tangents ? "computed"
                                               : "mesh"}});
  ctx.set_output_meta("model", std::move(meta));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType GltfExportStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Export a mesh and its color and normal maps as binary glTF 2.0 (model.glb)";
  type.doc =
      "Writes model.glb: positions (relative to a node translation that holds the mesh's "
      "origin, under a root node turning our z-up frame into glTF's y-up), unit normals "
      "(computed, area-weighted, when the mesh has none), TEXCOORD_0 with v flipped for glTF's "
      "top-left texture origin, TANGENT (the mesh's, else computed from uvs; handedness kept "
      "so a normal map baked in our convention renders the same), and a metal-free, fully "
      "rough PBR material with the `color` map as sRGB base color texture and the `normal` map "
      "as normal texture, both embedded as PNG (8-bit PNGs byte for byte; 16-bit PNGs and "
      "float EXRs converted to 8-bit). Vertex colors go to COLOR_0 (linear) only without a "
      "color texture. Textures need a mesh with uvs. Passes the Khronos glTF validator. See "
      "docs/export.md.\n\n"
      "Counters: `faces`, `vertices`, `bytes` (size of model.glb).";
  type.params_schema = kSchema;
  type.inputs = ExportInputPorts();
  type.outputs = {{"model", "model", "The model (model.glb).", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
