#include "stages/params.h"

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

Expected<std::string> StringParam(const StageContext& ctx, std::string_view stage_id, const char* name,
                                  std::optional<std::string> fallback) {
  const nlohmann::json* value = Find(ctx, name);
  if (!value) {
    if (fallback) return *fallback;
    return Missing(stage_id, name);
  }
  if (!value->is_string()) return WrongType(stage_id, name, "a string", *value);
  return value->get<std::string>();
}

Expected<double> NumberParam(const StageContext& ctx, std::string_view stage_id, const char* name,
                             std::optional<double> fallback) {
  const nlohmann::json* value = Find(ctx, name);
  if (!value) {
    if (fallback) return *fallback;
    return Missing(stage_id, name);
  }
  if (!value->is_number()) return WrongType(stage_id, name, "a number", *value);
  return value->get<double>();
}

Expected<bool> BoolParam(const StageContext& ctx, std::string_view stage_id, const char* name,
                         std::optional<bool> fallback) {
  const nlohmann::json* value = Find(ctx, name);
  if (!value) {
    if (fallback) return *fallback;
    return Missing(stage_id, name);
  }
  if (!value->is_boolean()) return WrongType(stage_id, name, "true or false", *value);
  return value->get<bool>();
}

Expected<std::string> InputFilePath(const StageContext& ctx, std::string_view stage_id, std::string_view port) {
  if (!ctx.has_input(port)) {
    return Status::Invalid(std::string(stage_id) + ": input '" + std::string(port) + "' is not connected");
  }
  const ArtifactView& view = ctx.input(port);
  if (view.files.empty()) {
    return Status::Invalid(std::string(stage_id) + ": input '" + std::string(port) + "' has no file");
  }
  return view.file();
}

}  // namespace pb
