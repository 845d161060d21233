// export.obj: a mesh and its baked maps as Wavefront OBJ + MTL + PNG
// (stages/geometry/io/obj.h).
#include <string>
#include <utility>

#include "engine/stage.h"
#include "stages/builtin.h"
#include "stages/export/export_io.h"
#include "stages/geometry/io/obj.h"
#include "stages/params.h"

namespace pb {
namespace {

constexpr const char* kId = "export.obj";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "name": {
      "type": "string",
      "minLength": 1,
      "default": "model",
      "description": "Name of the object and material inside the files (the files are always model.obj, model.mtl, color.png, normal.png)."
    },
    "vertex_colors": {
      "type": "boolean",
      "default": true,
      "description": "Write the mesh's vertex colors on the `v` lines (the extension MeshLab and Blender read)."
    },
    "coordinates": {
      "type": "string",
      "enum": ["absolute", "relative"],
      "default": "absolute",
      "description": "`absolute`: v lines hold origin + position in double precision (georeferenced). `relative`: v lines hold the positions relative to the origin (written in a `# origin` comment), for viewers that keep float32 coordinates (Blender, MeshLab), which round coordinates of millions of meters to decimeters."
    }
  }
})";

Status Run(StageContext& ctx) {
  ObjWriteOptions options;
  PB_ASSIGN_OR_RETURN(options.name, StringParam(ctx, kId, "name", "model"));
  PB_ASSIGN_OR_RETURN(options.vertex_colors, BoolParam(ctx, kId, "vertex_colors", true));
  PB_ASSIGN_OR_RETURN(const std::string coordinates, StringParam(ctx, kId, "coordinates", "absolute"));
  if (coordinates != "absolute" && coordinates != "relative") {
    return Status::Invalid(std::string(kId) + ": parameter 'coordinates' must be \"absolute\" or \"relative\", got \"" +
                           coordinates + "\"");
  }
  options.absolute_coordinates = coordinates == "absolute";
  PB_ASSIGN_OR_RETURN(ExportInputs inputs, ReadExportInputs(ctx, kId));
  options.base_color_png = std::move(inputs.color_png);
  options.normal_png = std::move(inputs.normal_png);
  const Mesh& mesh = inputs.mesh;
  ObjWriteReport report;
  {
    PB_PHASE(ctx, "io");
    // Every file of the artifact is named to the engine, which keeps exactly
    // those; WriteObj puts them in one folder.
    const std::string obj_path = ctx.output_path("model", "model.obj");
    ctx.output_path("model", "model.mtl");
    if (!options.base_color_png.empty()) ctx.output_path("model", "color.png");
    if (!options.normal_png.empty()) ctx.output_path("model", "normal.png");
    const Status status = WriteObj(obj_path, mesh, options, &report);
    if (!status.ok()) return status.WithContext(kId);
  }
  ctx.counter("faces", static_cast<double>(mesh.face_count()));
  ctx.counter("vertices", static_cast<double>(mesh.vertex_count()));
  ctx.counter("bytes", static_cast<double>(report.bytes));  // all files
  nlohmann::json meta = ExportMetaWith(
      ctx, mesh, "obj", report.bytes,
      {{"coordinates", coordinates},
       {"color_texture", !options.base_color_png.empty()},
       {"normal_texture", !options.normal_png.empty()},
       {"vertex_colors", mesh.has_colors() && options.vertex_colors},
       {"normals", report.computed_normals ? "computed" : "mesh"}});
  ctx.set_output_meta("model", std::move(meta));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType ObjExportStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Export a mesh and its color and normal maps as OBJ + MTL + PNG";
  type.doc =
      "Writes model.obj (absolute coordinates by default: origin + position in double "
      "precision, OBJ having no node transform; `coordinates: relative` for float32 viewers; "
      "z up as our frames; uvs with v up; unit normals, computed "
      "when the mesh has none; vertex colors on the `v` lines), model.mtl (Kd 1 1 1, map_Kd "
      "color.png, map_Bump and norm normal.png) and the maps as color.png and normal.png "
      "(8-bit PNGs byte for byte; 16-bit PNGs and float EXRs converted to 8-bit). OBJ has no "
      "tangents: viewers derive them from uvs. Opens in MeshLab and Blender (Up axis Z). "
      "Textures need a mesh with uvs. See docs/export.md.\n\n"
      "Counters: `faces`, `vertices`, `bytes` (all files together).";
  type.params_schema = kSchema;
  type.inputs = ExportInputPorts();
  type.outputs = {{"model", "model", "The model (model.obj, model.mtl, color.png, normal.png).", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
