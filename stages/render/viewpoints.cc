// The render stages' `viewpoints` parameter (viewpoints.h).
#include "stages/render/viewpoints.h"

#include <cctype>
#include <cmath>
#include <set>
#include <string>
#include <utility>

namespace pb {
namespace {

Expected<std::array<double, 3>> Vector3(std::string_view stage_id, const nlohmann::json& item, const char* key,
                                        size_t index) {
  const std::string where =
      std::string(stage_id) + ": viewpoints[" + std::to_string(index) + "]." + key + ": ";
  if (!item.contains(key)) return Status::Invalid(where + "missing");
  const nlohmann::json& value = item[key];
  if (!value.is_array() || value.size() != 3)
    return Status::Invalid(where + "must be an array of 3 numbers");
  std::array<double, 3> out{};
  for (size_t k = 0; k < 3; ++k) {
    if (!value[k].is_number()) return Status::Invalid(where + "must be an array of 3 numbers");
    out[k] = value[k].get<double>();
    if (!std::isfinite(out[k])) return Status::Invalid(where + "must be finite");
  }
  return out;
}

// Letters, digits, '-', '_' and '.' are kept; anything else becomes '_'.
std::string FileStem(const std::string& name) {
  std::string stem = name;
  for (char& c : stem)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  return stem;
}

}  // namespace

std::string DepthFileName(const std::string& png_file) {
  const std::string stem = png_file.size() > 4 ? png_file.substr(0, png_file.size() - 4) : png_file;
  return stem + ".depth.exr";
}

std::string SamplesFileName(const std::string& png_file) {
  const std::string stem = png_file.size() > 4 ? png_file.substr(0, png_file.size() - 4) : png_file;
  return stem + ".samples.png";
}

std::string WithViewpointsSchema(std::string schema) {
  const std::string token = "VIEWPOINTS_SCHEMA";
  const size_t at = schema.find(token);
  if (at != std::string::npos) schema.replace(at, token.size(), kViewpointsSchema);
  return schema;
}

Expected<std::vector<View>> ReadViewpoints(const StageContext& ctx, std::string_view stage_id, int size) {
  if (!ctx.params().contains("viewpoints"))
    return Status::Invalid(std::string(stage_id) + ": parameter 'viewpoints' is missing");
  const nlohmann::json& list = ctx.params()["viewpoints"];
  if (!list.is_array() || list.empty())
    return Status::Invalid(std::string(stage_id) + ": parameter 'viewpoints' must be a non-empty array");
  std::vector<View> views;
  std::set<std::string> names, files;
  for (size_t i = 0; i < list.size(); ++i) {
    const nlohmann::json& item = list[i];
    const std::string where = std::string(stage_id) + ": viewpoints[" + std::to_string(i) + "]";
    if (!item.is_object()) return Status::Invalid(where + ": must be an object");
    for (const auto& [key, value] : item.items())
      if (key != "name" && key != "eye" && key != "target" && key != "up" && key != "fov_deg")
        return Status::Invalid(where + ": unknown key '" + key + "'");
    View view;
    view.camera.size = size;
    std::string name = "view" + std::to_string(i + 1);
    if (item.contains("name")) {
      if (!item["name"].is_string() || item["name"].get<std::string>().empty())
        return Status::Invalid(where + ".name: must be a non-empty string");
      name = item["name"].get<std::string>();
    }
    if (!names.insert(name).second) return Status::Invalid(where + ": duplicate name '" + name + "'");
    FrameViewpoint viewpoint;
    PB_ASSIGN_OR_RETURN(viewpoint.eye, Vector3(stage_id, item, "eye", i));
    PB_ASSIGN_OR_RETURN(viewpoint.target, Vector3(stage_id, item, "target", i));
    view.camera.eye = viewpoint.eye;
    view.camera.target = viewpoint.target;
    if (item.contains("up")) {
      PB_ASSIGN_OR_RETURN(view.camera.up, Vector3(stage_id, item, "up", i));
      viewpoint.up = view.camera.up;
    }
    if (item.contains("fov_deg")) {
      if (!item["fov_deg"].is_number()) return Status::Invalid(where + ".fov_deg: must be a number");
      view.camera.fov_deg = item["fov_deg"].get<double>();
      if (!(view.camera.fov_deg > 0 && view.camera.fov_deg < 180))
        return Status::Invalid(where + ".fov_deg: must be in (0, 180)");
      viewpoint.fov_deg = view.camera.fov_deg;
    }
    std::string stem = FileStem(name);
    std::string file = stem + ".png";
    for (int k = 2; files.count(file) > 0; ++k) file = stem + "_" + std::to_string(k) + ".png";
    files.insert(file);
    view.entry = FrameEntry{name, file, viewpoint};
    views.push_back(std::move(view));
  }
  return views;
}


Status ReadBackground(const StageContext& ctx, std::string_view stage_id, std::array<uint8_t, 3>* rgb) {
  if (!ctx.params().contains("background")) return Status::Ok();
  const nlohmann::json& bg = ctx.params()["background"];
  const Status bad = Status::Invalid(std::string(stage_id) +
                                     ": 'background' must be 3 integers in [0, 255], as [R, G, B] or \"R,G,B\"");
  if (bg.is_string()) {  // "R,G,B"
    const std::string text = bg.get<std::string>();
    size_t start = 0;
    for (size_t c = 0; c < 3; ++c) {
      const size_t end = c < 2 ? text.find(',', start) : text.size();
      if (end == std::string::npos || end == start || end - start > 3 ||
          text.find_first_not_of("0123456789", start) < end)
        return bad;
      const int value = std::stoi(text.substr(start, end - start));
      if (value > 255) return bad;
      (*rgb)[c] = uint8_t(value);
      start = end + 1;
    }
    return Status::Ok();
  }
  if (!bg.is_array() || bg.size() != 3) return bad;
  for (size_t c = 0; c < 3; ++c) {
    if (!bg[c].is_number_integer() || bg[c].get<int64_t>() < 0 || bg[c].get<int64_t>() > 255) return bad;
  }
  for (size_t c = 0; c < 3; ++c) (*rgb)[c] = uint8_t(bg[c].get<int64_t>());
  return Status::Ok();
}

Status WriteFramesOutput(StageContext& ctx, const FrameSet& frames) {
  PB_PHASE(ctx, "io");
  return WriteFrames(frames, [&ctx](const std::string& file) { return ctx.output_path("frames", file); });
}

}  // namespace pb
