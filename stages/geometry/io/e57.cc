// E57 reader: file header, XML interpretation, and merging of scans into one
// PointCloud. Reference: ASTM E2807-11, section 7 (file header), 8.4 (XML
// section) and the E57 data3D schema (pose, points prototype, colorLimits,
// intensityLimits, invalid states). See e57.h for what is read and how.
#include "stages/geometry/io/e57.h"

#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <string_view>
#include <vector>

#include "stages/geometry/io/e57_binary.h"
#include "stages/geometry/io/e57_xml.h"
#include "stages/geometry/io/grid_station.h"

namespace pb {
namespace {

using e57::FieldCodec;
using e57::XmlElement;

constexpr char kSignature[8] = {'A', 'S', 'T', 'M', '-', 'E', '5', '7'};
constexpr uint64_t kProgressBytes = uint64_t{4} << 20;

// Field roles that ReadE57 uses; everything else is decoded and ignored.
enum Role : int {
  kCartesianX,
  kCartesianY,
  kCartesianZ,
  kRange,
  kAzimuth,
  kElevation,
  kRed,
  kGreen,
  kBlue,
  kIntensity,
  kCartesianInvalid,
  kSphericalInvalid,
  kRowIndex,
  kColumnIndex,
  kColorInvalid,
  kIntensityInvalid,
  kRoleCount
};
constexpr std::string_view kRoleNames[kRoleCount] = {"cartesianX",
                                                     "cartesianY",
                                                     "cartesianZ",
                                                     "sphericalRange",
                                                     "sphericalAzimuth",
                                                     "sphericalElevation",
                                                     "colorRed",
                                                     "colorGreen",
                                                     "colorBlue",
                                                     "intensity",
                                                     "cartesianInvalidState",
                                                     "sphericalInvalidState",
                                                     "rowIndex",
                                                     "columnIndex",
                                                     "isColorInvalid",
                                                     "isIntensityInvalid"};

struct Range {
  double min = 0.0;
  double max = 0.0;
};

struct ScanSpec {
  int index = 0;
  e57::CompressedVectorSpec points;
  std::array<int, kRoleCount> field{};                         // index into points.fields, or -1
  std::array<std::optional<Range>, kRoleCount> field_range{};  // declared min/max
  bool spherical = false;
  bool has_pose = false;
  std::array<double, 4> rotation{1, 0, 0, 0};  // w x y z
  std::array<double, 3> translation{};
  std::array<Range, 3> color_range{};
  Range intensity_range{};
  bool has_colors = false;
  bool has_intensity = false;
};

class E57Reader {
 public:
  E57Reader(const std::string& path, const ScanReadOptions& options)
      : path_(path), options_(options) {}

  Expected<ScanReadResult> Read();

 private:
  Status XmlError(const XmlElement& element, const std::string& what) const {
    return Status::Corrupt(path_ + ": XML line " + std::to_string(element.line) + ": " + what);
  }
  Status ReadHeader(uint64_t* xml_logical, uint64_t* xml_length);
  Expected<double> Number(const XmlElement& element, const std::string& context) const;
  Expected<double> ChildNumber(const XmlElement& parent, std::string_view name, double fallback,
                               const std::string& context) const;
  Status ParsePrototype(const XmlElement& prototype, const std::string& context, ScanSpec* scan,
                        bool top_level);
  Expected<ScanSpec> ParseScan(const XmlElement& element, int index);
  Status DecodeScan(const ScanSpec& scan, bool keep_colors, bool keep_intensity,
                    GridStationTest* grid);
  void ReportProgress();

  std::string path_;
  const ScanReadOptions& options_;
  e57::PagedReader file_;
  ScanReadResult result_;
  std::array<double, 3> provisional_origin_{};
  bool have_origin_ = false;
  std::array<double, 3> min_{}, max_{};
  uint64_t next_progress_bytes_ = kProgressBytes;
};

Status E57Reader::ReadHeader(uint64_t* xml_logical, uint64_t* xml_length) {
  uint8_t raw[48];
  PB_RETURN_IF_ERROR(file_.ReadRaw(sizeof(raw), raw));
  if (std::memcmp(raw, kSignature, sizeof(kSignature)) != 0) {
    return Status::Corrupt(path_ + ": not an E57 file (no 'ASTM-E57' signature)");
  }
  uint32_t major, minor;
  uint64_t physical_length, xml_physical, page_size;
  std::memcpy(&major, raw + 8, 4);
  std::memcpy(&minor, raw + 12, 4);
  std::memcpy(&physical_length, raw + 16, 8);
  std::memcpy(&xml_physical, raw + 24, 8);
  std::memcpy(xml_length, raw + 32, 8);
  std::memcpy(&page_size, raw + 40, 8);
  if (major != 1) {
    return Status::Unsupported(path_ + ": E57 version " + std::to_string(major) + "." +
                               std::to_string(minor) + " is not supported (only 1.x)");
  }
  if (page_size != e57::kPageBytes) {
    return Status::Unsupported(path_ + ": page size " + std::to_string(page_size) +
                               " is not supported (only 1024)");
  }
  if (file_.file_bytes() < physical_length) {
    return Status::Corrupt(path_ + ": truncated: the header says " +
                           std::to_string(physical_length) + " bytes, the file has " +
                           std::to_string(file_.file_bytes()));
  }
  if (physical_length % e57::kPageBytes != 0 || physical_length == 0) {
    return Status::Corrupt(path_ + ": file length " + std::to_string(physical_length) +
                           " in the header is not a whole number of 1024-byte pages");
  }
  if (file_.file_bytes() > physical_length) {
    result_.warnings.push_back("E57 file has " +
                               std::to_string(file_.file_bytes() - physical_length) +
                               " bytes after its declared end; ignored");
  }
  // Verify page 0's CRC now, so a damaged header is reported as such.
  PB_RETURN_IF_ERROR(file_.Read(0, sizeof(raw), raw));
  if (!e57::PhysicalToLogical(xml_physical, xml_logical) || *xml_logical > file_.logical_bytes() ||
      *xml_length > file_.logical_bytes() - *xml_logical || *xml_length == 0) {
    return Status::Corrupt(path_ + ": XML section (byte " + std::to_string(xml_physical) + ", " +
                           std::to_string(*xml_length) + " bytes) does not fit in the file");
  }
  return Status::Ok();
}

std::string_view Trim(std::string_view s) {
  while (!s.empty() && std::strchr(" \t\r\n", s.front()) != nullptr) s.remove_prefix(1);
  while (!s.empty() && std::strchr(" \t\r\n", s.back()) != nullptr) s.remove_suffix(1);
  return s;
}

std::optional<int64_t> ParseInt(std::string_view s) {
  s = Trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  int64_t value = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || end != s.data() + s.size() || s.empty()) return std::nullopt;
  return value;
}

std::optional<double> ParseDouble(std::string_view s) {
  s = Trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double value = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || end != s.data() + s.size() || s.empty()) return std::nullopt;
  return value;
}

// The value of an Integer, ScaledInteger or Float element (empty text = 0).
Expected<double> E57Reader::Number(const XmlElement& element, const std::string& context) const {
  const std::string* type = element.Attribute("type");
  const std::string_view text = Trim(element.text);
  const std::string what = context + element.name;
  if (type == nullptr) return XmlError(element, what + ": missing attribute 'type'");
  if (*type == "Float") {
    if (text.empty()) return 0.0;
    const auto value = ParseDouble(text);
    if (!value)
      return XmlError(element, what + ": expected a number, found '" + std::string(text) + "'");
    return *value;
  }
  if (*type == "Integer" || *type == "ScaledInteger") {
    int64_t raw = 0;
    if (!text.empty()) {
      const auto value = ParseInt(text);
      if (!value) {
        return XmlError(element, what + ": expected an integer, found '" + std::string(text) + "'");
      }
      raw = *value;
    }
    if (*type == "Integer") return static_cast<double>(raw);
    double scale = 1.0, offset = 0.0;
    if (const std::string* s = element.Attribute("scale")) {
      const auto value = ParseDouble(*s);
      if (!value) return XmlError(element, what + ": bad scale '" + *s + "'");
      scale = *value;
    }
    if (const std::string* s = element.Attribute("offset")) {
      const auto value = ParseDouble(*s);
      if (!value) return XmlError(element, what + ": bad offset '" + *s + "'");
      offset = *value;
    }
    return static_cast<double>(raw) * scale + offset;
  }
  return XmlError(element, what + ": expected a number, found type '" + *type + "'");
}

Expected<double> E57Reader::ChildNumber(const XmlElement& parent, std::string_view name,
                                        double fallback, const std::string& context) const {
  const XmlElement* child = parent.Child(name);
  if (child == nullptr) return fallback;
  return Number(*child, context);
}

// Appends the prototype's leaf fields (depth first) to scan->points.fields.
Status E57Reader::ParsePrototype(const XmlElement& prototype, const std::string& context,
                                 ScanSpec* scan, bool top_level) {
  for (const XmlElement& child : prototype.children) {
    const std::string* type = child.Attribute("type");
    const std::string what = context + "prototype field '" + child.name + "'";
    if (type == nullptr) return XmlError(child, what + ": missing attribute 'type'");
    if (*type == "Structure") {
      PB_RETURN_IF_ERROR(ParsePrototype(child, context, scan, false));
      continue;
    }
    FieldCodec codec;
    std::optional<Range> range;
    auto int_attribute = [&](const char* name, int64_t fallback) -> Expected<int64_t> {
      const std::string* s = child.Attribute(name);
      if (s == nullptr) return fallback;
      const auto value = ParseInt(*s);
      if (!value) return XmlError(child, what + ": bad " + name + " '" + *s + "'");
      return *value;
    };
    auto double_attribute = [&](const char* name, double fallback) -> Expected<double> {
      const std::string* s = child.Attribute(name);
      if (s == nullptr) return fallback;
      const auto value = ParseDouble(*s);
      if (!value || !std::isfinite(*value)) {
        return XmlError(child, what + ": bad " + name + " '" + *s + "'");
      }
      return *value;
    };
    if (*type == "Float") {
      const std::string* precision = child.Attribute("precision");
      if (precision == nullptr || *precision == "double") {
        codec.kind = FieldCodec::Kind::kFloat64;
      } else if (*precision == "single") {
        codec.kind = FieldCodec::Kind::kFloat32;
      } else {
        return XmlError(
            child, what + ": precision must be 'single' or 'double', found '" + *precision + "'");
      }
      if (child.Attribute("minimum") != nullptr && child.Attribute("maximum") != nullptr) {
        PB_ASSIGN_OR_RETURN(const double lo, double_attribute("minimum", 0.0));
        PB_ASSIGN_OR_RETURN(const double hi, double_attribute("maximum", 0.0));
        range = Range{lo, hi};
      }
    } else if (*type == "Integer" || *type == "ScaledInteger") {
      codec.kind =
          *type == "Integer" ? FieldCodec::Kind::kInteger : FieldCodec::Kind::kScaledInteger;
      PB_ASSIGN_OR_RETURN(codec.minimum,
                          int_attribute("minimum", std::numeric_limits<int64_t>::min()));
      PB_ASSIGN_OR_RETURN(codec.maximum,
                          int_attribute("maximum", std::numeric_limits<int64_t>::max()));
      if (codec.minimum > codec.maximum) {
        return XmlError(child, what + ": minimum " + std::to_string(codec.minimum) +
                                   " exceeds maximum " + std::to_string(codec.maximum));
      }
      if (codec.kind == FieldCodec::Kind::kScaledInteger) {
        PB_ASSIGN_OR_RETURN(codec.scale, double_attribute("scale", 1.0));
        PB_ASSIGN_OR_RETURN(codec.offset, double_attribute("offset", 0.0));
        if (codec.scale == 0.0) return XmlError(child, what + ": scale is 0");
      }
      const double lo = static_cast<double>(codec.minimum) * codec.scale + codec.offset;
      const double hi = static_cast<double>(codec.maximum) * codec.scale + codec.offset;
      range = Range{std::min(lo, hi), std::max(lo, hi)};
    } else {
      return Status::Unsupported(path_ + ": XML line " + std::to_string(child.line) + ": " + what +
                                 " has type '" + *type + "', which this reader does not support");
    }
    const int index = static_cast<int>(scan->points.fields.size());
    scan->points.fields.push_back(codec);
    if (top_level && child.Prefix().empty()) {
      for (int role = 0; role < kRoleCount; ++role) {
        if (child.name == kRoleNames[role]) {
          scan->field[role] = index;
          scan->field_range[role] = range;
        }
      }
    }
  }
  return Status::Ok();
}

Expected<ScanSpec> E57Reader::ParseScan(const XmlElement& element, int index) {
  ScanSpec scan;
  scan.index = index;
  scan.field.fill(-1);
  const std::string context = "data3D scan " + std::to_string(index) + ": ";
  scan.points.name = "data3D scan " + std::to_string(index) + " points";

  const XmlElement* points = element.Child("points");
  if (points == nullptr) return XmlError(element, context + "missing <points>");
  const std::string* type = points->Attribute("type");
  if (type == nullptr || *type != "CompressedVector") {
    return XmlError(*points, context + "<points> must have type=\"CompressedVector\"");
  }
  const std::string* file_offset = points->Attribute("fileOffset");
  const std::string* record_count = points->Attribute("recordCount");
  if (file_offset == nullptr || record_count == nullptr) {
    return XmlError(*points, context + "<points> needs attributes fileOffset and recordCount");
  }
  const auto offset_value = ParseInt(*file_offset);
  const auto count_value = ParseInt(*record_count);
  if (!offset_value || *offset_value < 0 || !count_value || *count_value < 0) {
    return XmlError(*points, context + "bad fileOffset '" + *file_offset + "' or recordCount '" +
                                 *record_count + "'");
  }
  scan.points.section_physical_offset = static_cast<uint64_t>(*offset_value);
  scan.points.record_count = static_cast<uint64_t>(*count_value);

  const XmlElement* prototype = points->Child("prototype");
  if (prototype == nullptr) return XmlError(*points, context + "missing <prototype>");
  PB_RETURN_IF_ERROR(ParsePrototype(*prototype, context, &scan, /*top_level=*/true));
  if (scan.points.fields.size() > 65535) {
    return XmlError(*prototype, context + "more than 65535 prototype fields");
  }
  if (const XmlElement* codecs = points->Child("codecs")) {
    for (const XmlElement& codec : codecs->children) {
      if (codec.Child("bitPackCodec") == nullptr) {
        const std::string name = codec.children.empty() ? codec.name : codec.children.back().name;
        return Status::Unsupported(path_ + ": XML line " + std::to_string(codec.line) + ": " +
                                   context + "codec '" + name +
                                   "' is not supported (only bitPackCodec)");
      }
    }
  }

  const auto& f = scan.field;
  if (f[kCartesianX] >= 0 && f[kCartesianY] >= 0 && f[kCartesianZ] >= 0) {
    scan.spherical = false;
  } else if (f[kRange] >= 0 && f[kAzimuth] >= 0 && f[kElevation] >= 0) {
    scan.spherical = true;
  } else {
    return XmlError(*prototype, context +
                                    "prototype has neither cartesianX/Y/Z nor "
                                    "sphericalRange/Azimuth/Elevation");
  }

  if (const XmlElement* pose = element.Child("pose")) {
    scan.has_pose = true;
    const std::string pose_context = context + "pose ";
    if (const XmlElement* rotation = pose->Child("rotation")) {
      const char* names[4] = {"w", "x", "y", "z"};
      for (int i = 0; i < 4; ++i) {
        PB_ASSIGN_OR_RETURN(scan.rotation[i],
                            ChildNumber(*rotation, names[i], i == 0 ? 1.0 : 0.0, pose_context));
      }
      const double norm =
          std::sqrt(scan.rotation[0] * scan.rotation[0] + scan.rotation[1] * scan.rotation[1] +
                    scan.rotation[2] * scan.rotation[2] + scan.rotation[3] * scan.rotation[3]);
      if (!(norm > 1e-9) || !std::isfinite(norm)) {
        return XmlError(*rotation, context + "pose rotation is not a unit quaternion");
      }
      for (double& q : scan.rotation) q /= norm;  // tolerate rounding in the file
    }
    if (const XmlElement* translation = pose->Child("translation")) {
      const char* names[3] = {"x", "y", "z"};
      for (int i = 0; i < 3; ++i) {
        PB_ASSIGN_OR_RETURN(scan.translation[i],
                            ChildNumber(*translation, names[i], 0.0, pose_context));
        if (!std::isfinite(scan.translation[i])) {
          return XmlError(*translation, context + "pose translation is not finite");
        }
      }
    }
  }

  // Normalization ranges: the limits element, else the field's own bounds,
  // else [0, 1] (Float fields without bounds).
  auto limits = [&](const char* limits_name, const char* min_name, const char* max_name,
                    Role role) -> Expected<Range> {
    Range range = scan.field_range[role].value_or(Range{0.0, 1.0});
    if (const XmlElement* node = element.Child(limits_name)) {
      PB_ASSIGN_OR_RETURN(range.min, ChildNumber(*node, min_name, range.min, context));
      PB_ASSIGN_OR_RETURN(range.max, ChildNumber(*node, max_name, range.max, context));
    }
    return range;
  };
  scan.has_colors = f[kRed] >= 0 && f[kGreen] >= 0 && f[kBlue] >= 0;
  if (scan.has_colors) {
    PB_ASSIGN_OR_RETURN(scan.color_range[0],
                        limits("colorLimits", "colorRedMinimum", "colorRedMaximum", kRed));
    PB_ASSIGN_OR_RETURN(scan.color_range[1],
                        limits("colorLimits", "colorGreenMinimum", "colorGreenMaximum", kGreen));
    PB_ASSIGN_OR_RETURN(scan.color_range[2],
                        limits("colorLimits", "colorBlueMinimum", "colorBlueMaximum", kBlue));
  }
  scan.has_intensity = f[kIntensity] >= 0;
  if (scan.has_intensity) {
    PB_ASSIGN_OR_RETURN(scan.intensity_range, limits("intensityLimits", "intensityMinimum",
                                                     "intensityMaximum", kIntensity));
  }
  return scan;
}

void E57Reader::ReportProgress() {
  if (!options_.progress || file_.bytes_loaded() < next_progress_bytes_) return;
  next_progress_bytes_ = file_.bytes_loaded() + kProgressBytes;
  options_.progress(
      std::min(1.0, static_cast<double>(file_.bytes_loaded()) /
                        static_cast<double>(std::max<uint64_t>(1, file_.file_bytes()))));
}

// Maps a value in `range` to [0, 1], clamped; a degenerate range maps to 0.
double Normalize(double value, const Range& range) {
  const double span = range.max - range.min;
  if (!(span > 0.0)) return 0.0;
  const double t = (value - range.min) / span;
  return t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
}

// `grid` (optional) is given the records' grid cells and local positions.
Status E57Reader::DecodeScan(const ScanSpec& scan, bool keep_colors, bool keep_intensity,
                             GridStationTest* grid) {
  PointCloud& cloud = result_.points;
  const auto& f = scan.field;
  const int invalid_field = scan.spherical ? f[kSphericalInvalid] : f[kCartesianInvalid];
  const int coordinate_fields[3] = {scan.spherical ? f[kRange] : f[kCartesianX],
                                    scan.spherical ? f[kAzimuth] : f[kCartesianY],
                                    scan.spherical ? f[kElevation] : f[kCartesianZ]};
  // Rotation matrix of the unit quaternion (w, x, y, z).
  const auto [w, qx, qy, qz] = scan.rotation;
  const double rot[3][3] = {
      {1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - w * qz), 2 * (qx * qz + w * qy)},
      {2 * (qx * qy + w * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - w * qx)},
      {2 * (qx * qz - w * qy), 2 * (qy * qz + w * qx), 1 - 2 * (qx * qx + qy * qy)}};
  uint64_t record = 0;

  auto on_batch = [&](size_t count, const std::vector<std::vector<double>>& columns) -> Status {
    const std::vector<double>& c0 = columns[coordinate_fields[0]];
    const std::vector<double>& c1 = columns[coordinate_fields[1]];
    const std::vector<double>& c2 = columns[coordinate_fields[2]];
    for (size_t i = 0; i < count; ++i, ++record) {
      if (invalid_field >= 0 && columns[invalid_field][i] != 0.0) {
        ++result_.no_return_points;
        continue;
      }
      double local[3];
      if (scan.spherical) {
        const double r = c0[i], az = c1[i], el = c2[i];
        local[0] = r * std::cos(el) * std::cos(az);
        local[1] = r * std::cos(el) * std::sin(az);
        local[2] = r * std::sin(el);
      } else {
        local[0] = c0[i];
        local[1] = c1[i];
        local[2] = c2[i];
      }
      double absolute[3];
      for (int a = 0; a < 3; ++a) {
        absolute[a] = rot[a][0] * local[0] + rot[a][1] * local[1] + rot[a][2] * local[2] +
                      scan.translation[a];
      }
      if (!std::isfinite(absolute[0]) || !std::isfinite(absolute[1]) ||
          !std::isfinite(absolute[2])) {
        if (options_.drop_invalid_points) {
          ++result_.dropped_points;
          continue;
        }
        return Status::Invalid(path_ + ": data3D scan " + std::to_string(scan.index) + " point " +
                               std::to_string(record) +
                               " has a NaN or infinite coordinate (drop_invalid_points skips it)");
      }
      if (grid != nullptr) {
        grid->Add(columns[f[kRowIndex]][i], columns[f[kColumnIndex]][i], local);
      }
      if (!have_origin_) {
        for (int a = 0; a < 3; ++a) {
          provisional_origin_[a] = std::round(absolute[a]);
          min_[a] = max_[a] = absolute[a];
        }
        have_origin_ = true;
      }
      for (int a = 0; a < 3; ++a) {
        min_[a] = std::min(min_[a], absolute[a]);
        max_[a] = std::max(max_[a], absolute[a]);
        cloud.positions.push_back(static_cast<float>(absolute[a] - provisional_origin_[a]));
      }
      // isColorInvalid / isIntensityInvalid != 0: the value is no
      // measurement (a point no photo covered); io.read_points gives it
      // its nearest valid neighbour's.
      const size_t index = cloud.positions.size() / 3 - 1;
      if (keep_colors && f[kColorInvalid] >= 0 && columns[f[kColorInvalid]][i] != 0.0) {
        result_.colorless_points.push_back(index);
      }
      if (keep_intensity && f[kIntensityInvalid] >= 0 && columns[f[kIntensityInvalid]][i] != 0.0) {
        result_.intensityless_points.push_back(index);
      }
      if (keep_colors) {
        for (int channel = 0; channel < 3; ++channel) {
          const double value = columns[f[kRed + channel]][i];
          cloud.colors.push_back(static_cast<uint8_t>(
              std::lround(Normalize(value, scan.color_range[channel]) * 255.0)));
        }
      }
      if (keep_intensity) {
        cloud.intensities.push_back(
            static_cast<float>(Normalize(columns[f[kIntensity]][i], scan.intensity_range)));
      }
    }
    ReportProgress();
    return Status::Ok();
  };
  return e57::DecodeCompressedVector(&file_, scan.points, on_batch);
}

Expected<ScanReadResult> E57Reader::Read() {
  PB_RETURN_IF_ERROR(file_.Open(path_));
  uint64_t xml_logical = 0, xml_length = 0;
  PB_RETURN_IF_ERROR(ReadHeader(&xml_logical, &xml_length));

  std::string xml(static_cast<size_t>(xml_length), '\0');
  PB_RETURN_IF_ERROR(file_.Read(xml_logical, xml.size(), reinterpret_cast<uint8_t*>(xml.data())));
  auto root = e57::ParseXml(xml);
  if (!root.ok()) return Status::Corrupt(path_ + ": XML " + root.status().message());
  xml = std::string();
  if (root->name != "e57Root") return XmlError(*root, "root element must be <e57Root>");

  const XmlElement* data3d = root->Child("data3D");
  std::vector<ScanSpec> scans;
  if (data3d != nullptr) {
    for (const XmlElement& child : data3d->children) {
      if (child.name != "vectorChild") continue;
      if (scans.size() >= 65535) return XmlError(child, "more than 65535 scans in data3D");
      PB_ASSIGN_OR_RETURN(ScanSpec scan, ParseScan(child, static_cast<int>(scans.size())));
      scans.push_back(std::move(scan));
    }
  }
  if (scans.empty()) {
    return Status::Invalid(path_ + ": no 3D data: data3D has no scans");
  }

  bool all_colors = true, any_colors = false, all_intensity = true, any_intensity = false;
  uint64_t total_records = 0;
  for (const ScanSpec& scan : scans) {
    all_colors &= scan.has_colors;
    any_colors |= scan.has_colors;
    all_intensity &= scan.has_intensity;
    any_intensity |= scan.has_intensity;
    total_records += scan.points.record_count;
  }
  if (any_colors && !all_colors) {
    result_.warnings.push_back("colors dropped: not every scan has colorRed/Green/Blue");
  }
  if (any_intensity && !all_intensity) {
    result_.warnings.push_back("intensities dropped: not every scan has intensity");
  }
  if (scans.size() > 1) result_.warnings.push_back(std::to_string(scans.size()) + " scans merged");

  // Reserve no more than the file can hold: at least 1 bit per record.
  PointCloud& cloud = result_.points;
  const uint64_t reserve = std::min<uint64_t>(total_records, file_.file_bytes() * 8);
  cloud.positions.reserve(reserve * 3);
  if (all_colors) cloud.colors.reserve(reserve * 3);
  if (all_intensity) cloud.intensities.reserve(reserve);

  // Each scan's scanner: at its pose's translation; without a pose (the
  // identity) at the origin of its frame when that is known to be the
  // scanner's: spherical coordinates are measured from it, and a row/column
  // grid whose steps seen from it are steady along every row and column was
  // swept from it (grid_station.h). Stations are kept when every scan has one.
  std::vector<size_t> first_point(scans.size() + 1, 0);
  std::vector<std::string> unknown;   // why a scan's scanner is not known
  std::vector<std::string> inferred;  // how a poseless scan's scanner was found
  bool worth_saying = false;         // a scan's station is known, or a grid failed the test
  for (const ScanSpec& scan : scans) {
    const std::string name = "data3D scan " + std::to_string(scan.index);
    const bool grid = options_.infer_stations && !scan.has_pose && !scan.spherical &&
                      scan.field[kRowIndex] >= 0 && scan.field[kColumnIndex] >= 0;
    GridStationTest test;
    first_point[scan.index] = cloud.size();
    PB_RETURN_IF_ERROR(DecodeScan(scan, all_colors, all_intensity, grid ? &test : nullptr));
    if (scan.has_pose) {
      worth_saying = true;
      continue;
    }
    if (scan.spherical) {
      worth_saying = true;
      inferred.push_back(name +
                         " has no pose: its scanner taken at its frame's origin, from which its "
                         "spherical coordinates are measured");
    } else if (!grid) {
      unknown.push_back(name + " has no pose and no row/column grid");
    } else if (const GridStationTest::Verdict verdict = test.Decide(); verdict.at_origin) {
      worth_saying = true;
      inferred.push_back(name + " has no pose: " + verdict.Finding("scanner"));
    } else {
      worth_saying = true;
      unknown.push_back(name + " has no pose, and " + verdict.Finding("scanner"));
    }
  }
  first_point[scans.size()] = cloud.size();
  // The caller sets the stations itself: nothing to say about the file's.
  if (!options_.infer_stations) {
    inferred.clear();
    worth_saying = false;
  }
  if (unknown.empty()) {
    // How the poseless scans' scanners were found: one line per scan, the
    // third for the rest of a file of many.
    for (size_t i = 0; i < inferred.size() && i < 3; ++i) {
      result_.warnings.push_back(
          inferred.size() > 3 && i == 2
              ? inferred[i] + " (and " + std::to_string(inferred.size() - 3) + " more scans alike)"
              : inferred[i]);
    }
    cloud.station_ids.resize(cloud.size());
    for (const ScanSpec& scan : scans) {
      cloud.stations.push_back(scan.translation);  // {0, 0, 0} without a pose
      std::fill(cloud.station_ids.begin() + first_point[scan.index],
                cloud.station_ids.begin() + first_point[scan.index + 1],
                static_cast<uint16_t>(scan.index));
    }
  } else if (worth_saying) {
    // Some scanners known, or a grid that was not swept from its origin:
    // say why there are no stations (normals are then oriented without
    // them): one scan without its scanner costs every scan its station.
    // Clouds without any pose or grid (merged, converted) say nothing.
    result_.warnings.push_back("no scanner stations: " + unknown.front() +
                               (unknown.size() > 1
                                    ? " (and " + std::to_string(unknown.size() - 1) + " more)"
                                    : std::string()) +
                               "; io.read_points `station` can declare where one scanner stood");
  }

  // Re-center on the bounding-box center rounded to 1 m. Both origins are
  // whole meters, so the exact double shift adds at most one float rounding.
  if (have_origin_) {
    std::array<double, 3> origin;
    for (int a = 0; a < 3; ++a) origin[a] = std::round((min_[a] + max_[a]) / 2.0) + 0.0;  // no -0
    if (origin != provisional_origin_) {
      double shift[3];
      for (int a = 0; a < 3; ++a) shift[a] = provisional_origin_[a] - origin[a];
      for (size_t i = 0; i < cloud.positions.size(); ++i) {
        cloud.positions[i] = static_cast<float>(cloud.positions[i] + shift[i % 3]);
      }
    }
    cloud.origin = origin;
  }
  result_.format = "e57";
  if (options_.progress) options_.progress(1.0);
  return std::move(result_);
}

}  // namespace

Expected<ScanReadResult> ReadE57(const std::string& path, const ScanReadOptions& options) {
  return E57Reader(path, options).Read();
}

}  // namespace pb
