#include "stages/geometry/io/ply.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <type_traits>
#include <string_view>

#include "stages/geometry/core/buffered_input.h"
#include "stages/geometry/core/text_parse.h"
#include "stages/geometry/io/grid_station.h"

namespace pb {
namespace {

// ---------------------------------------------------------------------------
// Header model.

enum class Scalar : uint8_t { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

struct ScalarName {
  std::string_view name;
  Scalar type;
};
constexpr ScalarName kScalarNames[] = {
    {"char", Scalar::kInt8},     {"int8", Scalar::kInt8},      {"uchar", Scalar::kUint8},
    {"uint8", Scalar::kUint8},   {"short", Scalar::kInt16},    {"int16", Scalar::kInt16},
    {"ushort", Scalar::kUint16}, {"uint16", Scalar::kUint16},  {"int", Scalar::kInt32},
    {"int32", Scalar::kInt32},   {"uint", Scalar::kUint32},    {"uint32", Scalar::kUint32},
    {"float", Scalar::kFloat32}, {"float32", Scalar::kFloat32}, {"double", Scalar::kFloat64},
    {"float64", Scalar::kFloat64},
};

size_t ScalarBytes(Scalar type) {
  switch (type) {
    case Scalar::kInt8:
    case Scalar::kUint8: return 1;
    case Scalar::kInt16:
    case Scalar::kUint16: return 2;
    case Scalar::kInt32:
    case Scalar::kUint32:
    case Scalar::kFloat32: return 4;
    case Scalar::kFloat64: return 8;
  }
  return 0;
}

bool IsFloatType(Scalar type) { return type == Scalar::kFloat32 || type == Scalar::kFloat64; }

enum class Format { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

const char* FormatName(Format format) {
  switch (format) {
    case Format::kAscii: return "ascii";
    case Format::kBinaryLittleEndian: return "binary_little_endian";
    case Format::kBinaryBigEndian: return "binary_big_endian";
  }
  return "";
}

// What a property means to us; kSkip for everything we do not read.
enum Role : uint8_t {
  kSkip, kX, kY, kZ, kNx, kNy, kNz, kRed, kGreen, kBlue, kU, kV, kTx, kTy, kTz, kTw,
  kIntensity, kStation, kRow, kColumn, kFaceIndices, kRoleCount
};

struct RoleName {
  std::string_view name;
  Role role;
};
constexpr RoleName kVertexRoles[] = {
    {"x", kX},           {"y", kY},           {"z", kZ},
    {"nx", kNx},         {"ny", kNy},         {"nz", kNz},
    {"red", kRed},       {"green", kGreen},   {"blue", kBlue},
    {"diffuse_red", kRed}, {"diffuse_green", kGreen}, {"diffuse_blue", kBlue},
    {"s", kU},           {"t", kV},           {"u", kU},
    {"v", kV},           {"texture_u", kU},   {"texture_v", kV},
    {"texture_s", kU},   {"texture_t", kV},   {"tx", kTx},
    {"ty", kTy},         {"tz", kTz},         {"tw", kTw},
    {"intensity", kIntensity}, {"scalar_intensity", kIntensity}, {"scalar_Intensity", kIntensity},
    {"station", kStation},
    // A structured scan's grid cell (E57's rowIndex / columnIndex, as
    // converters name them): only for GridStationTest.
    {"row", kRow},       {"col", kColumn},    {"column", kColumn},
    {"rowIndex", kRow},  {"columnIndex", kColumn},
    {"row_index", kRow}, {"column_index", kColumn},
};

struct Property {
  std::string name;
  Scalar type = Scalar::kFloat32;  // item type for lists
  bool is_list = false;
  Scalar count_type = Scalar::kUint8;
  Role role = kSkip;
  size_t offset = 0;  // byte offset inside a fixed-size binary record
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
  int line = 0;
  bool fixed_size = true;  // no list properties
  size_t record_bytes = 0;  // exact if fixed_size, else the minimum
};

// ---------------------------------------------------------------------------
// Scalar decoding.

template <typename T>
T Load(const uint8_t* bytes, bool swap) {
  uint8_t tmp[sizeof(T)];
  if (swap) {
    for (size_t i = 0; i < sizeof(T); ++i) tmp[i] = bytes[sizeof(T) - 1 - i];
    bytes = tmp;
  }
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

double Decode(const uint8_t* bytes, Scalar type, bool swap) {
  switch (type) {
    case Scalar::kInt8: return static_cast<int8_t>(bytes[0]);
    case Scalar::kUint8: return bytes[0];
    case Scalar::kInt16: return Load<int16_t>(bytes, swap);
    case Scalar::kUint16: return Load<uint16_t>(bytes, swap);
    case Scalar::kInt32: return Load<int32_t>(bytes, swap);
    case Scalar::kUint32: return Load<uint32_t>(bytes, swap);
    case Scalar::kFloat32: return Load<float>(bytes, swap);
    case Scalar::kFloat64: return Load<double>(bytes, swap);
  }
  return 0;
}

// Column decoding for the binary vertex fast path: one property of `n`
// fixed-size records (`stride` bytes apart) into every `dst_stride`-th slot of
// `dst`. Values convert as in Decode (through double), so both paths agree
// bit for bit.
template <typename T>
T ByteSwapped(T value) {
  if constexpr (sizeof(T) == 1) {
    return value;
  } else {
    using Bits = std::conditional_t<sizeof(T) == 2, uint16_t,
                                    std::conditional_t<sizeof(T) == 4, uint32_t, uint64_t>>;
    Bits bits = std::bit_cast<Bits>(value);
    if constexpr (sizeof(T) == 2) bits = __builtin_bswap16(bits);
    if constexpr (sizeof(T) == 4) bits = __builtin_bswap32(bits);
    if constexpr (sizeof(T) == 8) bits = __builtin_bswap64(bits);
    return std::bit_cast<T>(bits);
  }
}

template <typename In, bool kSwap, typename Out>
void DecodeColumnAs(const uint8_t* src, size_t stride, size_t n, Out* dst, size_t dst_stride) {
  for (size_t j = 0; j < n; ++j) {
    In value;
    std::memcpy(&value, src + j * stride, sizeof(In));
    if constexpr (kSwap) value = ByteSwapped(value);
    if constexpr (std::is_same_v<In, Out>) {
      dst[j * dst_stride] = value;
    } else {
      dst[j * dst_stride] = static_cast<Out>(static_cast<double>(value));
    }
  }
}

template <typename Out>
void DecodeColumn(Scalar type, bool swap, const uint8_t* src, size_t stride, size_t n, Out* dst,
                  size_t dst_stride) {
  auto run = [&]<typename In>() {
    if (swap) {
      DecodeColumnAs<In, true>(src, stride, n, dst, dst_stride);
    } else {
      DecodeColumnAs<In, false>(src, stride, n, dst, dst_stride);
    }
  };
  switch (type) {
    case Scalar::kInt8: return run.template operator()<int8_t>();
    case Scalar::kUint8: return run.template operator()<uint8_t>();
    case Scalar::kInt16: return run.template operator()<int16_t>();
    case Scalar::kUint16: return run.template operator()<uint16_t>();
    case Scalar::kInt32: return run.template operator()<int32_t>();
    case Scalar::kUint32: return run.template operator()<uint32_t>();
    case Scalar::kFloat32: return run.template operator()<float>();
    case Scalar::kFloat64: return run.template operator()<double>();
  }
}

uint8_t ColorToByte(double value, Scalar type) {
  double scaled = value;
  if (type == Scalar::kUint16) {
    scaled = value * (255.0 / 65535.0);
  } else if (IsFloatType(type)) {
    scaled = value * 255.0;
  }
  if (!(scaled > 0)) return 0;  // also NaN
  if (scaled >= 255) return 255;
  return static_cast<uint8_t>(std::lround(scaled));
}

// ---------------------------------------------------------------------------
// The parser.

class PlyParser {
 public:
  PlyParser(const std::string& path, const PlyReadOptions& options, bool keep_faces)
      : path_(path), options_(options), keep_faces_(keep_faces) {}

  // Per-point attributes that meshes do not carry, for ReadPlyPoints.
  std::vector<float> TakeIntensities() { return std::move(intensities_); }
  std::vector<uint16_t> TakeStationIds() { return std::move(station_ids_); }
  std::vector<std::array<double, 3>> TakeStations() { return std::move(stations_); }

  Status Run(Mesh* mesh, PlyReadReport* report) {
    PB_RETURN_IF_ERROR(in_.Open(path_, "a PLY file", &options_.progress));
    PB_RETURN_IF_ERROR(ParseHeader());
    PB_RETURN_IF_ERROR(PrepareElements());
    for (const Element& element : elements_) {
      if (format_ == Format::kAscii) {
        PB_RETURN_IF_ERROR(ReadAsciiElement(element));
      } else {
        PB_RETURN_IF_ERROR(ReadBinaryElement(element));
      }
    }
    PB_RETURN_IF_ERROR(CheckEndOfData());
    PB_RETURN_IF_ERROR(Finish());
    if (options_.progress) options_.progress(1.0);
    *mesh = std::move(mesh_);
    *report = std::move(report_);
    return Status::Ok();
  }

 private:
  Status HeaderError(int line, const std::string& what) const {
    return Status::Corrupt(path_ + ":" + std::to_string(line) + ": " + what);
  }

  Status ParseHeader() {
    std::string line;
    int line_number = 0;
    auto next_line = [&]() -> bool {
      if (!in_.ReadLine(&line)) return false;
      ++line_number;
      return true;
    };
    if (!next_line()) {
      PB_RETURN_IF_ERROR(in_.error());
      return Status::Corrupt(path_ + ": empty file (expected a PLY header starting with 'ply')");
    }
    if (line != "ply") return HeaderError(1, "expected 'ply' (is this a PLY file?)");
    bool have_format = false;
    std::array<double, 3> comment_origin{};
    bool have_origin = false;
    std::string origin_error;
    int origin_line = 0;
    while (true) {
      if (!next_line()) {
        PB_RETURN_IF_ERROR(in_.error());
        if (in_.line_too_long()) return HeaderError(line_number + 1, "header line too long");
        return HeaderError(line_number, "missing 'end_header' (the file ends inside the header)");
      }
      const std::vector<std::string_view> words = SplitWords(line);
      if (words.empty()) continue;
      const std::string_view keyword = words[0];
      if (keyword == "end_header") {
        break;
      } else if (keyword == "format") {
        static constexpr Format kFormats[] = {Format::kAscii, Format::kBinaryLittleEndian,
                                              Format::kBinaryBigEndian};
        bool known = false;
        for (Format format : kFormats) {
          if (words.size() == 3 && words[1] == FormatName(format) &&
              (words[2] == "1.0" || words[2] == "1")) {
            format_ = format;
            known = true;
          }
        }
        if (!known) {
          return HeaderError(line_number,
                             "expected 'format ascii 1.0', 'format binary_little_endian 1.0' or "
                             "'format binary_big_endian 1.0', got '" + line + "'");
        }
        have_format = true;
      } else if (keyword == "comment" || keyword == "obj_info") {
        const size_t start = line.find(keyword) + keyword.size();
        std::string text = line.substr(std::min(line.size(), start + 1));
        if (keyword == "comment" && words.size() >= 2 && words[1] == "pointbake") {
          int version = 0;
          if (words.size() != 4 || (words[2] != "points" && words[2] != "mesh") ||
              std::from_chars(words[3].data(), words[3].data() + words[3].size(), version).ec !=
                  std::errc()) {
            return HeaderError(line_number, "expected 'comment pointbake points|mesh <version>'");
          }
          report_.pointbake_kind = std::string(words[2]);
          report_.pointbake_version = version;
          const int supported = words[2] == "points" ? kPlyPointsVersion : kPlyMeshVersion;
          if (version > supported || version < 1) {
            return Status::Unsupported(path_ + ":" + std::to_string(line_number) +
                                       ": pointbake " + std::string(words[2]) +
                                       " format version " + std::to_string(version) +
                                       "; this build reads version " + std::to_string(supported));
          }
        } else if (keyword == "comment" && words.size() >= 2 && words[1] == "station") {
          // "comment station I X Y Z": scanner position I, absolute meters.
          uint64_t index = 0;
          std::array<double, 3> position{};
          bool parsed = words.size() == 6 && ParseUint(words[2], &index) &&
                        index == stations_.size() && index < 65535;
          for (int axis = 0; parsed && axis < 3; ++axis)
            parsed = ParseDouble(words[3 + axis], &position[axis]) && std::isfinite(position[axis]);
          if (!parsed)
            return HeaderError(line_number, "expected 'comment station " +
                                                std::to_string(stations_.size()) +
                                                " X Y Z' (stations numbered from 0, in order)");
          stations_.push_back(position);
        } else if (keyword == "comment" && words.size() >= 2 && words[1] == "origin") {
          bool parsed = words.size() == 5;
          for (int axis = 0; parsed && axis < 3; ++axis) {
            parsed = ParseDouble(words[2 + axis], &comment_origin[axis]) &&
                     std::isfinite(comment_origin[axis]);
          }
          if (parsed) {
            have_origin = true;
          } else {
            origin_error = "expected 'comment origin X Y Z' with three finite numbers";
            origin_line = line_number;
          }
        }
        report_.comments.push_back(std::move(text));
      } else if (keyword == "element") {
        Element element;
        if (words.size() != 3 || !ParseUint(words[2], &element.count)) {
          return HeaderError(line_number, "expected 'element <name> <count>', got '" + line + "'");
        }
        element.name = std::string(words[1]);
        element.line = line_number;
        elements_.push_back(std::move(element));
      } else if (keyword == "property") {
        if (elements_.empty()) return HeaderError(line_number, "'property' before any 'element'");
        Property property;
        auto scalar_of = [&](std::string_view name, Scalar* type) -> Status {
          for (const ScalarName& candidate : kScalarNames) {
            if (candidate.name == name) {
              *type = candidate.type;
              return Status::Ok();
            }
          }
          return HeaderError(line_number,
                             "unknown property type '" + std::string(name) +
                                 "' (expected char, uchar, short, ushort, int, uint, float, "
                                 "double or int8 ... float64)");
        };
        if (words.size() == 5 && words[1] == "list") {
          property.is_list = true;
          PB_RETURN_IF_ERROR(scalar_of(words[2], &property.count_type));
          PB_RETURN_IF_ERROR(scalar_of(words[3], &property.type));
          if (IsFloatType(property.count_type)) {
            return HeaderError(line_number, "a list count type must be an integer type");
          }
          property.name = std::string(words[4]);
        } else if (words.size() == 3 && words[1] != "list") {
          PB_RETURN_IF_ERROR(scalar_of(words[1], &property.type));
          property.name = std::string(words[2]);
        } else {
          return HeaderError(line_number,
                             "expected 'property <type> <name>' or "
                             "'property list <count type> <item type> <name>', got '" + line + "'");
        }
        elements_.back().properties.push_back(std::move(property));
      } else {
        return HeaderError(line_number, "unknown header keyword '" + std::string(keyword) + "'");
      }
    }
    if (!have_format) return HeaderError(line_number, "missing 'format' line before end_header");
    if (!origin_error.empty() && !report_.pointbake_kind.empty()) {
      return HeaderError(origin_line, origin_error);
    }
    if (have_origin) origin_ = comment_origin;
    header_lines_ = line_number;
    report_.format = FormatName(format_);
    return Status::Ok();
  }

  Status PrepareElements() {
    swap_ = (format_ == Format::kBinaryBigEndian) != (std::endian::native == std::endian::big);
    const Element* vertex = nullptr;
    for (Element& element : elements_) {
      element.fixed_size = true;
      element.record_bytes = 0;
      for (Property& property : element.properties) {
        property.offset = element.record_bytes;
        if (property.is_list) {
          element.fixed_size = false;
          element.record_bytes += ScalarBytes(property.count_type);
        } else {
          element.record_bytes += ScalarBytes(property.type);
        }
        if (element.name == "vertex" && !property.is_list) {
          for (const RoleName& role : kVertexRoles) {
            if (role.name == property.name) property.role = role.role;
          }
        } else if (element.name == "face" && property.is_list &&
                   (property.name == "vertex_indices" || property.name == "vertex_index")) {
          if (IsFloatType(property.type)) {
            return HeaderError(element.line, "face '" + property.name +
                                                 "' must hold integers, not floating point");
          }
          property.role = kFaceIndices;
          has_face_indices_ = true;
        }
      }
      if (element.name == "vertex" && vertex == nullptr) vertex = &element;
    }
    if (vertex == nullptr) return Status::Corrupt(path_ + ": no 'vertex' element in the header");
    bool present[kRoleCount] = {};
    for (const Property& property : vertex->properties) {
      present[property.role] = true;
      if (property.role == kRed) color_types_[0] = property.type;
      if (property.role == kGreen) color_types_[1] = property.type;
      if (property.role == kBlue) color_types_[2] = property.type;
      if ((property.role == kX || property.role == kY || property.role == kZ) &&
          property.type != Scalar::kFloat32) {
        recenter_ = true;
      }
    }
    for (Role role : {kX, kY, kZ}) {
      if (!present[role]) {
        return HeaderError(vertex->line, "element 'vertex' has no property '" +
                                             std::string(role == kX ? "x" : role == kY ? "y" : "z") +
                                             "'");
      }
    }
    has_normals_ = present[kNx] && present[kNy] && present[kNz];
    has_colors_ = present[kRed] && present[kGreen] && present[kBlue];
    has_uvs_ = present[kU] && present[kV];
    has_tangents_ = present[kTx] && present[kTy] && present[kTz] && present[kTw];
    has_intensities_ = present[kIntensity];
    has_stations_ = present[kStation];
    if (has_stations_ && stations_.empty())
      return Status::Corrupt(path_ + ": vertices have a 'station' property but the header "
                                     "names no 'comment station I X Y Z'");
    // A structured scan's grid (row and column per point) and no station
    // named: its scanner at the origin of the file's frame when the grid was
    // swept from there (grid_station.h), as for an E57 without a pose.
    if (!keep_faces_ && options_.infer_stations && stations_.empty() && present[kRow] &&
        present[kColumn]) {
      grid_.emplace();
    }
    vertex_count_ = vertex->count;
    report_.vertices_in_file = vertex->count;
    for (const Element& element : elements_) {
      if (element.name == "face") report_.faces_in_file += element.count;
    }
    if (keep_faces_ && has_face_indices_ && vertex_count_ > std::numeric_limits<uint32_t>::max()) {
      return Status::Unsupported(path_ + ": " + std::to_string(vertex_count_) +
                                 " vertices; meshes are limited to 2^32 vertices");
    }
    // Reserve, but never more than the bytes left in the file could hold, so a
    // corrupt count fails as truncation instead of exhausting memory.
    const uint64_t remaining = in_.remaining();
    const uint64_t min_bytes =
        format_ == Format::kAscii ? 2 * vertex->properties.size() : std::max<size_t>(1, vertex->record_bytes);
    const size_t reserve = static_cast<size_t>(std::min(vertex_count_, remaining / std::max<uint64_t>(1, min_bytes)));
    mesh_.positions.reserve(3 * reserve);
    if (has_normals_) mesh_.normals.reserve(3 * reserve);
    if (has_colors_) mesh_.colors.reserve(3 * reserve);
    if (has_uvs_) mesh_.uvs.reserve(2 * reserve);
    if (has_tangents_) mesh_.tangents.reserve(4 * reserve);
    if (has_intensities_) intensities_.reserve(reserve);
    if (has_stations_) station_ids_.reserve(reserve);
    return Status::Ok();
  }

  enum class Kind { kVertex, kFace, kOther };
  Kind KindOf(const Element& element) const {
    if (element.name == "vertex" && &element == FirstVertex()) return Kind::kVertex;
    if (element.name == "face" && keep_faces_ && has_face_indices_) return Kind::kFace;
    return Kind::kOther;
  }
  const Element* FirstVertex() const {
    for (const Element& element : elements_) {
      if (element.name == "vertex") return &element;
    }
    return nullptr;
  }

  Status Truncated(const Element& element, uint64_t index, uint64_t byte) const {
    PB_RETURN_IF_ERROR(in_.error());
    return Status::Corrupt(path_ + ": truncated: " + element.name + " " + std::to_string(index) +
                           " of " + std::to_string(element.count) + " at byte " +
                           std::to_string(byte));
  }

  // Where an error in the body happened: a line (ascii) or a byte (binary).
  Status BodyError(uint64_t place, const std::string& what) const {
    if (format_ == Format::kAscii) {
      return Status::Corrupt(path_ + ":" + std::to_string(place) + ": " + what);
    }
    return Status::Corrupt(path_ + ": " + what + " (at byte " + std::to_string(place) + ")");
  }

  Status ReadBinaryElement(const Element& element) {
    const Kind kind = KindOf(element);
    if (kind == Kind::kVertex && element.fixed_size) return ReadFixedBinaryVertices(element);
    if (kind == Kind::kOther && element.fixed_size) {
      const uint64_t start = in_.offset();
      const uint64_t want = element.count * element.record_bytes;
      if (element.record_bytes != 0 && want / element.record_bytes != element.count) {
        return Truncated(element, 0, start);  // the count overflows any file
      }
      const uint64_t skipped = in_.Skip(want);
      if (skipped < want) {
        const uint64_t index = skipped / element.record_bytes;
        return Truncated(element, index, start + index * element.record_bytes);
      }
      return Status::Ok();
    }
    std::vector<uint8_t> record(std::max<size_t>(element.record_bytes, 8));
    uint8_t item[8];
    for (uint64_t i = 0; i < element.count; ++i) {
      const uint64_t start = in_.offset();
      face_.clear();
      if (element.fixed_size) {
        if (!in_.Read(record.data(), element.record_bytes)) return Truncated(element, i, start);
        for (const Property& property : element.properties) {
          if (property.role != kSkip) {
            values_[property.role] = Decode(record.data() + property.offset, property.type, swap_);
          }
        }
      } else {
        for (const Property& property : element.properties) {
          if (!property.is_list) {
            if (!in_.Read(item, ScalarBytes(property.type))) return Truncated(element, i, start);
            if (property.role != kSkip) values_[property.role] = Decode(item, property.type, swap_);
            continue;
          }
          if (!in_.Read(item, ScalarBytes(property.count_type))) return Truncated(element, i, start);
          const double count_value = Decode(item, property.count_type, swap_);
          if (count_value < 0) {
            return BodyError(start, element.name + " " + std::to_string(i) + ": negative list count " +
                                        FormatDouble(count_value) + " for '" + property.name + "'");
          }
          const uint64_t count = static_cast<uint64_t>(count_value);
          const size_t item_bytes = ScalarBytes(property.type);
          if (property.role == kFaceIndices) {
            for (uint64_t k = 0; k < count; ++k) {
              if (!in_.Read(item, item_bytes)) return Truncated(element, i, start);
              face_.push_back(Decode(item, property.type, swap_));
            }
          } else if (in_.Skip(count * item_bytes) < count * item_bytes) {
            return Truncated(element, i, start);
          }
        }
      }
      if (kind == Kind::kVertex) {
        PB_RETURN_IF_ERROR(AddVertex(i, start));
      } else if (kind == Kind::kFace) {
        PB_RETURN_IF_ERROR(AddFace(i, start));
      }
    }
    return Status::Ok();
  }

  // Records per fast-path block: their bytes and the decoded columns fit in a
  // typical 32-48 KiB L1 data cache for the usual 12-40 byte records.
  static constexpr size_t kFastBlockBytes = 16 * 1024;

  // The fast path for the usual binary vertex element (no list properties):
  // blocks of records are decoded column by column, each column by a loop
  // specialized for its type and byte order, into block-sized arrays that
  // stay in cache; the points kept are then appended to the output arrays
  // (reserved in PrepareElements, so they grow without reallocating and
  // without zero-filling). Errors, NaN handling and recentering are those of
  // the generic path (AddVertex), record for record.
  Status ReadFixedBinaryVertices(const Element& element) {
    const size_t record_bytes = element.record_bytes;
    // The last property of a role wins, as values_[role] does in the generic path.
    const Property* field[kRoleCount] = {};
    for (const Property& property : element.properties) field[property.role] = &property;

    const size_t block_records =
        std::max<size_t>(1, std::min<size_t>(4096, kFastBlockBytes / record_bytes));
    // One block of decoded values per output array.
    struct FloatArray {
      std::vector<float>* out;
      size_t width;
      std::vector<float> block;
      // Set when all components are native-order float32 stored side by side
      // in the record (e.g. x y z as pointbake writes them): one memcpy each.
      std::optional<size_t> packed_offset;
    };
    struct FloatColumn {
      const Property* property;
      size_t array, component;
    };
    std::vector<FloatArray> arrays;
    std::vector<FloatColumn> columns;  // for the arrays that are not packed
    auto add_array = [&](std::vector<float>* out, std::initializer_list<Role> roles) {
      FloatArray array{out, roles.size(), std::vector<float>(roles.size() * block_records), {}};
      bool packed = !swap_;
      size_t component = 0;
      for (Role role : roles) {
        packed = packed && field[role]->type == Scalar::kFloat32 &&
                 field[role]->offset == field[*roles.begin()]->offset + 4 * component;
        ++component;
      }
      if (packed) array.packed_offset = field[*roles.begin()]->offset;
      component = 0;
      for (Role role : roles) {
        if (!packed) columns.push_back({field[role], arrays.size(), component});
        ++component;
      }
      arrays.push_back(std::move(array));
    };
    if (!recenter_) add_array(&mesh_.positions, {kX, kY, kZ});  // positions are arrays[0]
    if (has_normals_) add_array(&mesh_.normals, {kNx, kNy, kNz});
    if (has_uvs_) add_array(&mesh_.uvs, {kU, kV});
    if (has_tangents_) add_array(&mesh_.tangents, {kTx, kTy, kTz, kTw});
    if (has_intensities_) add_array(&intensities_, {kIntensity});
    std::vector<double> xyz(recenter_ ? 3 * block_records : 0);
    std::vector<float> recentered(recenter_ ? 3 * block_records : 0);
    std::vector<uint8_t> colors(has_colors_ ? 3 * block_records : 0);
    std::vector<double> stations(has_stations_ ? block_records : 0);
    std::vector<uint16_t> station_ids(has_stations_ ? block_records : 0);
    std::vector<double> scratch(block_records);
    std::vector<double> grid_cells(grid_ ? 2 * block_records : 0);  // row, column per record
    const double station_limit = static_cast<double>(stations_.size());

    std::vector<uint8_t> records(block_records * record_bytes);
    for (uint64_t first = 0; first < element.count;) {
      const size_t want =
          static_cast<size_t>(std::min<uint64_t>(block_records, element.count - first));
      const uint64_t block_start = in_.offset();
      const size_t n = in_.ReadUpTo(records.data(), want * record_bytes) / record_bytes;
      for (FloatArray& array : arrays) {
        if (!array.packed_offset) continue;
        const uint8_t* source = records.data() + *array.packed_offset;
        float* destination = array.block.data();
        // A constant size lets the compiler inline each memcpy as one move.
        auto copy = [&]<size_t kWidth>() {
          for (size_t j = 0; j < n; ++j) {
            std::memcpy(destination + kWidth * j, source + record_bytes * j, 4 * kWidth);
          }
        };
        switch (array.width) {
          case 1: copy.template operator()<1>(); break;
          case 2: copy.template operator()<2>(); break;
          case 3: copy.template operator()<3>(); break;
          default: copy.template operator()<4>(); break;  // tangents
        }
      }
      for (const FloatColumn& column : columns) {
        FloatArray& array = arrays[column.array];
        DecodeColumn(column.property->type, swap_, records.data() + column.property->offset,
                     record_bytes, n, array.block.data() + column.component, array.width);
      }
      if (recenter_) {
        for (Role role : {kX, kY, kZ}) {
          DecodeColumn(field[role]->type, swap_, records.data() + field[role]->offset,
                       record_bytes, n, xyz.data() + (role - kX), 3);
        }
      }
      if (has_colors_) {
        for (int channel = 0; channel < 3; ++channel) {
          const Property& property = *field[kRed + channel];
          const uint8_t* source = records.data() + property.offset;
          if (property.type == Scalar::kUint8) {
            DecodeColumn(property.type, swap_, source, record_bytes, n, colors.data() + channel, 3);
          } else {
            DecodeColumn(property.type, swap_, source, record_bytes, n, scratch.data(), 1);
            for (size_t j = 0; j < n; ++j) {
              colors[3 * j + channel] = ColorToByte(scratch[j], property.type);
            }
          }
        }
      }
      if (has_stations_) {
        DecodeColumn(field[kStation]->type, swap_, records.data() + field[kStation]->offset,
                     record_bytes, n, stations.data(), 1);
      }
      if (grid_) {
        for (Role role : {kRow, kColumn}) {
          DecodeColumn(field[role]->type, swap_, records.data() + field[role]->offset,
                       record_bytes, n, grid_cells.data() + (role - kRow), 2);
        }
      }

      // Check the records in order. The leading run of good records needs no
      // moving; after the first bad one, record j moves to slot kept < j.
      size_t kept = 0;
      if (!recenter_) {
        const float* positions = arrays[0].block.data();
        for (; kept < n; ++kept) {
          const float* p = positions + 3 * kept;
          if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) break;
        }
      }
      if (has_stations_) {
        size_t good = 0;
        for (; good < kept; ++good) {
          if (!(stations[good] >= 0 && stations[good] < station_limit)) break;
          station_ids[good] = static_cast<uint16_t>(stations[good]);
        }
        kept = good;
      }
      if (!remap_.empty()) {
        const uint32_t base = static_cast<uint32_t>(Count(mesh_.positions));
        for (size_t j = 0; j < kept; ++j) remap_[first + j] = base + static_cast<uint32_t>(j);
      }
      for (size_t j = kept; j < n; ++j) {
        const uint64_t index = first + j;
        double position[3];
        for (int axis = 0; axis < 3; ++axis) {
          position[axis] = recenter_ ? xyz[3 * j + axis] : arrays[0].block[3 * j + axis];
        }
        if (!(std::isfinite(position[0]) && std::isfinite(position[1]) &&
              std::isfinite(position[2]))) {
          PB_RETURN_IF_ERROR(DropInvalidVertex(index, block_start + j * record_bytes, position));
          continue;
        }
        if (has_stations_) {
          if (!(stations[j] >= 0 && stations[j] < station_limit)) {
            return StationError(index, block_start + j * record_bytes, stations[j]);
          }
          station_ids[kept] = static_cast<uint16_t>(stations[j]);
        }
        if (!remap_.empty()) {
          remap_[index] = static_cast<uint32_t>(Count(mesh_.positions) + kept);
        }
        if (recenter_) std::copy_n(&xyz[3 * j], 3, &xyz[3 * kept]);
        if (has_colors_) std::copy_n(&colors[3 * j], 3, &colors[3 * kept]);
        if (grid_) std::copy_n(&grid_cells[2 * j], 2, &grid_cells[2 * kept]);
        for (FloatArray& array : arrays) {
          std::copy_n(&array.block[array.width * j], array.width, &array.block[array.width * kept]);
        }
        ++kept;
      }

      if (grid_) {
        for (size_t j = 0; j < kept; ++j) {
          const double position[3] = {
              recenter_ ? xyz[3 * j] : arrays[0].block[3 * j],
              recenter_ ? xyz[3 * j + 1] : arrays[0].block[3 * j + 1],
              recenter_ ? xyz[3 * j + 2] : arrays[0].block[3 * j + 2]};
          grid_->Add(grid_cells[2 * j], grid_cells[2 * j + 1], position);
        }
      }
      if (recenter_) {
        for (size_t j = 0; j < kept; ++j) StoreRecentered(&xyz[3 * j], &recentered[3 * j]);
        mesh_.positions.insert(mesh_.positions.end(), recentered.begin(),
                               recentered.begin() + 3 * kept);
      }
      for (FloatArray& array : arrays) {
        array.out->insert(array.out->end(), array.block.begin(),
                          array.block.begin() + array.width * kept);
      }
      if (has_colors_) {
        mesh_.colors.insert(mesh_.colors.end(), colors.begin(), colors.begin() + 3 * kept);
      }
      if (has_stations_) {
        station_ids_.insert(station_ids_.end(), station_ids.begin(), station_ids.begin() + kept);
      }
      first += n;
      if (n < want) return Truncated(element, first, block_start + n * record_bytes);
    }
    return Status::Ok();
  }

  static size_t Count(const std::vector<float>& positions) { return positions.size() / 3; }

  // Next whitespace-separated token of the ascii body; false at end of file.
  bool NextToken(std::string_view* token) {
    while (true) {
      while (token_pos_ < line_.size() && IsBlankChar(line_[token_pos_])) ++token_pos_;
      if (token_pos_ < line_.size()) {
        const size_t start = token_pos_;
        while (token_pos_ < line_.size() && !IsBlankChar(line_[token_pos_])) ++token_pos_;
        *token = std::string_view(line_).substr(start, token_pos_ - start);
        return true;
      }
      if (!in_.ReadLine(&line_)) return false;
      ++line_number_;
      token_pos_ = 0;
    }
  }

  Status AsciiTruncated(const Element& element, uint64_t index) const {
    PB_RETURN_IF_ERROR(in_.error());
    if (in_.line_too_long()) return BodyError(line_number_ + 1, "line too long");
    return BodyError(line_number_, "truncated: " + element.name + " " + std::to_string(index) +
                                       " of " + std::to_string(element.count));
  }

  Status ReadAsciiValue(const Element& element, uint64_t index, const Property& property,
                        bool is_count, double* value) {
    std::string_view token;
    if (!NextToken(&token)) return AsciiTruncated(element, index);
    if (!ParseDouble(token, value)) {
      return BodyError(line_number_, element.name + " " + std::to_string(index) +
                                         ": expected a number for '" + property.name + "', got '" +
                                         std::string(token) + "'");
    }
    if (is_count && !(*value >= 0 && *value == std::floor(*value))) {
      return BodyError(line_number_, element.name + " " + std::to_string(index) +
                                         ": expected a list count for '" + property.name +
                                         "', got '" + std::string(token) + "'");
    }
    return Status::Ok();
  }

  Status ReadAsciiElement(const Element& element) {
    if (line_number_ == 0) line_number_ = header_lines_;
    const Kind kind = KindOf(element);
    for (uint64_t i = 0; i < element.count; ++i) {
      face_.clear();
      uint64_t first_line = 0;
      for (const Property& property : element.properties) {
        double value = 0;
        if (!property.is_list) {
          PB_RETURN_IF_ERROR(ReadAsciiValue(element, i, property, false, &value));
          if (first_line == 0) first_line = line_number_;
          if (property.role != kSkip) values_[property.role] = value;
          continue;
        }
        PB_RETURN_IF_ERROR(ReadAsciiValue(element, i, property, true, &value));
        if (first_line == 0) first_line = line_number_;
        const uint64_t count = static_cast<uint64_t>(value);
        for (uint64_t k = 0; k < count; ++k) {
          PB_RETURN_IF_ERROR(ReadAsciiValue(element, i, property, false, &value));
          if (property.role == kFaceIndices) face_.push_back(value);
        }
      }
      if (first_line == 0) first_line = line_number_;
      if (kind == Kind::kVertex) {
        PB_RETURN_IF_ERROR(AddVertex(i, first_line));
      } else if (kind == Kind::kFace) {
        PB_RETURN_IF_ERROR(AddFace(i, first_line));
      }
    }
    return Status::Ok();
  }

  Status CheckEndOfData() {
    std::string counts;
    for (const Element& element : elements_) {
      counts += (counts.empty() ? "" : ", ") + element.name + " " + std::to_string(element.count);
    }
    if (format_ == Format::kAscii) {
      if (line_number_ == 0) line_number_ = header_lines_;
      std::string_view token;
      if (NextToken(&token)) {
        return BodyError(line_number_, "unexpected data '" + std::string(token) +
                                           "' after the last element (the header declares " +
                                           counts + ")");
      }
      return in_.error();
    }
    const uint64_t end = in_.offset();
    char tail[3];
    size_t tail_bytes = 0;
    while (tail_bytes < sizeof tail && in_.Read(tail + tail_bytes, 1)) ++tail_bytes;
    PB_RETURN_IF_ERROR(in_.error());
    // A trailing newline is harmless; anything else means the counts are wrong.
    const bool only_newline = tail_bytes == 0 || (tail_bytes == 1 && tail[0] == '\n') ||
                              (tail_bytes == 2 && tail[0] == '\r' && tail[1] == '\n');
    if (!only_newline) {
      return Status::Corrupt(path_ + ": " + std::to_string(in_.size() - end) +
                             " bytes of unexpected data after the last element at byte " +
                             std::to_string(end) + " (the header declares " + counts + ")");
    }
    return Status::Ok();
  }

  // A vertex with a non-finite coordinate: the error, or (drop_invalid_points)
  // counted and, for meshes, remembered so that faces can be remapped.
  Status DropInvalidVertex(uint64_t index, uint64_t place, const double position[3]) {
    if (!options_.drop_invalid_points) {
      return BodyError(place, "vertex " + std::to_string(index) + " has a non-finite coordinate (" +
                                  FormatDouble(position[0]) + " " + FormatDouble(position[1]) +
                                  " " + FormatDouble(position[2]) +
                                  "); drop such points with drop_invalid_points");
    }
    if (remap_.empty() && keep_faces_ && has_face_indices_) {
      remap_.resize(vertex_count_, kDropped);
      for (uint64_t k = 0; k < index; ++k) remap_[k] = static_cast<uint32_t>(k);
    }
    ++report_.dropped_points;
    return Status::Ok();
  }

  Status StationError(uint64_t index, uint64_t place, double station) const {
    return BodyError(place, "vertex " + std::to_string(index) + " names station " +
                                FormatDouble(station) + " but the header lists " +
                                std::to_string(stations_.size()));
  }

  // Non-float32 coordinates may be georeferenced: store them relative to a
  // provisional origin (the first point, rounded to 1 m) and move to the
  // bounding-box center in Finish().
  void StoreRecentered(double position[3], float* out) {
    for (int axis = 0; axis < 3; ++axis) position[axis] += origin_[axis];
    if (!have_provisional_origin_) {
      for (int axis = 0; axis < 3; ++axis) provisional_origin_[axis] = std::round(position[axis]);
      have_provisional_origin_ = true;
    }
    for (int axis = 0; axis < 3; ++axis) {
      out[axis] = static_cast<float>(position[axis] - provisional_origin_[axis]);
    }
  }

  // The generic path: one vertex from values_.
  Status AddVertex(uint64_t index, uint64_t place) {
    double position[3] = {values_[kX], values_[kY], values_[kZ]};
    const bool finite =
        std::isfinite(position[0]) && std::isfinite(position[1]) && std::isfinite(position[2]);
    if (!finite) return DropInvalidVertex(index, place, position);
    if (has_stations_) {
      const double station = values_[kStation];
      if (!(station >= 0 && station < static_cast<double>(stations_.size())))
        return StationError(index, place, station);
    }
    if (!remap_.empty()) remap_[index] = static_cast<uint32_t>(mesh_.positions.size() / 3);
    if (grid_) grid_->Add(values_[kRow], values_[kColumn], position);  // the file's frame
    if (recenter_) {
      float stored[3];
      StoreRecentered(position, stored);
      mesh_.positions.insert(mesh_.positions.end(), stored, stored + 3);
    } else {
      for (int axis = 0; axis < 3; ++axis) {
        mesh_.positions.push_back(static_cast<float>(position[axis]));
      }
    }
    if (has_normals_) {
      for (Role role : {kNx, kNy, kNz}) mesh_.normals.push_back(static_cast<float>(values_[role]));
    }
    if (has_colors_) {
      mesh_.colors.push_back(ColorToByte(values_[kRed], color_types_[0]));
      mesh_.colors.push_back(ColorToByte(values_[kGreen], color_types_[1]));
      mesh_.colors.push_back(ColorToByte(values_[kBlue], color_types_[2]));
    }
    if (has_uvs_) {
      mesh_.uvs.push_back(static_cast<float>(values_[kU]));
      mesh_.uvs.push_back(static_cast<float>(values_[kV]));
    }
    if (has_tangents_) {
      for (Role role : {kTx, kTy, kTz, kTw}) {
        mesh_.tangents.push_back(static_cast<float>(values_[role]));
      }
    }
    if (has_intensities_) intensities_.push_back(static_cast<float>(values_[kIntensity]));
    if (has_stations_) station_ids_.push_back(static_cast<uint16_t>(values_[kStation]));
    return Status::Ok();
  }

  Status AddFace(uint64_t index, uint64_t place) {
    if (face_.size() < 3) {
      ++report_.dropped_triangles;
      return Status::Ok();
    }
    for (double corner : face_) {
      if (!(corner >= 0 && corner < static_cast<double>(vertex_count_))) {
        return BodyError(place, "face " + std::to_string(index) + " refers to vertex " +
                                    FormatDouble(corner) + " but the file has " +
                                    std::to_string(vertex_count_) + " vertices");
      }
    }
    // Polygons become triangle fans around their first corner.
    for (size_t k = 1; k + 1 < face_.size(); ++k) {
      mesh_.indices.push_back(static_cast<uint32_t>(face_[0]));
      mesh_.indices.push_back(static_cast<uint32_t>(face_[k]));
      mesh_.indices.push_back(static_cast<uint32_t>(face_[k + 1]));
    }
    return Status::Ok();
  }

  Status Finish() {
    if (grid_) DecideGridStation();
    if (!remap_.empty()) {
      size_t kept = 0;
      for (size_t t = 0; t + 2 < mesh_.indices.size(); t += 3) {
        const uint32_t a = remap_[mesh_.indices[t]];
        const uint32_t b = remap_[mesh_.indices[t + 1]];
        const uint32_t c = remap_[mesh_.indices[t + 2]];
        if (a == kDropped || b == kDropped || c == kDropped) {
          ++report_.dropped_triangles;
          continue;
        }
        mesh_.indices[kept++] = a;
        mesh_.indices[kept++] = b;
        mesh_.indices[kept++] = c;
      }
      mesh_.indices.resize(kept);
      std::vector<uint32_t>().swap(remap_);
    }
    if (!recenter_) {
      mesh_.origin = origin_;
      return Status::Ok();
    }
    // Move from the provisional origin to the bounding-box center rounded to
    // 1 m; the shift is a whole number of meters, so each coordinate is
    // rounded to float once more at most.
    const Bounds bounds = BoundsOf(mesh_.positions);
    const std::array<double, 3> center = bounds.center_m();
    std::array<double, 3> shift{};
    for (int axis = 0; axis < 3; ++axis) {
      mesh_.origin[axis] = provisional_origin_[axis] + std::round(center[axis]);
      shift[axis] = provisional_origin_[axis] - mesh_.origin[axis];
    }
    if (shift != std::array<double, 3>{0, 0, 0}) {
      for (size_t i = 0; i < mesh_.positions.size(); i += 3) {
        for (int axis = 0; axis < 3; ++axis) {
          mesh_.positions[i + axis] =
              static_cast<float>(static_cast<double>(mesh_.positions[i + axis]) + shift[axis]);
        }
      }
    }
    return Status::Ok();
  }

  // The scanner of a structured scan without a station: at the origin of the
  // file's frame ("comment origin", else 0 0 0) when its grid says so.
  void DecideGridStation() {
    const GridStationTest::Verdict verdict = grid_->Decide();
    if (verdict.at_origin) {
      stations_ = {origin_};
      station_ids_.assign(mesh_.positions.size() / 3, 0);
    }
    report_.warnings.push_back(verdict.Warning(
        "structured scan (row and column per point) without a station", "scanner"));
  }

  static constexpr uint32_t kDropped = std::numeric_limits<uint32_t>::max();

  const std::string path_;
  const PlyReadOptions& options_;
  const bool keep_faces_;
  BufferedInput in_;  // longest line: 1 MiB
  Format format_ = Format::kAscii;
  bool swap_ = false;
  std::vector<Element> elements_;
  int header_lines_ = 0;
  std::array<double, 3> origin_{};  // from "comment origin"
  bool recenter_ = false;
  bool have_provisional_origin_ = false;
  std::array<double, 3> provisional_origin_{};
  bool has_normals_ = false, has_colors_ = false, has_uvs_ = false, has_tangents_ = false;
  bool has_intensities_ = false, has_stations_ = false;
  std::vector<float> intensities_;
  std::vector<uint16_t> station_ids_;
  std::vector<std::array<double, 3>> stations_;
  std::optional<GridStationTest> grid_;  // row and column per point, no station named
  bool has_face_indices_ = false;
  Scalar color_types_[3] = {Scalar::kUint8, Scalar::kUint8, Scalar::kUint8};
  uint64_t vertex_count_ = 0;
  double values_[kRoleCount] = {};
  std::vector<double> face_;
  std::vector<uint32_t> remap_;  // old vertex index -> kept index, once a point is dropped
  std::string line_;
  size_t token_pos_ = 0;
  uint64_t line_number_ = 0;
  Mesh mesh_;
  PlyReadReport report_;
};

// ---------------------------------------------------------------------------
// Writing.

// Appends through a 1 MiB buffer to a durable write (Env::NewAtomicFile): the
// PLY is streamed, never built whole in memory.
class OutputFile {
 public:
  explicit OutputFile(std::unique_ptr<AtomicFile> file) : file_(std::move(file)) {
    buffer_.reserve(kChunkBytes);
  }

  void Append(const void* data, size_t n) {
    const char* bytes = static_cast<const char*>(data);
    buffer_.insert(buffer_.end(), bytes, bytes + n);
  }
  template <typename T>
  void AppendLittleEndian(T value) {
    uint8_t bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(T));
    Append(bytes, sizeof(T));
  }
  Status MaybeFlush() { return buffer_.size() >= kChunkBytes ? Flush() : Status::Ok(); }
  Status Flush() {
    if (!buffer_.empty()) PB_RETURN_IF_ERROR(file_->Append({buffer_.data(), buffer_.size()}));
    buffer_.clear();
    return Status::Ok();
  }
  Status Commit() {
    PB_RETURN_IF_ERROR(Flush());
    return file_->Commit();
  }

 private:
  static constexpr size_t kChunkBytes = size_t{1} << 20;
  std::unique_ptr<AtomicFile> file_;
  std::vector<char> buffer_;
};

// What the writer needs of a PointCloud or a Mesh, without copying either.
struct PlyArrays {
  std::array<double, 3> origin{};
  std::span<const float> positions, normals;
  std::span<const uint8_t> colors;
  std::span<const float> uvs, tangents;
  std::span<const float> intensities;
  std::span<const uint16_t> station_ids;
  std::span<const std::array<double, 3>> stations;
  std::span<const uint32_t> indices;
  std::span<const PlyVertexScalar> scalars;
  bool has_normals() const { return !normals.empty(); }
  bool has_colors() const { return !colors.empty(); }
  bool has_uvs() const { return !uvs.empty(); }
  bool has_tangents() const { return !tangents.empty(); }
  size_t face_count() const { return indices.size() / 3; }
};

Status WritePly(const std::string& path, const PlyArrays& mesh, bool is_mesh, Env* env) {
  const size_t n = mesh.positions.size() / 3;
  std::string header = "ply\nformat binary_little_endian 1.0\n";
  header += is_mesh ? "comment pointbake mesh " + std::to_string(kPlyMeshVersion) + "\n"
                    : "comment pointbake points " + std::to_string(kPlyPointsVersion) + "\n";
  header += "comment origin " + FormatDouble(mesh.origin[0]) + " " + FormatDouble(mesh.origin[1]) +
            " " + FormatDouble(mesh.origin[2]) + "\n";
  for (size_t s = 0; s < mesh.stations.size(); ++s)
    header += "comment station " + std::to_string(s) + " " + FormatDouble(mesh.stations[s][0]) +
              " " + FormatDouble(mesh.stations[s][1]) + " " + FormatDouble(mesh.stations[s][2]) +
              "\n";
  header += "element vertex " + std::to_string(n) + "\n";
  header += "property float x\nproperty float y\nproperty float z\n";
  if (mesh.has_normals()) header += "property float nx\nproperty float ny\nproperty float nz\n";
  if (mesh.has_colors()) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (mesh.has_uvs()) header += "property float s\nproperty float t\n";
  if (mesh.has_tangents()) {
    header += "property float tx\nproperty float ty\nproperty float tz\nproperty float tw\n";
  }
  if (!mesh.intensities.empty()) header += "property float intensity\n";
  if (!mesh.station_ids.empty()) header += "property ushort station\n";
  for (const PlyVertexScalar& scalar : mesh.scalars) header += "property float " + scalar.name + "\n";
  if (is_mesh) {
    header += "element face " + std::to_string(mesh.face_count()) + "\n";
    header += "property list uchar uint vertex_indices\n";
  }
  header += "end_header\n";

  PB_ASSIGN_OR_RETURN(std::unique_ptr<AtomicFile> file, env->NewAtomicFile(path));
  OutputFile out(std::move(file));
  out.Append(header.data(), header.size());
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) out.AppendLittleEndian(mesh.positions[3 * i + k]);
    if (mesh.has_normals()) {
      for (int k = 0; k < 3; ++k) out.AppendLittleEndian(mesh.normals[3 * i + k]);
    }
    if (mesh.has_colors()) out.Append(&mesh.colors[3 * i], 3);
    if (mesh.has_uvs()) {
      for (int k = 0; k < 2; ++k) out.AppendLittleEndian(mesh.uvs[2 * i + k]);
    }
    if (mesh.has_tangents()) {
      for (int k = 0; k < 4; ++k) out.AppendLittleEndian(mesh.tangents[4 * i + k]);
    }
    if (!mesh.intensities.empty()) out.AppendLittleEndian(mesh.intensities[i]);
    if (!mesh.station_ids.empty()) out.AppendLittleEndian(mesh.station_ids[i]);
    for (const PlyVertexScalar& scalar : mesh.scalars) out.AppendLittleEndian(scalar.values[i]);
    PB_RETURN_IF_ERROR(out.MaybeFlush());
  }
  if (is_mesh) {
    for (size_t t = 0; t < mesh.face_count(); ++t) {
      const uint8_t corners = 3;
      out.Append(&corners, 1);
      for (int k = 0; k < 3; ++k) out.AppendLittleEndian(mesh.indices[3 * t + k]);
      PB_RETURN_IF_ERROR(out.MaybeFlush());
    }
  }
  return out.Commit();
}

}  // namespace

Expected<PlyMesh> ReadPlyMesh(const std::string& path, const PlyReadOptions& options) {
  PlyMesh result;
  PlyParser parser(path, options, /*keep_faces=*/true);
  PB_RETURN_IF_ERROR(parser.Run(&result.mesh, &result.report));
  return result;
}

Expected<PlyPoints> ReadPlyPoints(const std::string& path, const PlyReadOptions& options) {
  Mesh mesh;
  PlyPoints result;
  PlyParser parser(path, options, /*keep_faces=*/false);
  PB_RETURN_IF_ERROR(parser.Run(&mesh, &result.report));
  result.points.origin = mesh.origin;
  result.points.positions = std::move(mesh.positions);
  result.points.normals = std::move(mesh.normals);
  result.points.colors = std::move(mesh.colors);
  result.points.intensities = parser.TakeIntensities();
  result.points.station_ids = parser.TakeStationIds();
  result.points.stations = parser.TakeStations();
  return result;
}

Status WritePlyPoints(const std::string& path, const PointCloud& cloud, Env* env) {
  PB_RETURN_IF_ERROR(Validate(cloud).WithContext("writing " + path));
  PlyArrays arrays;
  arrays.origin = cloud.origin;
  arrays.positions = cloud.positions;
  arrays.normals = cloud.normals;
  arrays.colors = cloud.colors;
  arrays.intensities = cloud.intensities;
  arrays.station_ids = cloud.station_ids;
  arrays.stations = cloud.stations;
  return WritePly(path, arrays, /*is_mesh=*/false, env);
}

Status WritePlyMesh(const std::string& path, const Mesh& mesh, Env* env) {
  return WritePlyMeshWithScalars(path, mesh, {}, env);
}

Status WritePlyMeshWithScalars(const std::string& path, const Mesh& mesh, std::span<const PlyVertexScalar> scalars,
                               Env* env) {
  PB_RETURN_IF_ERROR(Validate(mesh).WithContext("writing " + path));
  std::set<std::string> names = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "s", "t",
                                 "tx", "ty", "tz", "tw", "intensity", "station"};
  for (const PlyVertexScalar& scalar : scalars) {
    const bool identifier = !scalar.name.empty() && std::all_of(scalar.name.begin(), scalar.name.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
    });
    if (!identifier || !names.insert(scalar.name).second)
      return Status::Invalid("writing " + path + ": vertex property name '" + scalar.name +
                             "' is not a new identifier (letters, digits, '_')");
    if (scalar.values.size() != mesh.vertex_count())
      return Status::Invalid("writing " + path + ": vertex property '" + scalar.name + "' has " +
                             std::to_string(scalar.values.size()) + " values for " +
                             std::to_string(mesh.vertex_count()) + " vertices");
  }
  PlyArrays arrays;
  arrays.scalars = scalars;
  arrays.origin = mesh.origin;
  arrays.positions = mesh.positions;
  arrays.normals = mesh.normals;
  arrays.colors = mesh.colors;
  arrays.uvs = mesh.uvs;
  arrays.tangents = mesh.tangents;
  arrays.indices = mesh.indices;
  return WritePly(path, arrays, /*is_mesh=*/true, env);
}

}  // namespace pb
