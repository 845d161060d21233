#include "stages/bake/bake_io.h"

#include <tbb/parallel_invoke.h>

#include <utility>

#include "stages/geometry/core/image.h"
#include "stages/mesh_io.h"
#include "stages/params.h"

namespace pb {

std::string BakeCommonSchemaProperties() {
  return R"(
    "size": {
      "type": "integer",
      "minimum": 16,
      "maximum": 16384,
      "default": 4096,
      "description": "Width and height of the color and normal maps, in texels (the authors used 8192). Match uv.unwrap's size so its gutters are as planned."
    },
    "gutter": {
      "type": "integer",
      "minimum": 0,
      "maximum": 64,
      "default": 12,
      "description": "Dilation passes around the baked texels, so mipmaps and bilinear filtering at chart borders do not bleed background (the authors' 25x25 dilation is 12)."
    },
    "normal_format": {
      "type": "string",
      "enum": ["png", "exr"],
      "default": "png",
      "description": "png: 8-bit tangent-space normal map, (n + 1) / 2 * 255. exr: float OpenEXR with n in [-1, 1], for tools that want full precision."
    })";
}

Expected<BakeOptions> ReadBakeOptions(const StageContext& ctx, std::string_view stage_id) {
  BakeOptions options;
  PB_ASSIGN_OR_RETURN(const int64_t size, IntegerParam(ctx, stage_id, "size", {16, 16384}));
  PB_ASSIGN_OR_RETURN(const int64_t gutter, IntegerParam(ctx, stage_id, "gutter", {0, 64}));
  PB_ASSIGN_OR_RETURN(const std::string format, StringParam(ctx, stage_id, "normal_format"));
  if (format != "png" && format != "exr") {
    return Status::Invalid(std::string(stage_id) +
                           ": parameter 'normal_format' must be 'png' or 'exr', got '" + format +
                           "'");
  }
  options.size = static_cast<int>(size);
  options.gutter = static_cast<int>(gutter);
  options.float_normals = format == "exr";
  options.threads = ctx.threads();
  return options;
}

std::vector<PortSpec> BakeOutputPorts() {
  return {{"mesh", "mesh",
           "The target mesh with normals, uvs and tangent frames, the frames the normal map is "
           "expressed in (mesh.ply).",
           false},
          {"color", "image", "Color map, 8-bit sRGB RGB (color.png).", false},
          {"normal", "image",
           "Tangent-space normal map (normal.png, 8-bit; or normal.exr, float, with "
           "normal_format: exr).",
           false}};
}

Status WriteBakeOutputs(StageContext& ctx, std::string_view stage_id, const BakeResult& result,
                        const nlohmann::json& bake_meta) {
  const bool exr = result.maps.normal.type == Image::PixelType::kF32;
  {
    PB_PHASE(ctx, "io");
    const std::string color_path = ctx.output_path("color", "color.png");
    const std::string normal_path = ctx.output_path("normal", exr ? "normal.exr" : "normal.png");
    // The two maps encode at the same time (within the stage's thread arena):
    // each is one thread's work for ~0.5 s at 4096^2.
    Status color_status, normal_status;
    tbb::parallel_invoke([&] { color_status = WritePng(color_path, result.maps.color); },
                         [&] { normal_status = WriteImage(normal_path, result.maps.normal); });
    if (!color_status.ok()) return color_status.WithContext(std::string(stage_id) + ": " + color_path);
    if (!normal_status.ok())
      return normal_status.WithContext(std::string(stage_id) + ": " + normal_path);
  }
  const int size = result.maps.color.width;
  nlohmann::json bake = {{"stage", stage_id},
                         {"size", size},
                         {"covered_texels", result.covered_texels},
                         {"edge_texels", result.edge_texels},
                         {"gutter_texels", result.gutter_texels},
                         {"coverage", double(result.covered_texels) / (double(size) * size)}};
  bake.update(bake_meta);
  nlohmann::json mesh_meta =
      InputMeshMetaWith(ctx, result.mesh, {{"has_tangents", result.mesh.has_tangents()}, {"bake", bake}});
  PB_RETURN_IF_ERROR(WriteOutputMesh(ctx, result.mesh, std::move(mesh_meta)));
  ctx.set_output_meta("color", {{"kind", "color"}, {"width", size}, {"height", size},
                                {"encoding", "srgb8"}, {"bake", bake}});
  ctx.set_output_meta("normal", {{"kind", "normal"}, {"space", "tangent"}, {"width", size},
                                 {"height", size}, {"encoding", exr ? "float" : "unorm8"},
                                 {"bake", bake}});
  ctx.counter("covered_texels", static_cast<double>(result.covered_texels));
  ctx.counter("edge_texels", static_cast<double>(result.edge_texels));
  ctx.counter("gutter_texels", static_cast<double>(result.gutter_texels));
  return Status::Ok();
}

}  // namespace pb
