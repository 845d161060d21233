// PCD reader; the format is described in pcd.h. The LZF decoder follows
// liblzf's lzf_d.c (Marc Lehmann, BSD-2-Clause), the compressor PCL uses for
// binary_compressed: a control byte c < 32 copies c + 1 literal bytes; else
// len = c >> 5 (7 means: add the next byte), then the back distance is
// ((c & 31) << 8) + next byte + 1 and len + 2 bytes are copied from there.
// Unlike lzf_d.c it decodes as a stream into an 8 KiB window, because the
// block can be larger than the memory we want to spend on it.
#include "stages/geometry/io/pcd.h"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <optional>
#include <string_view>
#include <vector>

#include "stages/geometry/core/buffered_input.h"
#include "stages/geometry/core/text_parse.h"
#include "stages/geometry/io/grid_station.h"

namespace pb {
namespace {

// An LZF instruction of 3 bytes yields at most 264 bytes; shorter ones less.
constexpr uint64_t kLzfMaxExpansion = 88;

// ---------------------------------------------------------------------------
// Header model.

enum Role : uint8_t { kSkip, kX, kY, kZ, kNx, kNy, kNz, kRgb, kR, kG, kB, kIntensity };

struct RoleName {
  std::string_view name;
  Role role;
};
constexpr RoleName kRoles[] = {
    {"x", kX},         {"y", kY},         {"z", kZ},         {"normal_x", kNx},
    {"normal_y", kNy}, {"normal_z", kNz}, {"rgb", kRgb},     {"rgba", kRgb},
    {"r", kR},         {"g", kG},         {"b", kB},         {"intensity", kIntensity},
};

struct Field {
  std::string name;
  char type = 'F';      // 'I', 'U' or 'F'
  size_t size = 4;      // bytes per value
  uint64_t count = 1;   // values per point
  Role role = kSkip;
  size_t offset = 0;    // byte offset inside a binary record
  size_t bytes() const { return size * count; }
};

enum class DataFormat { kAscii, kBinary, kBinaryCompressed };

struct Header {
  std::vector<Field> fields;
  uint64_t width = 0, height = 1, points = 0;
  bool have_viewpoint = false;
  std::array<double, 7> viewpoint{0, 0, 0, 1, 0, 0, 0};  // tx ty tz qw qx qy qz
  DataFormat data = DataFormat::kAscii;
  size_t record_bytes = 0;
  int lines = 0;  // header lines, DATA included
  int field_of_role[12];
};

std::string FormatU128(unsigned __int128 value) {
  std::string digits;
  do {
    digits.insert(digits.begin(), static_cast<char>('0' + static_cast<int>(value % 10)));
    value /= 10;
  } while (value != 0);
  return digits;
}

// Decodes one little-endian value of a field.
double DecodeValue(const uint8_t* bytes, char type, size_t size) {
  uint64_t bits = 0;
  for (size_t i = 0; i < size; ++i) bits |= uint64_t{bytes[i]} << (8 * i);
  if (type == 'F') {
    if (size == 4) return std::bit_cast<float>(static_cast<uint32_t>(bits));
    return std::bit_cast<double>(bits);
  }
  if (type == 'U') return static_cast<double>(bits);
  const int shift = static_cast<int>(64 - 8 * size);  // sign-extend
  return static_cast<double>(static_cast<int64_t>(bits << shift) >> shift);
}

uint32_t LoadU32(const uint8_t* bytes) {
  return uint32_t{bytes[0]} | uint32_t{bytes[1]} << 8 | uint32_t{bytes[2]} << 16 |
         uint32_t{bytes[3]} << 24;
}

// The values of one point that we keep.
struct PointValues {
  double xyz[3] = {0, 0, 0};
  double normal[3] = {0, 0, 0};
  uint32_t rgb = 0;           // packed 0x..RRGGBB
  double channel[3] = {0, 0, 0};  // separate r g b fields
  double intensity = 0;
};

void Assign(PointValues* values, Role role, double value) {
  switch (role) {
    case kX: values->xyz[0] = value; break;
    case kY: values->xyz[1] = value; break;
    case kZ: values->xyz[2] = value; break;
    case kNx: values->normal[0] = value; break;
    case kNy: values->normal[1] = value; break;
    case kNz: values->normal[2] = value; break;
    case kR: values->channel[0] = value; break;
    case kG: values->channel[1] = value; break;
    case kB: values->channel[2] = value; break;
    case kIntensity: values->intensity = value; break;
    case kSkip:
    case kRgb: break;
  }
}

void DecodeField(const Field& field, const uint8_t* bytes, PointValues* values) {
  if (field.role == kRgb) {
    values->rgb = LoadU32(bytes);
  } else if (field.role != kSkip) {
    Assign(values, field.role, DecodeValue(bytes, field.type, field.size));
  }
}

uint8_t ChannelToByte(double value) {
  if (!(value > 0)) return 0;
  if (value >= 255) return 255;
  return static_cast<uint8_t>(std::lround(value));
}

// ---------------------------------------------------------------------------
// The reader.

class PcdReader {
 public:
  PcdReader(const std::string& path, const ScanReadOptions& options)
      : path_(path), options_(options) {}

  Expected<ScanReadResult> Run() {
    PB_RETURN_IF_ERROR(in_.Open(path_, "a PCD file", &options_.progress));
    PB_RETURN_IF_ERROR(ParseHeader());
    PB_RETURN_IF_ERROR(Prepare());
    switch (header_.data) {
      case DataFormat::kAscii:
        result_.format = "pcd ascii";
        PB_RETURN_IF_ERROR(ReadAscii());
        break;
      case DataFormat::kBinary:
        result_.format = "pcd binary";
        PB_RETURN_IF_ERROR(ReadBinary());
        break;
      case DataFormat::kBinaryCompressed:
        result_.format = "pcd binary_compressed";
        PB_RETURN_IF_ERROR(ReadCompressed());
        break;
    }
    Finish();
    if (options_.progress) options_.progress(1.0);
    return std::move(result_);
  }

 private:
  Status HeaderError(int line, const std::string& what) const {
    return Status::Corrupt(path_ + ":" + std::to_string(line) + ": " + what);
  }
  Status LineError(uint64_t line, const std::string& what) const {
    return Status::Corrupt(path_ + ":" + std::to_string(line) + ": " + what);
  }
  Status Corrupt(const std::string& what) const { return Status::Corrupt(path_ + ": " + what); }

  // -------------------------------------------------------------------------
  // Header.

  Status ParseHeader() {
    std::string line;
    int line_number = 0;
    int fields_line = 0, size_line = 0, type_line = 0, count_line = 0, width_line = 0,
        points_line = 0;
    std::vector<std::string_view> words;
    std::vector<std::string> names, sizes, types, counts;
    bool have_points = false, have_width = false;
    auto rest = [&]() {
      return std::vector<std::string>(words.begin() + 1, words.end());
    };
    while (true) {
      if (!in_.ReadLine(&line)) {
        PB_RETURN_IF_ERROR(in_.error());
        if (in_.line_too_long()) return HeaderError(line_number + 1, "header line too long");
        if (line_number == 0) {
          return Corrupt("empty file (expected a PCD header starting with 'VERSION' or 'FIELDS')");
        }
        return HeaderError(line_number,
                           "missing 'DATA ascii|binary|binary_compressed' (the file ends inside "
                           "the header)");
      }
      ++line_number;
      words = SplitWords(line);
      if (words.empty() || words[0][0] == '#') continue;
      const std::string_view keyword = words[0];
      if (keyword == "VERSION") {
        // 0.5 to 0.7 differ only in optional lines; nothing to check.
      } else if (keyword == "FIELDS" || keyword == "COLUMNS") {
        names = rest();
        fields_line = line_number;
        if (names.empty()) return HeaderError(line_number, "expected 'FIELDS <name>...'");
      } else if (keyword == "SIZE") {
        sizes = rest();
        size_line = line_number;
      } else if (keyword == "TYPE") {
        types = rest();
        type_line = line_number;
      } else if (keyword == "COUNT") {
        counts = rest();
        count_line = line_number;
      } else if (keyword == "WIDTH") {
        if (words.size() != 2 || !ParseUint(words[1], &header_.width)) {
          return HeaderError(line_number, "expected 'WIDTH <points per row>', got '" + line + "'");
        }
        have_width = true;
        width_line = line_number;
      } else if (keyword == "HEIGHT") {
        if (words.size() != 2 || !ParseUint(words[1], &header_.height)) {
          return HeaderError(line_number, "expected 'HEIGHT <rows>', got '" + line + "'");
        }
      } else if (keyword == "VIEWPOINT") {
        bool parsed = words.size() == 8;
        for (size_t k = 0; parsed && k < 7; ++k) {
          parsed = ParseDouble(words[k + 1], &header_.viewpoint[k]) &&
                   std::isfinite(header_.viewpoint[k]);
        }
        if (!parsed) {
          return HeaderError(line_number,
                             "expected 'VIEWPOINT tx ty tz qw qx qy qz' with seven finite "
                             "numbers, got '" + line + "'");
        }
        const double norm = std::hypot(header_.viewpoint[3], header_.viewpoint[4],
                                       header_.viewpoint[5]) +
                            std::abs(header_.viewpoint[6]);
        if (!(norm > 0)) {
          return HeaderError(line_number, "VIEWPOINT quaternion qw qx qy qz is zero");
        }
        header_.have_viewpoint = true;
      } else if (keyword == "POINTS") {
        if (words.size() != 2 || !ParseUint(words[1], &header_.points)) {
          return HeaderError(line_number, "expected 'POINTS <count>', got '" + line + "'");
        }
        have_points = true;
        points_line = line_number;
      } else if (keyword == "DATA") {
        if (words.size() == 2 && words[1] == "ascii") {
          header_.data = DataFormat::kAscii;
        } else if (words.size() == 2 && words[1] == "binary") {
          header_.data = DataFormat::kBinary;
        } else if (words.size() == 2 && words[1] == "binary_compressed") {
          header_.data = DataFormat::kBinaryCompressed;
        } else {
          return HeaderError(line_number,
                             "expected 'DATA ascii', 'DATA binary' or 'DATA binary_compressed', "
                             "got '" + line + "'");
        }
        break;
      } else {
        return HeaderError(line_number,
                           "unknown header keyword '" + std::string(keyword) +
                               "' (expected VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, "
                               "VIEWPOINT, POINTS or DATA; is this a PCD file?)");
      }
    }
    header_.lines = line_number;

    // Everything is known; check the per-field lists against each other.
    if (fields_line == 0) return HeaderError(line_number, "missing 'FIELDS' line before DATA");
    if (size_line == 0) return HeaderError(line_number, "missing 'SIZE' line before DATA");
    if (type_line == 0) return HeaderError(line_number, "missing 'TYPE' line before DATA");
    auto check_length = [&](const std::vector<std::string>& list, int at,
                            const char* keyword) -> Status {
      if (list.size() == names.size()) return Status::Ok();
      return HeaderError(at, std::string(keyword) + " has " + std::to_string(list.size()) +
                                 " values but FIELDS (line " + std::to_string(fields_line) +
                                 ") names " + std::to_string(names.size()) + " fields");
    };
    PB_RETURN_IF_ERROR(check_length(sizes, size_line, "SIZE"));
    PB_RETURN_IF_ERROR(check_length(types, type_line, "TYPE"));
    if (count_line != 0) PB_RETURN_IF_ERROR(check_length(counts, count_line, "COUNT"));
    for (int& index : header_.field_of_role) index = -1;
    for (size_t k = 0; k < names.size(); ++k) {
      Field field;
      field.name = names[k];
      uint64_t size = 0;
      if (!ParseUint(sizes[k], &size) || (size != 1 && size != 2 && size != 4 && size != 8)) {
        return HeaderError(size_line, "field '" + field.name +
                                          "': SIZE must be 1, 2, 4 or 8, got '" + sizes[k] + "'");
      }
      field.size = size;
      if (types[k] != "F" && types[k] != "I" && types[k] != "U") {
        return HeaderError(type_line, "field '" + field.name + "': TYPE must be F, I or U, got '" +
                                          types[k] + "'");
      }
      field.type = types[k][0];
      if (field.type == 'F' && field.size != 4 && field.size != 8) {
        return HeaderError(size_line, "field '" + field.name + "': TYPE F needs SIZE 4 or 8, got " +
                                          std::to_string(field.size));
      }
      if (count_line != 0 &&
          (!ParseUint(counts[k], &field.count) || field.count < 1 || field.count > (1u << 20))) {
        return HeaderError(count_line, "field '" + field.name +
                                           "': COUNT must be an integer in 1..1048576, got '" +
                                           counts[k] + "'");
      }
      for (const RoleName& role : kRoles) {
        if (role.name == field.name) field.role = role.role;
      }
      if (field.role != kSkip) {
        if (header_.field_of_role[field.role] >= 0) {
          return HeaderError(fields_line, "field '" + field.name + "' appears twice");
        }
        if (field.count != 1) {
          return HeaderError(count_line, "field '" + field.name + "' must have COUNT 1, got " +
                                             std::to_string(field.count));
        }
        if ((field.role == kX || field.role == kY || field.role == kZ) && field.type != 'F') {
          return HeaderError(type_line, "field '" + field.name +
                                            "' must be TYPE F (SIZE 4 or 8), got TYPE " +
                                            std::string(1, field.type));
        }
        if (field.role == kRgb && field.size != 4) {
          return HeaderError(size_line, "field '" + field.name + "' must have SIZE 4 (packed "
                                            "0xAARRGGBB), got " + std::to_string(field.size));
        }
        header_.field_of_role[field.role] = static_cast<int>(k);
      }
      field.offset = header_.record_bytes;
      header_.record_bytes += field.bytes();
      header_.fields.push_back(std::move(field));
    }
    for (Role role : {kX, kY, kZ}) {
      if (header_.field_of_role[role] < 0) {
        return HeaderError(fields_line, std::string("no field '") +
                                            (role == kX ? "x" : role == kY ? "y" : "z") +
                                            "' in FIELDS");
      }
    }
    if (!have_width) {
      if (!have_points) return HeaderError(line_number, "missing 'WIDTH' line before DATA");
      header_.width = header_.points;
      header_.height = 1;
    }
    const unsigned __int128 grid =
        static_cast<unsigned __int128>(header_.width) * header_.height;
    if (have_points && grid != header_.points) {
      return HeaderError(points_line,
                         "size mismatch: POINTS " + std::to_string(header_.points) +
                             " but WIDTH " + std::to_string(header_.width) + " x HEIGHT " +
                             std::to_string(header_.height) + " (line " +
                             std::to_string(width_line) + ")");
    }
    if (grid > std::numeric_limits<uint32_t>::max() * uint64_t{16}) {
      return HeaderError(line_number, "WIDTH x HEIGHT is too large");
    }
    header_.points = static_cast<uint64_t>(grid);
    return Status::Ok();
  }

  // -------------------------------------------------------------------------
  // Output.

  Status Prepare() {
    const int* of = header_.field_of_role;
    has_normals_ = of[kNx] >= 0 && of[kNy] >= 0 && of[kNz] >= 0;
    has_packed_rgb_ = of[kRgb] >= 0;
    has_channels_ = !has_packed_rgb_ && of[kR] >= 0 && of[kG] >= 0 && of[kB] >= 0;
    has_intensity_ = of[kIntensity] >= 0;
    organized_ = header_.height > 1;

    // Rotation from the (normalized) viewpoint quaternion.
    const auto& v = header_.viewpoint;
    const double norm = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
    const double w = v[3] / norm, x = v[4] / norm, y = v[5] / norm, z = v[6] / norm;
    rotation_ = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                 2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                 2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
    rotate_ = header_.have_viewpoint && !(w == 1 || w == -1);
    translate_ = header_.have_viewpoint && (v[0] != 0 || v[1] != 0 || v[2] != 0);
    coordinates_f4_ = true;
    for (Role role : {kX, kY, kZ}) coordinates_f4_ &= header_.fields[of[role]].size == 4;
    recenter_ = !coordinates_f4_ || translate_;
    // An organized cloud in its sensor's frame (no VIEWPOINT, or the
    // identity): the sensor stands at the origin if the image grid was
    // swept from there.
    if (organized_ && !rotate_ && !translate_ && options_.infer_stations) grid_.emplace();

    // Reserve, but never more than the bytes left in the file could hold, so a
    // corrupt POINTS fails as truncation instead of exhausting memory.
    uint64_t min_bytes = std::max<uint64_t>(1, header_.record_bytes);
    if (header_.data == DataFormat::kAscii) min_bytes = 2 * header_.fields.size();
    uint64_t capacity = in_.remaining();
    if (header_.data == DataFormat::kBinaryCompressed) capacity *= kLzfMaxExpansion;
    const size_t reserve =
        static_cast<size_t>(std::min<uint64_t>(header_.points, capacity / min_bytes));
    PointCloud& cloud = result_.points;
    cloud.positions.reserve(3 * reserve);
    if (has_normals_) cloud.normals.reserve(3 * reserve);
    if (has_packed_rgb_ || has_channels_) cloud.colors.reserve(3 * reserve);
    if (has_intensity_) cloud.intensities.reserve(reserve);
    return Status::Ok();
  }

  // `place` says where point `index` is, for error messages.
  Status AddPoint(const PointValues& values, uint64_t index, const std::string& place) {
    double p[3] = {values.xyz[0], values.xyz[1], values.xyz[2]};
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      return DropOrFail(p, index, place);
    }
    PointCloud& cloud = result_.points;
    if (grid_) AddToGrid(index, p);
    float out[3];
    ToOutputFrame(p, out);
    cloud.positions.insert(cloud.positions.end(), out, out + 3);
    if (has_normals_) {
      double n[3] = {values.normal[0], values.normal[1], values.normal[2]};
      if (rotate_) Rotate(n);
      for (int axis = 0; axis < 3; ++axis) cloud.normals.push_back(static_cast<float>(n[axis]));
    }
    if (has_packed_rgb_) {
      cloud.colors.push_back(static_cast<uint8_t>(values.rgb >> 16));
      cloud.colors.push_back(static_cast<uint8_t>(values.rgb >> 8));
      cloud.colors.push_back(static_cast<uint8_t>(values.rgb));
    } else if (has_channels_) {
      for (int c = 0; c < 3; ++c) cloud.colors.push_back(ChannelToByte(values.channel[c]));
    }
    if (has_intensity_) cloud.intensities.push_back(IntensityToFloat(values.intensity));
    return Status::Ok();
  }

  // A point with a non-finite coordinate `p` (as read): dropped and counted
  // when it is an organized cloud's "no return" or drop_invalid_points is set,
  // else an error.
  Status DropOrFail(const double* p, uint64_t index, const std::string& place) {
    const bool no_return = organized_ && (std::isnan(p[0]) || std::isnan(p[1]) || std::isnan(p[2]));
    if (!no_return && !options_.drop_invalid_points) {
      return Status::Corrupt(path_ + place + ": point " + std::to_string(index) +
                             " has a non-finite coordinate (" + FormatDouble(p[0]) + " " +
                             FormatDouble(p[1]) + " " + FormatDouble(p[2]) +
                             "); drop such points with drop_invalid_points");
    }
    if (no_return)
      ++result_.no_return_points;
    else
      ++result_.dropped_points;
    return Status::Ok();
  }

  // Point `index` of an organized cloud, as read (sensor frame), to the
  // grid test: WIDTH points per row.
  void AddToGrid(uint64_t index, const double* p) {
    grid_->Add(static_cast<double>(index / header_.width),
               static_cast<double>(index % header_.width), p);
  }

  // Non-finite (also after narrowing to float) intensities carry no signal.
  static float IntensityToFloat(double value) {
    const float intensity = static_cast<float>(value);
    return std::isfinite(intensity) ? intensity : 0.f;
  }

  // A valid point as read (meters, sensor frame) to the output floats: the
  // VIEWPOINT rotation, then, when re-centering, the translation and the
  // provisional origin (the first valid point rounded to 1 m; Finish() moves
  // to the bounding-box center).
  void ToOutputFrame(double* p, float* out) {
    if (rotate_) Rotate(p);
    if (recenter_) {
      for (int axis = 0; axis < 3; ++axis) p[axis] += header_.viewpoint[axis];
      if (!have_provisional_origin_) {
        for (int axis = 0; axis < 3; ++axis) provisional_origin_[axis] = std::round(p[axis]);
        have_provisional_origin_ = true;
      }
      for (int axis = 0; axis < 3; ++axis) {
        out[axis] = static_cast<float>(p[axis] - provisional_origin_[axis]);
      }
    } else {
      for (int axis = 0; axis < 3; ++axis) out[axis] = static_cast<float>(p[axis]);
    }
  }

  void Rotate(double* v) const {
    const double x = v[0], y = v[1], z = v[2];
    for (int row = 0; row < 3; ++row) {
      v[row] = rotation_[3 * row] * x + rotation_[3 * row + 1] * y + rotation_[3 * row + 2] * z;
    }
  }

  void Finish() {
    PointCloud& cloud = result_.points;
    if (has_intensity_) NormalizeIntensities();
    // PCL writes the identity VIEWPOINT into every file, fused clouds included,
    // so only a pose that moves the points names a real sensor position.
    if (rotate_ || translate_) {
      cloud.stations = {{header_.viewpoint[0], header_.viewpoint[1], header_.viewpoint[2]}};
      cloud.station_ids.assign(cloud.size(), 0);
    } else if (grid_) {
      // An organized cloud without a VIEWPOINT pose: its sensor at the
      // origin when the image grid was swept from there (grid_station.h).
      const GridStationTest::Verdict verdict = grid_->Decide();
      if (verdict.at_origin) {
        cloud.stations = {{0.0, 0.0, 0.0}};
        cloud.station_ids.assign(cloud.size(), 0);
      }
      result_.warnings.push_back(
          verdict.Warning("organized cloud without a VIEWPOINT pose", "sensor"));
    }
    if (!recenter_ || cloud.empty()) return;
    // The bounding-box center rounded to 1 m; the shift is whole meters, so
    // each coordinate is rounded to float once more at most.
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

  // Maps intensities to [0, 1]: integers by their type's range, floats as
  // they are if they already lie in [0, 1], else by the cloud's maximum (PCD
  // says nothing about the scale; scanners write 0..1, 0..255 or raw counts).
  void NormalizeIntensities() {
    std::vector<float>& values = result_.points.intensities;
    const Field& field = header_.fields[header_.field_of_role[kIntensity]];
    double scale = 1;
    if (field.type == 'U' && field.size <= 2) {
      scale = field.size == 1 ? 1.0 / 255 : 1.0 / 65535;
    } else {
      float low = 0, high = 0;
      for (float value : values) {
        low = std::min(low, value);
        high = std::max(high, value);
      }
      if (low < 0 || high > 1) {
        scale = high > 0 ? 1.0 / high : 1;
        result_.warnings.push_back("intensity range [" + FormatDouble(low) + ", " +
                                   FormatDouble(high) + "] scaled to [0, 1] by 1/" +
                                   FormatDouble(high > 0 ? high : 1) +
                                   " (negative values clamped to 0)");
      }
    }
    for (float& value : values) {
      const float scaled = static_cast<float>(value * scale);
      value = std::isfinite(scaled) ? std::clamp(scaled, 0.f, 1.f) : 0.f;
    }
  }

  // -------------------------------------------------------------------------
  // Bodies.

  Status Truncated(uint64_t index, uint64_t byte) const {
    PB_RETURN_IF_ERROR(in_.error());
    return Corrupt("truncated: point " + std::to_string(index) + " of " +
                   std::to_string(header_.points) + " at byte " + std::to_string(byte) +
                   " (the file has " + std::to_string(in_.size()) + " bytes)");
  }

  Status ReadAscii() {
    std::string line;
    uint64_t line_number = header_.lines;
    uint64_t values_per_point = 0;
    for (const Field& field : header_.fields) values_per_point += field.count;
    std::vector<std::string_view> words;
    for (uint64_t i = 0; i < header_.points; ++i) {
      do {
        if (!in_.ReadLine(&line)) {
          PB_RETURN_IF_ERROR(in_.error());
          if (in_.line_too_long()) {
            return LineError(line_number + 1, "line too long");
          }
          return Corrupt("truncated: point " + std::to_string(i) + " of " +
                         std::to_string(header_.points) + " (the file ends at line " +
                         std::to_string(line_number) + ")");
        }
        ++line_number;
        words = SplitWords(line);
      } while (words.empty());
      const std::string place = ":" + std::to_string(line_number);
      if (words.size() != values_per_point) {
        return Status::Corrupt(path_ + place + ": point " + std::to_string(i) + ": expected " +
                               std::to_string(values_per_point) + " values (one per FIELDS x "
                               "COUNT), got " + std::to_string(words.size()));
      }
      PointValues values;
      size_t word = 0;
      for (const Field& field : header_.fields) {
        if (field.role == kSkip) {
          word += field.count;
          continue;
        }
        const std::string_view token = words[word++];
        double value = 0;
        if (field.role == kRgb && field.type == 'F' &&
            token.find_first_of(".eEnN") != std::string_view::npos) {
          // Older PCL writes the packed float itself; newer PCL its bits as an
          // unsigned integer.
          float packed = 0;
          const auto parsed = std::from_chars(token.data(), token.data() + token.size(), packed);
          if (parsed.ec == std::errc() && parsed.ptr == token.data() + token.size()) {
            values.rgb = std::bit_cast<uint32_t>(packed);
            continue;
          }
        } else if (ParseDouble(token, &value)) {
          if (field.role == kRgb) {
            values.rgb = value >= 0 && value <= 4294967295.0 ? static_cast<uint32_t>(value) : 0;
          } else {
            Assign(&values, field.role, value);
          }
          continue;
        }
        return Status::Corrupt(path_ + place + ": point " + std::to_string(i) +
                               ": expected a number for field '" + field.name + "', got '" +
                               std::string(token) + "'");
      }
      PB_RETURN_IF_ERROR(AddPoint(values, i, place));
    }
    while (in_.ReadLine(&line)) {
      ++line_number;
      if (!SplitWords(line).empty()) {
        return LineError(line_number,
                         "unexpected data after the last of the " +
                               std::to_string(header_.points) + " points (POINTS is too small?)");
      }
    }
    return in_.error();
  }

  Status ReadBinary() {
    if (header_.points > 0 && header_.record_bytes > in_.remaining()) {
      return Truncated(0, in_.offset());  // before allocating a record that cannot be there
    }
    std::vector<uint8_t> record(header_.record_bytes);
    for (uint64_t i = 0; i < header_.points; ++i) {
      const uint64_t start = in_.offset();
      if (!in_.Read(record.data(), record.size())) return Truncated(i, start);
      PointValues values;
      for (const Field& field : header_.fields) {
        DecodeField(field, record.data() + field.offset, &values);
      }
      PB_RETURN_IF_ERROR(AddPoint(values, i, " (byte " + std::to_string(start) + ")"));
    }
    WarnAboutTrailingBytes();
    return in_.error();
  }

  void WarnAboutTrailingBytes() {
    const uint64_t extra = in_.remaining();
    if (extra > 1) {  // PCL may end the file with a newline
      result_.warnings.push_back(path_ + ": ignored " + std::to_string(extra) +
                                 " bytes after the point data at byte " +
                                 std::to_string(in_.offset()));
    }
  }

  Status ReadCompressed() {
    const uint64_t sizes_at = in_.offset();
    uint8_t sizes[8];
    if (!in_.Read(sizes, sizeof sizes)) {
      PB_RETURN_IF_ERROR(in_.error());
      return Corrupt("truncated: expected the 8-byte binary_compressed sizes at byte " +
                     std::to_string(sizes_at) + " (the file has " + std::to_string(in_.size()) +
                     " bytes)");
    }
    const uint64_t compressed = LoadU32(sizes);
    const uint64_t uncompressed = LoadU32(sizes + 4);
    const uint64_t block_at = in_.offset();
    const unsigned __int128 expected =
        static_cast<unsigned __int128>(header_.points) * header_.record_bytes;
    if (uncompressed != expected) {
      return Corrupt("size mismatch: binary_compressed block at byte " + std::to_string(sizes_at) +
                     " declares " + std::to_string(uncompressed) +
                     " uncompressed bytes, but POINTS " + std::to_string(header_.points) +
                     " x " + std::to_string(header_.record_bytes) + " bytes per point = " +
                     FormatU128(expected));
    }
    if (compressed > in_.remaining()) {
      return Corrupt("truncated: binary_compressed block of " + std::to_string(compressed) +
                     " bytes at byte " + std::to_string(block_at) + ", but only " +
                     std::to_string(in_.remaining()) + " bytes remain");
    }
    if (uncompressed > kLzfMaxExpansion * compressed) {
      return Corrupt("corrupt LZF block at byte " + std::to_string(block_at) + ": " +
                     std::to_string(compressed) + " compressed bytes cannot expand to " +
                     std::to_string(uncompressed));
    }
    // The block holds the fields one after another; each recognized value
    // goes straight to its place in the output arrays as the stream yields it.
    PointCloud& cloud = result_.points;
    const size_t points = static_cast<size_t>(header_.points);
    cloud.positions.resize(3 * points);  // reserved by Prepare(): POINTS fits the file
    if (has_normals_) cloud.normals.resize(3 * points);
    if (has_packed_rgb_ || has_channels_) cloud.colors.resize(3 * points);
    if (has_intensity_) cloud.intensities.resize(points);
    size_t field = 0;     // the field being streamed
    uint64_t within = 0;  // bytes of it seen so far
    uint8_t partial[8];   // a value cut in two by the stream's chunks
    size_t partial_bytes = 0;
    auto sink = [&](uint64_t, const uint8_t* data, size_t n) {
      while (n > 0) {
        const Field& f = header_.fields[field];
        const uint64_t segment = header_.points * f.bytes();
        if (within == segment) {
          ++field;
          within = 0;
          continue;
        }
        const size_t take = static_cast<size_t>(std::min<uint64_t>(n, segment - within));
        if (Kept(f.role)) {
          uint64_t index = within / f.size;
          const uint8_t* bytes = data;
          size_t left = take;
          if (partial_bytes > 0) {
            const size_t k = std::min(left, f.size - partial_bytes);
            std::memcpy(partial + partial_bytes, bytes, k);
            partial_bytes += k;
            bytes += k;
            left -= k;
            if (partial_bytes == f.size) {
              StoreStreamed(f, index++, partial);
              partial_bytes = 0;
            }
          }
          for (; left >= f.size; left -= f.size, bytes += f.size) {
            StoreStreamed(f, index++, bytes);
          }
          std::memcpy(partial + partial_bytes, bytes, left);
          partial_bytes += left;
        }
        within += take;
        data += take;
        n -= take;
      }
    };
    PB_RETURN_IF_ERROR(DecodeLzf(compressed, uncompressed, sink));
    PB_RETURN_IF_ERROR(CompactStreamed());
    WarnAboutTrailingBytes();
    return in_.error();
  }

  // Whether values of `role` reach the output (a lone normal_x, or r g b next
  // to rgb, do not).
  bool Kept(Role role) const {
    switch (role) {
      case kX: case kY: case kZ: return true;
      case kNx: case kNy: case kNz: return has_normals_;
      case kRgb: return has_packed_rgb_;
      case kR: case kG: case kB: return has_channels_;
      case kIntensity: return has_intensity_;
      case kSkip: return false;
    }
    return false;
  }

  // Puts value `index` of a binary_compressed field into the output arrays.
  // Coordinates: F4 ones (all three) are kept as read, exactly; otherwise they
  // are stored relative to a per-axis streaming origin (see CompactStreamed).
  void StoreStreamed(const Field& field, uint64_t index, const uint8_t* bytes) {
    PointCloud& cloud = result_.points;
    const size_t i = static_cast<size_t>(index);
    switch (field.role) {
      case kX: case kY: case kZ: {
        const int axis = field.role - kX;
        double value = DecodeValue(bytes, field.type, field.size);
        if (!coordinates_f4_ && std::isfinite(value)) {
          // Without rotation the translation can be added now, as AddPoint does.
          if (!rotate_) value += header_.viewpoint[axis];
          if (!have_stream_origin_[axis]) {
            stream_origin_[axis] = std::round(value);
            have_stream_origin_[axis] = true;
          }
          value -= stream_origin_[axis];
        }
        cloud.positions[3 * i + axis] = static_cast<float>(value);
        break;
      }
      case kNx: case kNy: case kNz:
        cloud.normals[3 * i + (field.role - kNx)] =
            static_cast<float>(DecodeValue(bytes, field.type, field.size));
        break;
      case kRgb: {
        const uint32_t rgb = LoadU32(bytes);
        cloud.colors[3 * i] = static_cast<uint8_t>(rgb >> 16);
        cloud.colors[3 * i + 1] = static_cast<uint8_t>(rgb >> 8);
        cloud.colors[3 * i + 2] = static_cast<uint8_t>(rgb);
        break;
      }
      case kR: case kG: case kB:
        cloud.colors[3 * i + (field.role - kR)] =
            ChannelToByte(DecodeValue(bytes, field.type, field.size));
        break;
      case kIntensity:
        cloud.intensities[i] = IntensityToFloat(DecodeValue(bytes, field.type, field.size));
        break;
      case kSkip:
        break;
    }
  }

  // After the block: drops invalid points (organized "no return", or with
  // drop_invalid_points; else the first one is an error, as in the other
  // bodies) by moving the valid ones down in place, and applies the
  // VIEWPOINT pose and provisional origin as AddPoint does.
  Status CompactStreamed() {
    PointCloud& cloud = result_.points;
    const size_t points = cloud.size();
    // Without rotation, streamed non-F4 coordinates are already relative to
    // the streaming origin, which becomes the provisional origin.
    const bool in_place = !coordinates_f4_ && !rotate_;
    if (in_place) {
      provisional_origin_ = stream_origin_;
      have_provisional_origin_ = true;
    }
    size_t kept = 0;
    for (size_t i = 0; i < points; ++i) {
      const float* f = &cloud.positions[3 * i];
      if (!std::isfinite(f[0]) || !std::isfinite(f[1]) || !std::isfinite(f[2])) {
        // The values as read (up to float rounding for F8 coordinates).
        double p[3];
        for (int axis = 0; axis < 3; ++axis) {
          p[axis] = coordinates_f4_ ? f[axis]
                                    : stream_origin_[axis] + f[axis] -
                                          (rotate_ ? 0 : header_.viewpoint[axis]);
        }
        PB_RETURN_IF_ERROR(DropOrFail(p, i, ""));
        continue;
      }
      if (grid_) {
        // No VIEWPOINT pose: the values as read are the streamed ones.
        double p[3];
        for (int axis = 0; axis < 3; ++axis) {
          p[axis] = (coordinates_f4_ ? 0.0 : stream_origin_[axis]) + f[axis];
        }
        AddToGrid(i, p);
      }
      float out[3];
      if (in_place) {
        std::copy(f, f + 3, out);
      } else {
        double p[3];
        for (int axis = 0; axis < 3; ++axis) {
          p[axis] = (coordinates_f4_ ? 0.0 : stream_origin_[axis]) + f[axis];
        }
        ToOutputFrame(p, out);
      }
      std::copy(out, out + 3, &cloud.positions[3 * kept]);
      if (has_normals_) {
        double n[3];
        for (int axis = 0; axis < 3; ++axis) n[axis] = cloud.normals[3 * i + axis];
        if (rotate_) Rotate(n);
        for (int axis = 0; axis < 3; ++axis) {
          cloud.normals[3 * kept + axis] = static_cast<float>(n[axis]);
        }
      }
      if (cloud.has_colors()) {
        std::copy_n(&cloud.colors[3 * i], 3, &cloud.colors[3 * kept]);
      }
      if (has_intensity_) cloud.intensities[kept] = cloud.intensities[i];
      ++kept;
    }
    cloud.positions.resize(3 * kept);
    if (has_normals_) cloud.normals.resize(3 * kept);
    if (cloud.has_colors()) cloud.colors.resize(3 * kept);
    if (has_intensity_) cloud.intensities.resize(kept);
    return Status::Ok();
  }

  // Streams one LZF block of `compressed` bytes from the input, checking that
  // it yields exactly `uncompressed` bytes; `sink(offset, data, n)` receives
  // the output in order.
  Status DecodeLzf(uint64_t compressed, uint64_t uncompressed,
                   const std::function<void(uint64_t, const uint8_t*, size_t)>& sink) {
    constexpr size_t kWindow = 8192;  // the farthest an LZF reference reaches
    constexpr size_t kChunk = size_t{1} << 16;
    std::vector<uint8_t> buffer(kWindow + kChunk);
    const uint64_t block_at = in_.offset();
    uint64_t base = 0;  // uncompressed offset of buffer[0]
    size_t fill = 0, emitted = 0;
    uint64_t used = 0;  // compressed bytes consumed
    auto flush = [&]() {
      sink(base + emitted, buffer.data() + emitted, fill - emitted);
      emitted = fill;
      if (fill > kWindow) {
        std::memmove(buffer.data(), buffer.data() + fill - kWindow, kWindow);
        base += fill - kWindow;
        fill = emitted = kWindow;
      }
    };
    auto corrupt = [&](uint64_t at, const std::string& what) {
      return Corrupt("corrupt LZF block: " + what + " (compressed byte " + std::to_string(at) +
                     ", file byte " + std::to_string(block_at + at) + ")");
    };
    auto next = [&](uint64_t at, int* byte) -> Status {
      if (used == compressed) return corrupt(at, "instruction cut off by the end of the block");
      *byte = in_.GetByte();
      if (*byte < 0) {
        PB_RETURN_IF_ERROR(in_.error());
        return Corrupt("truncated: the file ended inside the binary_compressed block at byte " +
                       std::to_string(in_.offset()));
      }
      ++used;
      return Status::Ok();
    };
    while (used < compressed) {
      const uint64_t at = used;
      const uint64_t out = base + fill;
      int control = 0;
      PB_RETURN_IF_ERROR(next(at, &control));
      if (control < 32) {
        const size_t length = static_cast<size_t>(control) + 1;
        if (out + length > uncompressed) {
          return corrupt(at, "literal run of " + std::to_string(length) + " bytes at output byte " +
                                 std::to_string(out) + " overruns the declared " +
                                 std::to_string(uncompressed) + " bytes");
        }
        if (used + length > compressed) {
          return corrupt(at, "literal run of " + std::to_string(length) +
                                 " bytes runs past the end of the block");
        }
        if (fill + length > buffer.size()) flush();
        if (!in_.Read(buffer.data() + fill, length)) {
          PB_RETURN_IF_ERROR(in_.error());
          return Corrupt("truncated: the file ended inside the binary_compressed block");
        }
        fill += length;
        used += length;
        continue;
      }
      size_t length = static_cast<size_t>(control >> 5);
      int byte = 0;
      if (length == 7) {
        PB_RETURN_IF_ERROR(next(at, &byte));
        length += static_cast<size_t>(byte);
      }
      length += 2;
      PB_RETURN_IF_ERROR(next(at, &byte));
      const uint64_t distance = ((static_cast<uint64_t>(control) & 31) << 8) + byte + 1;
      if (distance > out) {
        return corrupt(at, "back reference of " + std::to_string(distance) +
                               " bytes at output byte " + std::to_string(out) +
                               " reaches before the start");
      }
      if (out + length > uncompressed) {
        return corrupt(at, "back reference of " + std::to_string(length) +
                               " bytes at output byte " + std::to_string(out) +
                               " overruns the declared " + std::to_string(uncompressed) + " bytes");
      }
      if (fill + length > buffer.size()) flush();
      // Byte by byte: source and destination overlap when distance < length.
      uint8_t* destination = buffer.data() + fill;
      const uint8_t* source = destination - distance;
      for (size_t k = 0; k < length; ++k) destination[k] = source[k];
      fill += length;
    }
    if (base + fill != uncompressed) {
      return corrupt(used, "the block yields " + std::to_string(base + fill) + " of the declared " +
                               std::to_string(uncompressed) + " bytes");
    }
    flush();
    return Status::Ok();
  }

  const std::string path_;
  const ScanReadOptions& options_;
  BufferedInput in_{size_t{1} << 16};  // longest line: 64 KiB
  Header header_;
  bool has_normals_ = false, has_packed_rgb_ = false, has_channels_ = false,
       has_intensity_ = false, organized_ = false;
  bool coordinates_f4_ = true, rotate_ = false, translate_ = false, recenter_ = false;
  std::array<double, 9> rotation_{};
  bool have_provisional_origin_ = false;
  std::array<double, 3> provisional_origin_{};
  // binary_compressed with non-F4 coordinates: per axis, the first finite
  // value (plus the translation when there is no rotation) rounded to 1 m.
  std::array<bool, 3> have_stream_origin_{};
  std::array<double, 3> stream_origin_{};
  std::optional<GridStationTest> grid_;  // organized, no VIEWPOINT pose
  ScanReadResult result_;
};

}  // namespace

Expected<ScanReadResult> ReadPcd(const std::string& path, const ScanReadOptions& options) {
  PcdReader reader(path, options);
  return reader.Run();
}

}  // namespace pb
