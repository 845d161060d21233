// XYZ/TXT/PTS reader; the formats are described in xyz.h. The PTS intensity
// range (-2048..2047) follows Leica Cyclone's export documentation.
#include "stages/geometry/io/xyz.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <functional>
#include <string_view>
#include <vector>

#include "stages/geometry/core/buffered_input.h"
#include "stages/geometry/core/text_parse.h"

namespace pb {
namespace {

enum Role : uint8_t { kSkip, kX, kY, kZ, kR, kG, kB, kI, kNx, kNy, kNz, kRoleCount };

struct RoleName {
  std::string_view name;
  Role role;
};
constexpr RoleName kRoleNames[] = {
    {"x", kX},        {"y", kY},          {"z", kZ},          {"r", kR},     {"g", kG},
    {"b", kB},        {"red", kR},        {"green", kG},      {"blue", kB},  {"i", kI},
    {"intensity", kI}, {"nx", kNx},       {"ny", kNy},        {"nz", kNz},   {"_", kSkip},
};

// Default columns by the number of values on the first data line.
struct DefaultColumns {
  size_t count;
  std::string_view names;
};
constexpr DefaultColumns kDefaults[] = {
    {3, "x y z"},
    {4, "x y z i"},
    {6, "x y z r g b"},
    {7, "x y z i r g b"},
    {9, "x y z r g b nx ny nz"},
};

bool IsSeparator(char c) { return IsBlankChar(c) || c == ','; }

// Splits on whitespace, or on commas with optional whitespace around them.
// False (with *empty_field set to the 1-based column) for "1,,2" or a leading
// or trailing comma.
bool SplitValues(std::string_view line, std::vector<std::string_view>* values,
                 size_t* empty_field) {
  values->clear();
  size_t i = 0;
  bool after_comma = false;
  while (true) {
    while (i < line.size() && IsBlankChar(line[i])) ++i;
    if (i == line.size()) {
      if (after_comma) {
        *empty_field = values->size() + 1;
        return false;
      }
      return true;
    }
    if (line[i] == ',') {
      *empty_field = values->size() + 1;
      return false;
    }
    const size_t start = i;
    while (i < line.size() && !IsSeparator(line[i])) ++i;
    values->push_back(line.substr(start, i - start));
    while (i < line.size() && IsBlankChar(line[i])) ++i;
    after_comma = i < line.size() && line[i] == ',';
    if (after_comma) ++i;
  }
}

std::string Lowercase(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

class XyzReader {
 public:
  XyzReader(const std::string& path, const ScanReadOptions& options)
      : path_(path), options_(options) {
    std::string extension = Lowercase(std::filesystem::path(path).extension().string());
    if (!extension.empty()) extension.erase(0, 1);  // the dot
    is_pts_ = extension == "pts";
    extension_ = extension.empty() ? "xyz" : extension;
  }

  Expected<ScanReadResult> Run() {
    PB_RETURN_IF_ERROR(in_.Open(path_, "a point file", &options_.progress));
    if (!options_.columns.empty()) {
      PB_RETURN_IF_ERROR(SetColumns(options_.columns, 0));
      explicit_columns_ = true;
    }
    std::string line;
    std::vector<std::string_view> values;
    while (in_.ReadLine(&line)) {
      ++line_number_;
      const size_t first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos || line[first] == '#' ||
          line.compare(first, 2, "//") == 0) {
        continue;
      }
      size_t empty_field = 0;
      if (!SplitValues(line, &values, &empty_field)) {
        return LineError("column " + std::to_string(empty_field) + " is empty");
      }
      if (is_pts_ && block_remaining_ == 0) {
        PB_RETURN_IF_ERROR(StartPtsBlock(values));
        continue;
      }
      if (columns_.empty()) {
        PB_RETURN_IF_ERROR(DetectColumns(values.size()));
      }
      PB_RETURN_IF_ERROR(AddPoint(values));
      if (is_pts_) --block_remaining_;
    }
    PB_RETURN_IF_ERROR(in_.error());
    if (in_.line_too_long()) {
      ++line_number_;
      return LineError("line longer than " + std::to_string(in_.max_line_bytes()) +
                       " bytes (is this a text point file?)");
    }
    if (is_pts_ && block_remaining_ > 0) {
      return Status::Corrupt(path_ + ":" + std::to_string(block_line_) + ": count mismatch: " +
                             std::to_string(block_count_) + " points declared, the file ends after " +
                             std::to_string(block_count_ - block_remaining_));
    }
    if (is_pts_ && blocks_ == 0) {
      return Status::Corrupt(path_ + ": empty PTS file (expected a point count line)");
    }
    Finish();
    result_.format = extension_ + " (" + column_names_ + ")";
    if (options_.progress) options_.progress(1.0);
    return std::move(result_);
  }

 private:
  Status LineError(const std::string& what) const {
    return Status::Corrupt(path_ + ":" + std::to_string(line_number_) + ": " + what);
  }

  // `line` is 0 for options.columns.
  Status SetColumns(std::string_view names, uint64_t line) {
    auto error = [&](const std::string& what) {
      return Status::Invalid(path_ + ": columns '" + std::string(names) + "'" +
                             (line ? " (chosen from line " + std::to_string(line) + ")" : "") +
                             ": " + what);
    };
    std::vector<std::string_view> words;
    size_t unused = 0;
    std::string spaced(names);
    std::replace(spaced.begin(), spaced.end(), ',', ' ');
    SplitValues(spaced, &words, &unused);
    bool present[kRoleCount] = {};
    columns_.clear();
    for (std::string_view word : words) {
      const std::string lower = Lowercase(std::string(word));
      Role role = kRoleCount;
      for (const RoleName& candidate : kRoleNames) {
        if (candidate.name == lower) role = candidate.role;
      }
      if (role == kRoleCount) {
        return error("unknown column name '" + std::string(word) +
                     "' (expected x y z r g b i nx ny nz or _ to skip)");
      }
      if (role != kSkip && present[role]) return error("column '" + lower + "' appears twice");
      present[role] = true;
      columns_.push_back(role);
    }
    if (!present[kX] || !present[kY] || !present[kZ]) return error("x, y and z are required");
    has_colors_ = present[kR] || present[kG] || present[kB];
    if (has_colors_ && !(present[kR] && present[kG] && present[kB])) {
      return error("r, g and b go together");
    }
    has_normals_ = present[kNx] || present[kNy] || present[kNz];
    if (has_normals_ && !(present[kNx] && present[kNy] && present[kNz])) {
      return error("nx, ny and nz go together");
    }
    has_intensity_ = present[kI];
    while (!columns_.empty() && columns_.back() == kSkip) columns_.pop_back();
    column_names_.clear();
    for (std::string_view word : words) column_names_ += (column_names_.empty() ? "" : " ") + std::string(word);
    return Status::Ok();
  }

  Status DetectColumns(size_t count) {
    for (const DefaultColumns& candidate : kDefaults) {
      if (candidate.count == count) {
        detected_count_ = count;
        detected_line_ = line_number_;
        return SetColumns(candidate.names, line_number_);
      }
    }
    return LineError("cannot tell what " + std::to_string(count) +
                     " columns mean (3 = x y z, 4 = x y z i, 6 = x y z r g b, 7 = x y z i r g b, "
                     "9 = x y z r g b nx ny nz); name them with columns, e.g. 'x y z _ r g b'");
  }

  Status StartPtsBlock(const std::vector<std::string_view>& values) {
    uint64_t count = 0;
    bool single_integer = values.size() == 1;
    if (single_integer) single_integer = ParseUint(values[0], &count);
    if (!single_integer) {
      if (blocks_ == 0) {
        return LineError("expected the point count (a single integer) at the start of a PTS "
                         "file, got " + std::to_string(values.size()) + " values");
      }
      return LineError("count mismatch: more points than the " + std::to_string(block_count_) +
                       " declared at line " + std::to_string(block_line_));
    }
    ++blocks_;
    block_count_ = block_remaining_ = count;
    block_line_ = line_number_;
    return Status::Ok();
  }

  Status AddPoint(const std::vector<std::string_view>& values) {
    if (values.size() < columns_.size() ||
        (detected_count_ != 0 && values.size() != detected_count_)) {
      std::string what = "expected " + std::to_string(explicit_columns_ ? columns_.size()
                                                                         : detected_count_) +
                         " values (" + column_names_ + "), got " + std::to_string(values.size());
      if (is_pts_ && values.size() == 1) {
        what = "count mismatch: " + std::to_string(block_count_) + " points declared at line " +
               std::to_string(block_line_) + ", but a new count (or a short line) follows after " +
               std::to_string(block_count_ - block_remaining_);
      } else if (detected_line_ != 0) {
        what += "; line " + std::to_string(detected_line_) + " had " +
                std::to_string(detected_count_);
      }
      return LineError(what);
    }
    double parsed[kRoleCount] = {};
    for (size_t c = 0; c < columns_.size(); ++c) {
      const Role role = columns_[c];
      if (role == kSkip) continue;
      if (!ParseDouble(values[c], &parsed[role])) {
        return LineError("column " + std::to_string(c + 1) + " ('" + ColumnName(c) +
                         "'): expected a number, got '" + std::string(values[c]) + "'");
      }
    }
    const uint64_t index = points_seen_++;
    double p[3] = {parsed[kX], parsed[kY], parsed[kZ]};
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      if (!options_.drop_invalid_points) {
        return LineError("point " + std::to_string(index) + " has a non-finite coordinate (" +
                         FormatDouble(p[0]) + " " + FormatDouble(p[1]) + " " + FormatDouble(p[2]) +
                         "); drop such points with drop_invalid_points");
      }
      ++result_.dropped_points;
      return Status::Ok();
    }
    PointCloud& cloud = result_.points;
    if (!have_provisional_origin_) {
      // Positions are stored relative to the first point rounded to 1 m
      // until Finish() moves them to the bounding-box center.
      for (int axis = 0; axis < 3; ++axis) provisional_origin_[axis] = std::round(p[axis]);
      have_provisional_origin_ = true;
    }
    for (int axis = 0; axis < 3; ++axis) {
      cloud.positions.push_back(static_cast<float>(p[axis] - provisional_origin_[axis]));
    }
    if (has_normals_) {
      for (Role role : {kNx, kNy, kNz}) cloud.normals.push_back(static_cast<float>(parsed[role]));
    }
    if (has_colors_) {
      for (Role role : {kR, kG, kB}) {
        uint8_t byte = 0;
        PB_RETURN_IF_ERROR(ColorByte(parsed[role], role, &byte));
        cloud.colors.push_back(byte);
      }
    }
    if (has_intensity_) {
      const double value = parsed[kI];
      if (!std::isfinite(value)) {
        return LineError("intensity is '" + FormatDouble(value) + "'; expected a finite number");
      }
      intensity_min_ = std::min(intensity_min_, value);
      intensity_max_ = std::max(intensity_max_, value);
      cloud.intensities.push_back(static_cast<float>(value));
    }
    return Status::Ok();
  }

  std::string ColumnName(size_t c) const {
    for (const RoleName& name : kRoleNames) {
      if (name.role == columns_[c]) return std::string(name.name);
    }
    return "_";
  }

  // 0..255 or 0..1: undecided while every value is 0 or 1.
  Status ColorByte(double value, Role role, uint8_t* byte) {
    const char* name = role == kR ? "r" : role == kG ? "g" : "b";
    if (!(value >= 0 && value <= 255)) {
      return LineError("color '" + std::string(name) + "' is " + FormatDouble(value) +
                       "; expected 0..255 or 0..1");
    }
    if (color_scale_ == ColorScale::kUndecided) {
      if (value > 1) {
        color_scale_ = ColorScale::kBytes;
        color_scale_line_ = line_number_;
      } else if (value != std::floor(value)) {
        color_scale_ = ColorScale::kUnit;
        color_scale_line_ = line_number_;
        for (uint8_t& earlier : result_.points.colors) earlier = earlier ? 255 : 0;
      }
    }
    if (color_scale_ == ColorScale::kUnit) {
      if (value > 1) {
        return LineError("color '" + std::string(name) + "' is " + FormatDouble(value) +
                         " but line " + std::to_string(color_scale_line_) +
                         " had 0..1 colors; the file mixes 0..1 and 0..255");
      }
      value *= 255;
    }
    *byte = static_cast<uint8_t>(std::lround(value));
    return Status::Ok();
  }

  void NormalizeIntensities() {
    std::vector<float>& values = result_.points.intensities;
    const double low = intensity_min_, high = intensity_max_;
    double offset = 0, scale = 1;
    std::string mapping;
    if (is_pts_ && low >= -2048 && high <= 2047) {
      offset = 2048;
      scale = 1.0 / 4095;
    } else if (low >= 0 && high <= 1) {
      return;
    } else if (low >= 0 && high <= 255) {
      scale = 1.0 / 255;
      mapping = "divided by 255";
    } else if (low >= 0 && high <= 65535) {
      scale = 1.0 / 65535;
      mapping = "divided by 65535";
    } else {
      offset = -low;
      scale = high > low ? 1.0 / (high - low) : 1;
      mapping = "mapped from its range to [0, 1]";
    }
    if (!mapping.empty()) {
      result_.warnings.push_back(path_ + ": intensity range [" + FormatDouble(low) + ", " +
                                 FormatDouble(high) + "] " + mapping);
    }
    for (float& value : values) {
      const double scaled = (value + offset) * scale;
      value = std::isfinite(scaled) ? static_cast<float>(std::clamp(scaled, 0.0, 1.0)) : 0.f;
    }
  }

  void Finish() {
    PointCloud& cloud = result_.points;
    if (has_intensity_ && !cloud.intensities.empty()) NormalizeIntensities();
    if (cloud.empty()) return;
    const std::array<double, 3> center = BoundsOf(cloud.positions).center_m();
    std::array<double, 3> shift{};
    for (int axis = 0; axis < 3; ++axis) {
      cloud.origin[axis] = provisional_origin_[axis] + std::round(center[axis]);
      shift[axis] = provisional_origin_[axis] - cloud.origin[axis];
    }
    if (shift == std::array<double, 3>{0, 0, 0}) return;
    for (size_t i = 0; i < cloud.positions.size(); i += 3) {
      for (int axis = 0; axis < 3; ++axis) {
        cloud.positions[i + axis] =
            static_cast<float>(static_cast<double>(cloud.positions[i + axis]) + shift[axis]);
      }
    }
  }

  enum class ColorScale { kUndecided, kBytes, kUnit };

  const std::string path_;
  const ScanReadOptions& options_;
  bool is_pts_ = false;
  std::string extension_;
  BufferedInput in_{size_t{1} << 16};  // longest line: 64 KiB
  uint64_t line_number_ = 0;
  std::vector<Role> columns_;  // trailing skips removed
  std::string column_names_;
  bool explicit_columns_ = false;
  size_t detected_count_ = 0;  // values per line when auto-detected
  uint64_t detected_line_ = 0;
  bool has_colors_ = false, has_normals_ = false, has_intensity_ = false;
  ColorScale color_scale_ = ColorScale::kUndecided;
  uint64_t color_scale_line_ = 0;
  double intensity_min_ = std::numeric_limits<double>::infinity();
  double intensity_max_ = -std::numeric_limits<double>::infinity();
  uint64_t blocks_ = 0, block_count_ = 0, block_remaining_ = 0, block_line_ = 0;
  uint64_t points_seen_ = 0;
  bool have_provisional_origin_ = false;
  std::array<double, 3> provisional_origin_{};
  ScanReadResult result_;
};

}  // namespace

Expected<ScanReadResult> ReadXyz(const std::string& path, const ScanReadOptions& options) {
  XyzReader reader(path, options);
  return reader.Run();
}

}  // namespace pb
