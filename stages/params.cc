#include "stages/params.h"

#include <cctype>
#include <cmath>
#include <cstring>

namespace pb {
namespace {

// The parameter's JSON value, or nullptr if absent.
const nlohmann::json* Find(const StageContext& ctx, const char* name) {
  const nlohmann::json& params = ctx.params();
  if (!params.is_object()) return nullptr;
  auto it = params.find(name);
  return it == params.end() || it->is_null() ? nullptr : &*it;
}

Status Missing(std::string_view stage_id, const char* name) {
  return Status::Invalid(std::string(stage_id) + ": missing parameter '" + name + "'");
}

Status WrongType(std::string_view stage_id, const char* name, const char* type, const nlohmann::json& value) {
  return Status::Invalid(std::string(stage_id) + ": parameter '" + name + "' must be " + type +
                         ", got " + value.dump());
}

}  // namespace

Expected<std::string> StringParam(const StageContext& ctx, std::string_view stage_id, const char* name) {
  const nlohmann::json* value = Find(ctx, name);
  if (!value) return Missing(stage_id, name);
  if (!value->is_string()) return WrongType(stage_id, name, "a string", *value);
  return value->get<std::string>();
}

Expected<double> NumberParam(const StageContext& ctx, std::string_view stage_id, const char* name) {
  const nlohmann::json* value = Find(ctx, name);
  if (!value) return Missing(stage_id, name);
  if (!value->is_number()) return WrongType(stage_id, name, "a number", *value);
  return value->get<double>();
}

Expected<bool> BoolParam(const StageContext& ctx, std::string_view stage_id, const char* name) {
  const nlohmann::json* value = Find(ctx, name);
  if (!value) return Missing(stage_id, name);
  if (!value->is_boolean()) return WrongType(stage_id, name, "true or false", *value);
  return value->get<bool>();
}

Expected<int64_t> IntegerParam(const StageContext& ctx, std::string_view stage_id, const char* name,
                               IntegerRange range) {
  // Doubles hold every integer up to 2^53 exactly; beyond, "integer" means little.
  constexpr int64_t kMaxExact = int64_t{1} << 53;
  const int64_t min = range.min;
  const std::optional<int64_t> max = range.max;
  PB_ASSIGN_OR_RETURN(const double value, NumberParam(ctx, stage_id, name));
  const int64_t upper = max ? *max : kMaxExact;
  const bool above = value > static_cast<double>(upper);
  if (value != std::floor(value) || value < static_cast<double>(min) || above) {
    const std::string range = max || above
                                  ? "in " + std::to_string(min) + ".." + std::to_string(upper)
                                  : ">= " + std::to_string(min);
    return Status::Invalid(std::string(stage_id) + ": parameter '" + name +
                           "' must be an integer " + range + ", got " + std::to_string(value));
  }
  return static_cast<int64_t>(value);
}

Expected<std::string> InputFilePath(const StageContext& ctx, std::string_view stage_id,
                                    std::string_view port, std::string_view preferred_file) {
  if (!ctx.has_input(port)) {
    return Status::Invalid(std::string(stage_id) + ": input '" + std::string(port) + "' is not connected");
  }
  const ArtifactView& view = ctx.input(port);
  if (view.files.empty()) {
    return Status::Invalid(std::string(stage_id) + ": input '" + std::string(port) + "' has no file");
  }
  if (!preferred_file.empty()) {
    auto named = view.files.find(std::string(preferred_file));
    if (named != view.files.end()) return named->second;
  }
  return view.file();
}

std::string InputFileName(const StageContext& ctx, std::string_view port, const std::string& path) {
  for (const auto& [file_name, file_path] : ctx.input(port).files)
    if (file_path == path) return file_name;
  return path;
}

Expected<Image> ReadInputImage(const StageContext& ctx, std::string_view stage_id,
                               std::string_view port) {
  PB_ASSIGN_OR_RETURN(const std::string path, InputFilePath(ctx, stage_id, port));
  const std::string context = std::string(stage_id) + ": input '" + std::string(port) + "'";
  std::string name = InputFileName(ctx, port, path);
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  auto ends_with = [&](const char* ext) {
    const size_t n = std::strlen(ext);
    return name.size() >= n && name.compare(name.size() - n, n, ext) == 0;
  };
  Expected<Image> image = ends_with(".png")   ? ReadPng(path)
                          : ends_with(".exr") ? ReadExr(path)
                                              : Expected<Image>(Status::Unsupported(
                                                    path + ": unsupported image file '" + name +
                                                    "' (supported: .png, .exr)"));
  if (!image.ok()) return image.status().WithContext(context);
  return image;
}

}  // namespace pb
