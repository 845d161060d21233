// The `viewpoints` parameter shared by the render stages (render.frames,
// render.splats): a scene's `viewpoints:` list read into cameras and frame
// entries, so that every render of a scene uses the same names, files and
// cameras.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "base/status.h"
#include "engine/stage.h"
#include "stages/geometry/io/frames.h"
#include "stages/geometry/render/render.h"

namespace pb {

// The JSON schema of the `viewpoints` parameter (an object schema's property
// value); it repeats schemas/scene.schema.json's items so that a workflow can
// pass `viewpoints: ${scene.viewpoints}` unchanged.
inline constexpr const char* kViewpointsSchema = R"({
      "type": "array",
      "minItems": 1,
      "description": "Views to render, as a scene's `viewpoints` (pass ${scene.viewpoints}): eye and target in scene coordinates (meters), optional up (default [0, 0, 1]), vertical fov_deg (default 60) and name (default view<N>, N counted from 1).",
      "items": {
        "type": "object",
        "required": ["eye", "target"],
        "additionalProperties": false,
        "properties": {
          "name": { "type": "string", "description": "Frame name, unique; also the PNG's name." },
          "eye": { "type": "array", "items": { "type": "number" }, "minItems": 3, "maxItems": 3, "description": "Camera position, meters." },
          "target": { "type": "array", "items": { "type": "number" }, "minItems": 3, "maxItems": 3, "description": "Point looked at, meters." },
          "up": { "type": "array", "items": { "type": "number" }, "minItems": 3, "maxItems": 3, "description": "Up direction (default [0, 0, 1])." },
          "fov_deg": { "type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 180, "description": "Vertical field of view, degrees (default 60)." }
        }
      }
    })";

// `schema` (a stage's parameter schema) with the token "VIEWPOINTS_SCHEMA"
// replaced by kViewpointsSchema.
std::string WithViewpointsSchema(std::string schema);

struct View {
  FrameEntry entry;     // name, PNG file (the name's letters, digits, '-', '_', '.'; else '_'), viewpoint
  RenderCamera camera;  // of `size` x `size` pixels
};

// The depth map's file name beside frame file `png_file`: "door.png" ->
// "door.depth.exr".
std::string DepthFileName(const std::string& png_file);
// The sample mask's file name beside frame file `png_file` (render.splats):
// "door.png" -> "door.samples.png".
std::string SamplesFileName(const std::string& png_file);

// Reads parameter `viewpoints` of the stage `stage_id` (errors name it and
// the item: "render.frames: viewpoints[1].eye: must be finite").
Expected<std::vector<View>> ReadViewpoints(const StageContext& ctx, std::string_view stage_id, int size);

// Reads the optional parameter `background` (3 integers in [0, 255], or a
// string "R,G,B", which --set and a campaign's set: can give) into
// `rgb`, which keeps its value when the parameter is absent.
Status ReadBackground(const StageContext& ctx, std::string_view stage_id, std::array<uint8_t, 3>* rgb);

// Writes `frames` as the stage's output port "frames" (frames.json, PNGs and
// depth maps, one durable set).
Status WriteFramesOutput(StageContext& ctx, const FrameSet& frames);

}  // namespace pb
