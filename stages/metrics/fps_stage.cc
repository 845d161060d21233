// estimate.fps: the frame rate a device profile predicts for a textured mesh
// (model: stages/metrics/fps_model.h; calibration: docs/fps.md).
#include <algorithm>
#include <array>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "engine/stage.h"
#include "stages/geometry/table.h"
#include "stages/mesh/mesh_io.h"
#include "stages/metrics/fps_model.h"
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

uint32_t BigEndian32(const unsigned char* p) {
  return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | uint32_t(p[3]);
}
int32_t LittleEndian32(const unsigned char* p) {
  return static_cast<int32_t>(uint32_t(p[0]) | (uint32_t(p[1]) << 8) | (uint32_t(p[2]) << 16) |
                              (uint32_t(p[3]) << 24));
}

// Width and height from a PNG's IHDR chunk.
Expected<TextureSize> PngSize(std::ifstream& in, const std::string& path) {
  std::array<unsigned char, 24> head{};
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(head.data()), head.size()) ||
      std::string(reinterpret_cast<const char*>(head.data() + 12), 4) != "IHDR") {
    return Status::Corrupt(path + ": truncated PNG: no IHDR chunk after the signature");
  }
  const uint32_t width = BigEndian32(head.data() + 16);
  const uint32_t height = BigEndian32(head.data() + 20);
  if (width == 0 || height == 0 || width > 0x7fffffffu || height > 0x7fffffffu) {
    return Status::Corrupt(path + ": PNG IHDR gives an invalid size " + std::to_string(width) +
                           "x" + std::to_string(height));
  }
  return TextureSize{static_cast<int>(width), static_cast<int>(height)};
}

// Width and height from an OpenEXR header's dataWindow (box2i) attribute.
Expected<TextureSize> ExrSize(std::ifstream& in, const std::string& path) {
  in.seekg(8);  // magic + version
  auto read_name = [&](std::string* out) {
    out->clear();
    char c;
    while (in.get(c) && c != '\0') {
      if (out->size() > 255) return false;
      *out += c;
    }
    return static_cast<bool>(in);
  };
  std::string name, type;
  while (read_name(&name) && !name.empty()) {
    unsigned char size_bytes[4];
    if (!read_name(&type) || !in.read(reinterpret_cast<char*>(size_bytes), 4)) break;
    const int32_t size = LittleEndian32(size_bytes);
    if (size < 0) break;
    if (name == "dataWindow" && type == "box2i" && size == 16) {
      unsigned char box[16];
      if (!in.read(reinterpret_cast<char*>(box), 16)) break;
      const int64_t width = int64_t(LittleEndian32(box + 8)) - LittleEndian32(box) + 1;
      const int64_t height = int64_t(LittleEndian32(box + 12)) - LittleEndian32(box + 4) + 1;
      if (width <= 0 || height <= 0 || width > 0x7fffffff || height > 0x7fffffff) {
        return Status::Corrupt(path + ": OpenEXR dataWindow gives an invalid size");
      }
      return TextureSize{static_cast<int>(width), static_cast<int>(height)};
    }
    in.seekg(size, std::ios::cur);
  }
  return Status::Corrupt(path + ": OpenEXR header without a readable dataWindow attribute");
}

// The size of image input `port`: from the file's PNG or OpenEXR header,
// else from the width/height of the input's meta.
Expected<TextureSize> InputImageSize(const StageContext& ctx, const char* port) {
  PB_ASSIGN_OR_RETURN(const std::string path, InputFilePath(ctx, kId, port));
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::NotFound(std::string(kId) + ": input '" + port + "': cannot open " + path);
  std::array<unsigned char, 8> magic{};
  in.read(reinterpret_cast<char*>(magic.data()), magic.size());
  static constexpr unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  Expected<TextureSize> size = Status::Unsupported("");
  if (in && std::equal(magic.begin(), magic.end(), kPng)) {
    size = PngSize(in, path);
  } else if (in && magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01) {
    size = ExrSize(in, path);
  } else {
    const nlohmann::json& meta = ctx.input(port).meta;
    if (meta.value("width", 0) > 0 && meta.value("height", 0) > 0) {
      return TextureSize{meta.value("width", 0), meta.value("height", 0)};
    }
    return Status::Unsupported(std::string(kId) + ": input '" + port + "': " + path +
                               " is neither PNG nor OpenEXR and its meta has no width/height");
  }
  if (!size.ok()) return size.status().WithContext(std::string(kId) + ": input '" + port + "'");
  return size;
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
