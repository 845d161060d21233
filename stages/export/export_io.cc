#include "stages/export/export_io.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "stages/builtin.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/core/text_parse.h"
#include "stages/mesh_io.h"
#include "stages/params.h"

namespace pb {

namespace {

uint8_t ToByte(double value) { return static_cast<uint8_t>(std::lround(std::clamp(value, 0.0, 1.0) * 255.0)); }

// An 8-bit image from a 16-bit or float one (see TexturePng).
Image ToEightBit(const Image& image, bool normal_map) {
  Image out = Image::Make(image.width, image.height, image.channels, Image::PixelType::kU8);
  const size_t samples = image.sample_count();
  for (size_t i = 0; i < samples; ++i) {
    if (image.type == Image::PixelType::kU16) {
      out.data[i] = static_cast<uint8_t>((uint32_t(image.u16()[i]) * 255 + 32767) / 65535);
      continue;
    }
    const double value = image.f32()[i];
    const bool alpha = (image.channels == 2 || image.channels == 4) && i % image.channels == size_t(image.channels - 1);
    if (normal_map && !alpha) {
      out.data[i] = ToByte((value + 1) / 2);
    } else if (alpha) {
      out.data[i] = ToByte(value);
    } else {
      const double v = std::clamp(value, 0.0, 1.0);
      out.data[i] = ToByte(v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055);
    }
  }
  return out;
}

}  // namespace

Expected<std::vector<uint8_t>> TexturePng(const StageContext& ctx, std::string_view stage_id,
                                          std::string_view port, bool normal_map) {
  if (!ctx.has_input(port)) return std::vector<uint8_t>{};
  PB_ASSIGN_OR_RETURN(const std::string path, InputFilePath(ctx, stage_id, port));
  const std::string context = std::string(stage_id) + ": input '" + std::string(port) + "'";
  const std::string extension = LowerExtension(InputFileName(ctx, port, path));
  if (extension == ".png") {
    auto header = ReadImageSize(path);
    const bool png = header.ok() ? header->png_bit_depth > 0
                                 : header.status().code() != Status::Code::kUnsupported;
    if (!png) return Status::Corrupt(context + ": " + path + " is not a PNG file");
    if (!header.ok()) return header.status().WithContext(context);
    if (header->png_bit_depth == 8) {  // as baked, byte for byte
      auto bytes = Env::Default()->ReadFile(path);
      if (!bytes.ok()) return bytes.status().WithContext(context);
      return std::vector<uint8_t>(bytes->begin(), bytes->end());
    }
    auto image = ReadPng(path);
    if (!image.ok()) return image.status().WithContext(context);
    if (image->type == Image::PixelType::kU8) return EncodePng(*image);  // low bit depths, palettes
    return EncodePng(ToEightBit(*image, normal_map));
  }
  if (extension == ".exr") {
    auto image = ReadExr(path);
    if (!image.ok()) return image.status().WithContext(context);
    return EncodePng(ToEightBit(*image, normal_map));
  }
  return Status::Unsupported(context + ": " + InputFileName(ctx, port, path) +
                             ": expected a .png or .exr image");
}

Expected<Image> TextureImage8(const StageContext& ctx, std::string_view stage_id, std::string_view port,
                              bool normal_map) {
  PB_ASSIGN_OR_RETURN(const std::string path, InputFilePath(ctx, stage_id, port));
  const std::string context = std::string(stage_id) + ": input '" + std::string(port) + "'";
  const std::string extension = LowerExtension(InputFileName(ctx, port, path));
  Expected<Image> image = extension == ".png"   ? ReadPng(path)
                          : extension == ".exr" ? ReadExr(path)
                                                : Expected<Image>(Status::Unsupported(
                                                      InputFileName(ctx, port, path) +
                                                      ": expected a .png or .exr image"));
  if (!image.ok()) return image.status().WithContext(context);
  if (image->type == Image::PixelType::kU8) return std::move(*image);
  return ToEightBit(*image, normal_map);
}

std::vector<PortSpec> ExportInputPorts() {
  return {
      {"mesh", "mesh", "The mesh to export (mesh.ply), with uvs when textures are given.", false},
      {"color", "image", "Base color map (sRGB PNG, or EXR converted to sRGB).", true},
      {"normal", "image", "Tangent-space normal map (PNG, +Y up; or EXR in [-1,1]).", true}};
}

Expected<ExportInputs> ReadExportInputs(StageContext& ctx, std::string_view stage_id) {
  ExportInputs inputs;
  PB_ASSIGN_OR_RETURN(InputMesh input, ReadInputMesh(ctx, stage_id, 0.3));
  inputs.mesh_path = std::move(input.path);
  inputs.mesh = std::move(input.mesh);
  {
    PB_PHASE(ctx, "io");
    PB_ASSIGN_OR_RETURN(inputs.color_png, TexturePng(ctx, stage_id, "color", false));
    PB_ASSIGN_OR_RETURN(inputs.normal_png, TexturePng(ctx, stage_id, "normal", true));
  }
  if ((!inputs.color_png.empty() || !inputs.normal_png.empty()) && !inputs.mesh.has_uvs()) {
    return Status::Invalid(std::string(stage_id) + ": textures need uvs, and " +
                           inputs.mesh_path +
                           " has none (run uv.unwrap before baking and exporting)");
  }
  ctx.progress(0.4);
  return inputs;
}

nlohmann::json ExportMetaWith(const StageContext& ctx, const Mesh& mesh, std::string_view format,
                              uint64_t bytes, const nlohmann::json& changes) {
  const nlohmann::json& input_meta = ctx.input("mesh").meta;
  nlohmann::json meta = input_meta.is_object() ? input_meta : nlohmann::json::object();
  meta.update({{"format", format},
               {"origin", mesh.origin},
               {"vertices", mesh.vertex_count()},
               {"faces", mesh.face_count()},
               {"bytes", bytes}});
  meta.update(changes);
  return meta;
}

}  // namespace pb
