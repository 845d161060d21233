// export.gltf: a mesh and its baked maps as binary glTF 2.0
// (stages/geometry/io/gltf.h).
#include <string>
#include <utility>
#include <vector>

#include "engine/stage.h"
#include "stages/builtin.h"
#include "stages/export/export_io.h"
#include "stages/export/ktx2_encode.h"
#include "stages/geometry/io/gltf.h"
#include "stages/geometry/mesh/vertex_order.h"
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
    },
    "textures": {
      "enum": ["png", "ktx2"],
      "default": "png",
      "description": "How the maps are embedded. `png`: lossless PNG (every glTF reader, Blender 3.4 included). `ktx2`: Basis Universal in KTX2 through KHR_texture_basisu (required extension, no PNG fallback): the color map as ETC1S (sRGB), the normal map as UASTC (linear), both with full mip chains, for mobile GPUs and WebXR (4 to 8 times less GPU memory than RGBA8). Needs Node.js and the npm packages of tools/ (npm ci --prefix tools)."
    },
    "vertex_order": {
      "enum": ["mesh", "optimized"],
      "default": "mesh",
      "description": "`mesh`: triangles and vertices in the mesh's order. `optimized`: reordered for the GPU's vertex cache, then vertices for fetch locality (meshoptimizer); the same triangles, unreferenced vertices dropped."
    }
  }
})";

// The maps of `inputs` as KTX2 into `options` (ETC1S color, UASTC normal).
// `encoders`: the encoder's name and version (ktx2_encode.h: it depends on
// the map's size), each map's when they differ; "" without maps.
Status EncodeMaps(StageContext& ctx, ExportInputs& inputs, GltfWriteOptions& options,
                  std::string& encoders) {
  PB_PHASE(ctx, "encode");
  std::vector<std::pair<std::string, std::string>> used;  // (encoder, map)
  if (!inputs.color_png.empty()) {
    PB_ASSIGN_OR_RETURN(const Image color, TextureImage8(ctx, kId, "color", false));
    std::string encoder;
    PB_ASSIGN_OR_RETURN(options.base_color_ktx2, EncodeKtx2(color, Ktx2Mode::kEtc1sSrgb,
                                                            std::string(kId) + ": the color map", &encoder));
    used.emplace_back(encoder, "color");
    ctx.progress(0.6);
  }
  if (!inputs.normal_png.empty()) {
    PB_ASSIGN_OR_RETURN(const Image normal, TextureImage8(ctx, kId, "normal", true));
    std::string encoder;
    PB_ASSIGN_OR_RETURN(options.normal_ktx2, EncodeKtx2(normal, Ktx2Mode::kUastcLinear,
                                                        std::string(kId) + ": the normal map", &encoder));
    used.emplace_back(encoder, "normal");
  }
  if (used.size() == 2 && used[0].first != used[1].first) {
    encoders = used[0].first + " (color), " + used[1].first + " (normal)";
  } else if (!used.empty()) {
    encoders = used[0].first;
  }
  inputs.color_png.clear();
  inputs.normal_png.clear();
  ctx.progress(0.8);
  return Status::Ok();
}

Status Run(StageContext& ctx) {
  GltfWriteOptions options;
  PB_ASSIGN_OR_RETURN(options.name, StringParam(ctx, kId, "name"));
  PB_ASSIGN_OR_RETURN(options.vertex_colors, BoolParam(ctx, kId, "vertex_colors"));
  PB_ASSIGN_OR_RETURN(const std::string textures, StringParam(ctx, kId, "textures"));
  PB_ASSIGN_OR_RETURN(const std::string vertex_order, StringParam(ctx, kId, "vertex_order"));
  PB_ASSIGN_OR_RETURN(ExportInputs inputs, ReadExportInputs(ctx, kId));
  std::string encoders;
  if (textures == "ktx2") PB_RETURN_IF_ERROR(EncodeMaps(ctx, inputs, options, encoders));
  options.base_color_png = std::move(inputs.color_png);
  options.normal_png = std::move(inputs.normal_png);
  Mesh& mesh = inputs.mesh;
  nlohmann::json vertex_order_meta = "mesh";
  if (vertex_order == "optimized") {
    PB_PHASE(ctx, "compute");
    VertexOrderReport order;
    OptimizeVertexOrder(mesh, &order);
    vertex_order_meta = {{"acmr_before", order.acmr_before}, {"acmr_after", order.acmr_after},
                         {"overfetch_before", order.overfetch_before},
                         {"overfetch_after", order.overfetch_after}};
    ctx.counter("acmr", order.acmr_after);
  }
  GltfWriteReport report;
  {
    PB_PHASE(ctx, "io");
    const Status status = WriteGlb(ctx.output_path("model", "model.glb"), mesh, options, &report);
    if (!status.ok()) return status.WithContext(kId);
  }
  ctx.counter("faces", static_cast<double>(mesh.face_count()));
  ctx.counter("vertices", static_cast<double>(mesh.vertex_count()));
  ctx.counter("bytes", static_cast<double>(report.bytes));
  const bool color = !options.base_color_png.empty() || !options.base_color_ktx2.empty();
  const bool normal = !options.normal_png.empty() || !options.normal_ktx2.empty();
  nlohmann::json changes = {
       {"color_texture", color},
       {"normal_texture", normal},
       {"vertex_colors", report.wrote_colors},
       {"normals", report.computed_normals ? "computed" : "mesh"},
       {"tangents", !report.wrote_tangents     ? "none"
                    : report.computed_tangents ? "computed"
                                               : "mesh"}};
  // Only the options' own keys, so the default output's meta is unchanged.
  if (textures == "ktx2") {
    changes["textures"] = "ktx2";
    changes["ktx2_encoder"] = encoders.empty() ? Ktx2EncoderVersion() : encoders;
  }
  if (vertex_order == "optimized") changes["vertex_order"] = vertex_order_meta;
  nlohmann::json meta = ExportMetaWith(ctx, mesh, "glb", report.bytes, changes);
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
      "Mobile-ready variant: `textures: ktx2` embeds the maps as Basis Universal KTX2 "
      "(KHR_texture_basisu; ETC1S color, UASTC normal, mip chains) and `vertex_order: "
      "optimized` reorders triangles and vertices for the GPU's caches (meshoptimizer). Blender "
      "3.4 cannot read KTX2: workflows export the PNG model too.\n\n"
      "Counters: `faces`, `vertices`, `bytes` (size of model.glb), `acmr` (with `vertex_order: "
      "optimized`: vertices transformed per triangle, 16-entry FIFO cache).";
  type.params_schema = kSchema;
  type.inputs = ExportInputPorts();
  type.outputs = {{"model", "model", "The model (model.glb).", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
