// estimate.fps: the frame rate a device profile predicts for a textured mesh
// (model: stages/estimate/fps_model.h; calibration: docs/fps.md).
#include <algorithm>
#include <array>
#include <optional>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/stage.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/core/table.h"
#include "stages/geometry/io/gltf.h"
#include "stages/geometry/io/ktx2.h"
#include "stages/mesh_io.h"
#include "stages/estimate/fps_model.h"
#include "stages/params.h"

namespace pb {
namespace {

constexpr const char* kId = "estimate.fps";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "required": ["device"],
  "properties": {
    "device": {
      "type": "string",
      "x-path": true,
      "description": "The device profile (YAML, e.g. configs/devices/oculus-go.yaml), relative to the file that names it: triangle throughput, refresh cap, texture budget and GPU texel format. Keyed by content, so editing the profile re-runs the estimate."
    }
  }
})";

// The size of image input `port`: from the file's PNG or OpenEXR header,
// else from the width/height of the input's meta.
Expected<TextureSize> InputImageSize(const StageContext& ctx, const char* port) {
  PB_ASSIGN_OR_RETURN(const std::string path, InputFilePath(ctx, kId, port));
  Expected<ImageSize> size = ReadImageSize(path);
  if (size.ok()) return TextureSize{size->width, size->height};
  if (size.status().code() == Status::Code::kUnsupported) {
    const nlohmann::json& meta = ctx.input(port).meta;
    if (meta.value("width", 0) > 0 && meta.value("height", 0) > 0) {
      return TextureSize{meta.value("width", 0), meta.value("height", 0)};
    }
    return Status::Unsupported(std::string(kId) + ": input '" + port + "': " + path +
                               " is neither PNG nor OpenEXR and its meta has no width/height");
  }
  return size.status().WithContext(std::string(kId) + ": input '" + port + "'");
}

// The KTX2 maps of input "model" (empty when it is not connected or its maps
// are PNG): [0] color, [1] normal, each absent as std::nullopt.
Expected<std::array<std::optional<CompressedMap>, 2>> ModelKtx2Maps(const StageContext& ctx) {
  std::array<std::optional<CompressedMap>, 2> maps;
  if (!ctx.has_input("model")) return maps;
  PB_ASSIGN_OR_RETURN(const std::string path, InputFilePath(ctx, kId, "model"));
  const std::string context = std::string(kId) + ": input 'model'";
  Expected<GlbModel> model = ReadGlb(path);
  if (!model.ok()) return model.status().WithContext(context);
  const std::vector<uint8_t>* ktx2[2] = {&model->base_color_ktx2, &model->normal_ktx2};
  for (int k = 0; k < 2; ++k) {
    if (ktx2[k]->empty()) continue;
    Expected<Ktx2Info> info = ReadKtx2Info(*ktx2[k], path + (k == 0 ? ": color map" : ": normal map"));
    if (!info.ok()) return info.status().WithContext(context);
    if (info->codec == Ktx2Codec::kOther) {
      return Status::Unsupported(context + ": " + path + ": a KTX2 map is neither ETC1S nor UASTC");
    }
    maps[k] = CompressedMap{{info->width, info->height}, Ktx2GpuBytes(*info)};
  }
  return maps;
}

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const std::string device_path, StringParam(ctx, kId, "device"));
  Expected<DeviceProfile> device = ReadDeviceProfile(device_path);
  if (!device.ok()) return device.status().WithContext(kId);

  PB_ASSIGN_OR_RETURN(const auto model_maps, ModelKtx2Maps(ctx));
  std::vector<TextureSize> maps;
  std::vector<CompressedMap> compressed;
  const char* ports[2] = {"color", "normal"};
  for (int k = 0; k < 2; ++k) {
    if (model_maps[k]) {  // the model's KTX2 map stands for the image input
      compressed.push_back(*model_maps[k]);
      continue;
    }
    if (!ctx.has_input(ports[k])) continue;
    PB_ASSIGN_OR_RETURN(const TextureSize size, InputImageSize(ctx, ports[k]));
    maps.push_back(size);
  }
  PB_ASSIGN_OR_RETURN(InputMesh input, ReadInputMesh(ctx, kId, 0.8));

  FpsEstimate estimate;
  {
    PB_PHASE(ctx, "compute");
    estimate = EstimateFrameRate(*device, input.mesh.face_count(), maps, compressed);
  }
  Table table;
  table.columns = {"device",        "triangles",           "texture_width",
                   "texture_height", "texture_bytes",      "texture_budget_bytes",
                   "fits_texture_budget", "triangles_per_s", "refresh_hz",
                   "fps"};
  table.rows = {{device->name, static_cast<int64_t>(estimate.triangles),
                 int64_t{estimate.texture_width}, int64_t{estimate.texture_height},
                 static_cast<int64_t>(estimate.texture_bytes), device->texture_budget_bytes,
                 estimate.fits_texture_budget, device->triangles_per_s, device->refresh_hz,
                 estimate.fps}};
  {
    PB_PHASE(ctx, "io");
    PB_RETURN_IF_ERROR(WriteTable(ctx.output_path("table", "table.json"), table));
  }
  ctx.set_output_meta("table", {{"kind", "fps_estimate"},
                                {"device", device->name},
                                {"mipmaps", device->mipmaps},
                                {"texture_format", compressed.empty() ? "profile" : "ktx2"},
                                {"texture_bytes_per_texel", device->texture_bytes_per_texel}});
  ctx.counter("fps", estimate.fps);
  ctx.counter("triangles", static_cast<double>(estimate.triangles));
  ctx.counter("texture_bytes", static_cast<double>(estimate.texture_bytes));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType FpsStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Estimate a mesh's frame rate and texture memory on a device profile";
  type.doc =
      "Predicts the frame rate of a textured mesh on a headset from a device profile "
      "(configs/devices/*.yaml): fps = min(refresh_hz, triangles_per_s / triangles), counting "
      "every triangle of the mesh (no culling). Texture memory is the color and normal maps' "
      "texels with full mip chains (when the profile says so) times the profile's bytes per "
      "texel, compared with its texture budget; a KTX2 map of the optional `model` input "
      "counts instead with its transcoded size (ETC1S as ETC2: 4 bits per texel; UASTC as ASTC "
      "4x4: 8 bits) over its stored mip levels (table meta `texture_format`: ktx2). The Oculus "
      "Go profile is calibrated on the "
      "paper's Table 4 (within 7 % on the three high meshes, 60 FPS on the low ones); fill "
      "rate, overdraw, draw calls and thermal throttling are not modeled (docs/fps.md).\n\n"
      "Output table (one row): `device`, `triangles`, `texture_width`, `texture_height` (the "
      "largest map's), `texture_bytes`, `texture_budget_bytes`, `fits_texture_budget`, "
      "`triangles_per_s`, `refresh_hz`, `fps`.\n\n"
      "Counters: `fps`, `triangles`, `texture_bytes`.";
  type.params_schema = kSchema;
  type.inputs = {
      {"mesh", "mesh", "The mesh to draw (mesh.ply); its faces are the triangle count.", false},
      {"color", "image", "Color map (PNG or OpenEXR); its size counts toward texture memory.", true},
      {"normal", "image", "Normal map (PNG or OpenEXR); its size counts toward texture memory.", true},
      {"model", "model",
       "The exported model (model.glb). Its KTX2 maps (export.gltf `textures: ktx2`) count with "
       "their GPU block sizes instead of the `color`/`normal` image they stand for.", true}};
  type.outputs = {{"table", "table", "The estimate, one row (table.json).", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
