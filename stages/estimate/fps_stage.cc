// estimate.fps: the frame rate a device profile predicts for a textured mesh
// (model: stages/estimate/fps_model.h; calibration: docs/fps.md).
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/stage.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/core/table.h"
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

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const std::string device_path, StringParam(ctx, kId, "device"));
  Expected<DeviceProfile> device = ReadDeviceProfile(device_path);
  if (!device.ok()) return device.status().WithContext(kId);

  std::vector<TextureSize> maps;
  for (const char* port : {"color", "normal"}) {
    if (!ctx.has_input(port)) continue;
    PB_ASSIGN_OR_RETURN(const TextureSize size, InputImageSize(ctx, port));
    maps.push_back(size);
  }
  PB_ASSIGN_OR_RETURN(InputMesh input, ReadInputMesh(ctx, kId, 0.8));

  FpsEstimate estimate;
  {
    PB_PHASE(ctx, "compute");
    estimate = EstimateFrameRate(*device, input.mesh.face_count(), maps);
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
      "texel, compared with its texture budget. The Oculus Go profile is calibrated on the "
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
      {"normal", "image", "Normal map (PNG or OpenEXR); its size counts toward texture memory.", true}};
  type.outputs = {{"table", "table", "The estimate, one row (table.json).", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
