// What the three bake stages share at the stage level: the common
// parameters (size, gutter, normal_format), the output ports, and writing a
// BakeResult as the outputs
//   mesh   mesh.ply   the target mesh with normals, uvs and tangents
//   color  color.png  8-bit sRGB RGB
//   normal normal.png 8-bit tangent-space RGB, or normal.exr (float,
//                     [-1, 1]) with normal_format: exr
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "base/status.h"
#include "engine/stage.h"
#include "stages/geometry/bake/bake.h"

namespace pb {

// The JSON Schema properties every bake stage has ("size", "gutter",
// "normal_format"), as the text of object members without the braces, to
// splice into a stage's schema: R"({"type":"object", ..., "properties": {)"
// + BakeCommonSchemaProperties() + R"(, "cage": {...}}})".
std::string BakeCommonSchemaProperties();

// size, gutter, normal_format -> BakeOptions (threads from the context;
// progress left unset).
Expected<BakeOptions> ReadBakeOptions(const StageContext& ctx, std::string_view stage_id);

// The ports every bake stage writes.
std::vector<PortSpec> BakeOutputPorts();

// Writes the three outputs inside an "io" phase, sets their meta (the mesh
// input's meta with the bake's facts under "bake": stage, size, gutter,
// texel counts, and `bake_meta`'s keys) and the counters covered_texels,
// edge_texels, gutter_texels.
Status WriteBakeOutputs(StageContext& ctx, std::string_view stage_id, const BakeResult& result,
                        const nlohmann::json& bake_meta);

}  // namespace pb
