// export.vtp: a mesh and its baked maps as VTK XML PolyData for ParaView
// (stages/geometry/io/vtp.h), the maps as PNGs beside it.
#include <string>
#include <utility>

#include "engine/stage.h"
#include "stages/builtin.h"
#include "stages/export/export_io.h"
#include "stages/geometry/io/vtp.h"

namespace pb {
namespace {

constexpr const char* kId = "export.vtp";

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(ExportInputs inputs, ReadExportInputs(ctx, kId));
  const Mesh& mesh = inputs.mesh;
  VtpWriteOptions options;
  // The maps' file names in the field data (ParaView applies a texture chosen
  // by hand, Properties > Texture; docs/export.md), and the maps beside the
  // .vtp as one durable set with it.
  if (!inputs.color_png.empty()) {
    options.field_data.push_back({"BaseColorTexture", "color.png"});
    options.companions.push_back({ctx.output_path("model", "color.png"), inputs.color_png});
  }
  if (!inputs.normal_png.empty()) {
    options.field_data.push_back({"NormalTexture", "normal.png"});
    options.companions.push_back({ctx.output_path("model", "normal.png"), inputs.normal_png});
  }
  uint64_t bytes = 0;
  {
    PB_PHASE(ctx, "io");
    const std::string path = ctx.output_path("model", "model.vtp");
    if (Status s = WriteVtp(path, mesh, options, &bytes); !s.ok()) return s.WithContext(kId);
  }
  bytes += inputs.color_png.size() + inputs.normal_png.size();
  ctx.counter("faces", static_cast<double>(mesh.face_count()));
  ctx.counter("vertices", static_cast<double>(mesh.vertex_count()));
  ctx.counter("bytes", static_cast<double>(bytes));  // all files
  ctx.set_output_meta("model", ExportMetaWith(ctx, mesh, "vtp", bytes,
                                              {{"color_texture", !inputs.color_png.empty()},
                                               {"normal_texture", !inputs.normal_png.empty()},
                                               {"vertex_colors", mesh.has_colors()},
                                               {"normals", mesh.has_normals()},
                                               {"tangents", mesh.has_tangents()}}));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType VtpExportStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary =
      "Export a mesh and its color and normal maps as VTK XML PolyData (.vtp) + PNG, for ParaView";
  type.doc =
      "Writes model.vtp (stages/geometry/io/vtp.h: absolute coordinates in double precision, "
      "triangles, and the mesh's per-vertex attributes: `Normals` and `TCoords` (uvs, v up) as "
      "VTK's normal and texture-coordinate attributes, `Colors` (sRGB bytes), `Tangents` (xyz + "
      "handedness w)) and the maps as color.png and normal.png beside it (8-bit PNGs byte for "
      "byte; 16-bit PNGs and float EXRs converted to 8-bit), named in the field data "
      "(`BaseColorTexture`, `NormalTexture`). ParaView opens model.vtp; the color map is applied "
      "with Properties > Texture (docs/export.md). Textures need a mesh with uvs.\n\n"
      "Counters: `faces`, `vertices`, `bytes` (all files together).";
  type.params_schema = R"({"type": "object", "additionalProperties": false, "properties": {}})";
  type.inputs = ExportInputPorts();
  type.outputs = {{"model", "model", "The model (model.vtp, color.png, normal.png).", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
