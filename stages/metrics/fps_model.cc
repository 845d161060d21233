// Frame-rate model and device profiles (fps_model.h). Calibration of the
// Oculus Go profile on the paper's Table 4: docs/fps.md.
//
// Departure: device files are parsed here as flat `key: value` YAML instead
// of through the engine's YAML reader (engine/yaml_json.h), which the stage
// library does not link; a profile is a few scalars, and this keeps their
// errors at file:line.
#include "stages/metrics/fps_model.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <utility>

namespace pb {
namespace {

struct RawValue {
  std::string text;
  bool quoted = false;
  int line = 0;
};

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::string At(const std::string& source, int line) {
  return source + ":" + std::to_string(line) + ": ";
}

// Removes a `#` comment that starts the line or follows whitespace, outside
// quotes.
std::string_view StripComment(std::string_view line) {
  char quote = 0;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '#' && (i == 0 || line[i - 1] == ' ' || line[i - 1] == '\t')) {
      return line.substr(0, i);
    }
  }
  return line;
}

// A scalar after `key:`: "double quoted" (\" and \\ escapes), 'single
// quoted' ('' escape) or plain.
Expected<RawValue> ParseScalar(std::string_view text, const std::string& where) {
  RawValue value;
  if (text.empty()) {
    return Status::Invalid(where + "expected a value after ':' (nested mappings and lists are "
                                   "not supported in device files)");
  }
  const char quote = text.front();
  if (quote != '"' && quote != '\'') {
    if (text.front() == '[' || text.front() == '{' || text.front() == '|' || text.front() == '>') {
      return Status::Invalid(where + "expected a scalar value, got '" + std::string(text) +
                             "' (flow collections and block scalars are not supported)");
    }
    value.text = std::string(text);
    return value;
  }
  value.quoted = true;
  size_t i = 1;
  for (; i < text.size(); ++i) {
    const char c = text[i];
    if (quote == '"' && c == '\\' && i + 1 < text.size()) {
      const char next = text[++i];
      if (next != '"' && next != '\\') {
        return Status::Invalid(where + "unsupported escape '\\" + std::string(1, next) +
                               "' (only \\\" and \\\\)");
      }
      value.text += next;
    } else if (c == quote) {
      if (quote == '\'' && i + 1 < text.size() && text[i + 1] == '\'') {
        value.text += '\'';
        ++i;
      } else {
        break;
      }
    } else {
      value.text += c;
    }
  }
  if (i >= text.size()) return Status::Invalid(where + "unterminated quoted string");
  if (!Trim(text.substr(i + 1)).empty()) {
    return Status::Invalid(where + "unexpected text after the closing quote: '" +
                           std::string(Trim(text.substr(i + 1))) + "'");
  }
  return value;
}

Expected<std::map<std::string, RawValue>> ParseFlatYaml(std::string_view text,
                                                         const std::string& source) {
  std::map<std::string, RawValue> values;
  int line_number = 0;
  while (!text.empty()) {
    const size_t end = text.find('\n');
    std::string_view raw = text.substr(0, end);
    text = end == std::string_view::npos ? std::string_view() : text.substr(end + 1);
    ++line_number;
    const std::string where = At(source, line_number);
    const std::string_view line = Trim(StripComment(raw));
    if (line.empty()) continue;
    if (line == "---" && values.empty()) continue;
    if (raw.front() == ' ' || raw.front() == '\t' || line.front() == '-') {
      return Status::Invalid(where + "expected 'key: value' at the start of the line (nested "
                                     "mappings and lists are not supported in device files)");
    }
    const size_t colon = line.find(':');
    if (colon == std::string_view::npos) {
      return Status::Invalid(where + "expected 'key: value', got '" + std::string(line) + "'");
    }
    const std::string key(Trim(line.substr(0, colon)));
    const bool key_ok = !key.empty() && std::all_of(key.begin(), key.end(), [](char c) {
      return std::islower(static_cast<unsigned char>(c)) || std::isdigit(static_cast<unsigned char>(c)) || c == '_';
    });
    if (!key_ok) {
      return Status::Invalid(where + "expected a key of lower-case letters, digits and '_', got '" +
                             key + "'");
    }
    if (colon + 1 < line.size() && line[colon + 1] != ' ' && line[colon + 1] != '\t') {
      return Status::Invalid(where + "expected a space after '" + key + ":'");
    }
    PB_ASSIGN_OR_RETURN(RawValue value, ParseScalar(Trim(line.substr(colon + 1)), where));
    value.line = line_number;
    const auto [it, inserted] = values.emplace(key, std::move(value));
    if (!inserted) {
      return Status::Invalid(where + "duplicate key '" + key + "' (first on line " +
                             std::to_string(it->second.line) + ")");
    }
  }
  return values;
}

Expected<double> ToNumber(const RawValue& value, const std::string& source, const char* key) {
  const std::string where = At(source, value.line);
  if (!value.quoted && !value.text.empty()) {
    errno = 0;
    char* end = nullptr;
    const double number = std::strtod(value.text.c_str(), &end);
    if (end == value.text.c_str() + value.text.size() && errno == 0 && std::isfinite(number)) {
      return number;
    }
  }
  return Status::Invalid(where + "'" + key + "' must be a number, got '" + value.text + "'");
}

Expected<bool> ToBool(const RawValue& value, const std::string& source, const char* key) {
  if (!value.quoted && value.text == "true") return true;
  if (!value.quoted && value.text == "false") return false;
  return Status::Invalid(At(source, value.line) + "'" + key + "' must be true or false, got '" +
                         value.text + "'");
}

}  // namespace

Expected<DeviceProfile> ParseDeviceProfile(std::string_view text, const std::string& source) {
  PB_ASSIGN_OR_RETURN(auto values, ParseFlatYaml(text, source));
  static constexpr const char* kKnown[] = {"name", "description", "triangles_per_s", "refresh_hz",
                                           "texture_budget_bytes", "texture_bytes_per_texel",
                                           "mipmaps"};
  for (const auto& [key, value] : values) {
    if (std::find_if(std::begin(kKnown), std::end(kKnown),
                     [&](const char* k) { return key == k; }) == std::end(kKnown)) {
      std::string known;
      for (const char* k : kKnown) known += (known.empty() ? "" : ", ") + std::string(k);
      return Status::Invalid(At(source, value.line) + "unknown key '" + key + "'; device files have: " + known);
    }
  }
  for (const char* required : {"name", "triangles_per_s", "refresh_hz", "texture_budget_bytes"}) {
    if (!values.count(required)) {
      return Status::Invalid(source + ": missing required key '" + required + "'");
    }
  }
  DeviceProfile device;
  device.name = values.at("name").text;
  if (device.name.empty()) return Status::Invalid(At(source, values.at("name").line) + "'name' is empty");
  if (values.count("description")) device.description = values.at("description").text;

  // A positive finite number, else an error at the key's line.
  auto positive = [&](const char* key, double* out) -> Status {
    const RawValue& value = values.at(key);
    PB_ASSIGN_OR_RETURN(*out, ToNumber(value, source, key));
    if (!(*out > 0)) {
      return Status::Invalid(At(source, value.line) + "'" + key + "' must be > 0, got " + value.text);
    }
    return Status::Ok();
  };
  PB_RETURN_IF_ERROR(positive("triangles_per_s", &device.triangles_per_s));
  PB_RETURN_IF_ERROR(positive("refresh_hz", &device.refresh_hz));
  if (values.count("texture_bytes_per_texel")) {
    PB_RETURN_IF_ERROR(positive("texture_bytes_per_texel", &device.texture_bytes_per_texel));
  }
  {
    const RawValue& value = values.at("texture_budget_bytes");
    PB_ASSIGN_OR_RETURN(const double budget, ToNumber(value, source, "texture_budget_bytes"));
    if (!(budget >= 0 && budget < 9.2e18 && budget == std::floor(budget))) {
      return Status::Invalid(At(source, value.line) +
                             "'texture_budget_bytes' must be a whole number >= 0, got " + value.text);
    }
    device.texture_budget_bytes = static_cast<int64_t>(budget);
  }
  if (values.count("mipmaps")) {
    PB_ASSIGN_OR_RETURN(device.mipmaps, ToBool(values.at("mipmaps"), source, "mipmaps"));
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
                              std::span<const TextureSize> maps) {
  FpsEstimate estimate;
  estimate.triangles = triangles;
  for (const TextureSize& map : maps) {
    estimate.texture_width = std::max(estimate.texture_width, map.width);
    estimate.texture_height = std::max(estimate.texture_height, map.height);
  }
  estimate.texture_bytes = TextureBytes(device, maps);
  estimate.fits_texture_budget =
      estimate.texture_bytes <= static_cast<uint64_t>(std::max<int64_t>(device.texture_budget_bytes, 0));
  estimate.fps = EstimateFps(device, triangles);
  return estimate;
}

}  // namespace pb
