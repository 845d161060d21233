// The export family: `export.gltf` (model.glb) and `export.obj` (model.obj +
// model.mtl + color.png + normal.png), from a mesh and optional baked color
// and normal maps (stages/geometry/gltf.h, obj.h).
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include "engine/base/status.h"
#include "engine/stage.h"

namespace pb {

void RegisterExportStages(StageRegistry& registry);

StageType GltfExportStage();
StageType ObjExportStage();

// Shared by the export stages: the PNG bytes for texture input `port`, empty
// when the port is not connected. An 8-bit PNG is passed through byte for
// byte; a 16-bit PNG is reduced to 8 bits; a float EXR is encoded as 8-bit
// PNG: color maps from linear to sRGB, normal maps from [-1,1] to
// (n + 1) / 2 * 255. Status naming the stage, port and file otherwise.
Expected<std::vector<uint8_t>> TexturePng(const StageContext& ctx, std::string_view stage_id,
                                          std::string_view port, bool normal_map);

}  // namespace pb
