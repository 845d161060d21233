// Frame-rate model and device profiles (fps_model.h). Calibration of the
// Oculus Go profile on the paper's Table 4: docs/fps.md.
//
// Device files are YAML read by the engine's reader (engine/yaml_json.h), so
// errors carry file:line:column like every other file of the project.
#include "stages/estimate/fps_model.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "engine/yaml_json.h"

namespace pb {

Expected<DeviceProfile> ParseDeviceProfile(std::string_view text, const std::string& source) {
  PB_ASSIGN_OR_RETURN(YamlDocument doc, ParseYamlString(text, source));
  const nlohmann::json& values = doc.value;
  auto at = [&](const std::string& key) { return doc.PositionOf("/" + key).ToString() + ": "; };
  if (!values.is_object())
    return Status::Invalid(doc.PositionOf("").ToString() +
                           ": a device profile is a mapping (name, triangles_per_s, ...)");
  static constexpr const char* kKnown[] = {"name", "description", "triangles_per_s", "refresh_hz",
                                           "texture_budget_bytes", "texture_bytes_per_texel",
                                           "mipmaps"};
  for (const auto& [key, value] : values.items()) {
    if (std::find_if(std::begin(kKnown), std::end(kKnown),
                     [&](const char* k) { return key == k; }) == std::end(kKnown)) {
      std::string known;
      for (const char* k : kKnown) known += (known.empty() ? "" : ", ") + std::string(k);
      return Status::Invalid(doc.KeyPositionOf("/" + key).ToString() + ": unknown key '" + key +
                             "'; device files have: " + known);
    }
  }
  for (const char* required : {"name", "triangles_per_s", "refresh_hz", "texture_budget_bytes"})
    if (!values.contains(required))
      return Status::Invalid(source + ": missing required key '" + required + "'");

  auto text_of = [&](const char* key, std::string* out) -> Status {
    if (!values[key].is_string())
      return Status::Invalid(at(key) + "'" + key + "' must be text, got " + values[key].dump());
    *out = values[key].get<std::string>();
    return Status::Ok();
  };
  // A finite number, else an error at the value.
  auto number = [&](const char* key, double* out) -> Status {
    const nlohmann::json& value = values[key];
    if (!value.is_number() || !std::isfinite(value.get<double>()))
      return Status::Invalid(at(key) + "'" + key + "' must be a number, got " + value.dump());
    *out = value.get<double>();
    return Status::Ok();
  };
  auto positive = [&](const char* key, double* out) -> Status {
    PB_RETURN_IF_ERROR(number(key, out));
    if (!(*out > 0))
      return Status::Invalid(at(key) + "'" + key + "' must be > 0, got " + values[key].dump());
    return Status::Ok();
  };
  DeviceProfile device;
  PB_RETURN_IF_ERROR(text_of("name", &device.name));
  if (device.name.empty()) return Status::Invalid(at("name") + "'name' is empty");
  if (values.contains("description")) PB_RETURN_IF_ERROR(text_of("description", &device.description));
  PB_RETURN_IF_ERROR(positive("triangles_per_s", &device.triangles_per_s));
  PB_RETURN_IF_ERROR(positive("refresh_hz", &device.refresh_hz));
  if (values.contains("texture_bytes_per_texel"))
    PB_RETURN_IF_ERROR(positive("texture_bytes_per_texel", &device.texture_bytes_per_texel));
  double budget = 0;
  PB_RETURN_IF_ERROR(number("texture_budget_bytes", &budget));
  if (!(budget >= 0 && budget < 9.2e18 && budget == std::floor(budget)))
    return Status::Invalid(at("texture_budget_bytes") +
                           "'texture_budget_bytes' must be a whole number >= 0, got " +
                           values["texture_budget_bytes"].dump());
  device.texture_budget_bytes = static_cast<int64_t>(budget);
  if (values.contains("mipmaps")) {
    if (!values["mipmaps"].is_boolean())
      return Status::Invalid(at("mipmaps") + "'mipmaps' must be true or false, got " +
                             values["mipmaps"].dump());
    device.mipmaps = values["mipmaps"].get<bool>();
  }
  return device;
}

Expected<DeviceProfile> ReadDeviceProfile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::NotFound(path + ": cannot open the device profile");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return Status::Io(path + ": cannot read the device profile");
  return ParseDeviceProfile(text.str(), path);
}

uint64_t TextureTexels(TextureSize size, bool mipmaps) {
  uint64_t width = static_cast<uint64_t>(std::max(size.width, 0));
  uint64_t height = static_cast<uint64_t>(std::max(size.height, 0));
  if (width == 0 || height == 0) return 0;
  uint64_t texels = width * height;
  while (mipmaps && (width > 1 || height > 1)) {
    width = std::max<uint64_t>(1, width / 2);
    height = std::max<uint64_t>(1, height / 2);
    texels += width * height;
  }
  return texels;
}

uint64_t TextureBytes(const DeviceProfile& device, std::span<const TextureSize> maps) {
  uint64_t texels = 0;
  for (const TextureSize& map : maps) texels += TextureTexels(map, device.mipmaps);
  return static_cast<uint64_t>(std::ceil(static_cast<double>(texels) * device.texture_bytes_per_texel));
}

double EstimateFps(const DeviceProfile& device, uint64_t triangles) {
  if (triangles == 0) return device.refresh_hz;
  return std::min(device.refresh_hz, device.triangles_per_s / static_cast<double>(triangles));
}

FpsEstimate EstimateFrameRate(const DeviceProfile& device, uint64_t triangles,
                              std::span<const TextureSize> maps,
                              std::span<const CompressedMap> compressed) {
  FpsEstimate estimate;
  estimate.triangles = triangles;
  for (const TextureSize& map : maps) {
    estimate.texture_width = std::max(estimate.texture_width, map.width);
    estimate.texture_height = std::max(estimate.texture_height, map.height);
  }
  estimate.texture_bytes = TextureBytes(device, maps);
  for (const CompressedMap& map : compressed) {
    estimate.texture_width = std::max(estimate.texture_width, map.size.width);
    estimate.texture_height = std::max(estimate.texture_height, map.size.height);
    estimate.texture_bytes += map.gpu_bytes;
  }
  estimate.fits_texture_budget =
      estimate.texture_bytes <= static_cast<uint64_t>(std::max<int64_t>(device.texture_budget_bytes, 0));
  estimate.fps = EstimateFps(device, triangles);
  return estimate;
}

}  // namespace pb
