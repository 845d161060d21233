// What the export family (`export.gltf`: model.glb; `export.obj`: model.obj +
// model.mtl + color.png + normal.png) shares: reading a mesh and optional
// baked color and normal maps (stages/geometry/io/gltf.h, obj.h).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "base/status.h"
#include "engine/stage.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/core/mesh.h"

namespace pb {

// Shared by the export stages: the PNG bytes for texture input `port`, empty
// when the port is not connected. An 8-bit PNG is passed through byte for
// byte; a 16-bit PNG is reduced to 8 bits; a float EXR is encoded as 8-bit
// PNG: color maps from linear to sRGB, normal maps from [-1,1] to
// (n + 1) / 2 * 255. Status naming the stage, port and file otherwise.
Expected<std::vector<uint8_t>> TexturePng(const StageContext& ctx, std::string_view stage_id,
                                          std::string_view port, bool normal_map);

// The image of texture input `port` as 8 bits per sample (converted as for
// TexturePng), e.g. to encode it as KTX2. Status naming the stage, port and
// file for anything but a PNG or EXR file.
Expected<Image> TextureImage8(const StageContext& ctx, std::string_view stage_id, std::string_view port,
                              bool normal_map);

// The input ports both export stages declare: mesh, and optional color and
// normal maps.
std::vector<PortSpec> ExportInputPorts();

// What both export stages read, in an "io" phase (progress 0..0.3): input
// "mesh" and the PNG bytes of the optional "color" and "normal" maps. A map
// with a mesh without uvs is a Status naming the file.
struct ExportInputs {
  std::string mesh_path;
  Mesh mesh;
  std::vector<uint8_t> color_png;   // empty: no color map
  std::vector<uint8_t> normal_png;  // empty: no normal map
};
Expected<ExportInputs> ReadExportInputs(StageContext& ctx, std::string_view stage_id);

// The exported model's meta: the mesh input's, with the facts every export
// shares (format, origin, counts, bytes), then `changes`.
nlohmann::json ExportMetaWith(const StageContext& ctx, const Mesh& mesh, std::string_view format,
                              uint64_t bytes, const nlohmann::json& changes);

}  // namespace pb
