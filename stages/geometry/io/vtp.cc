// VTK XML PolyData writer (vtp.h). Layout from the VTK file-format
// description (VTK User's Guide 11th ed., 19.3 "XML File Formats"):
// appended raw data, each array's block a UInt64 byte count then the values;
// `offset` counts from the byte after the '_'.
#include "stages/geometry/io/vtp.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <functional>
#include <memory>
#include <set>
#include <string_view>

#include "base/markup.h"

namespace pb {
namespace {

// A numeric array of the appended block.
struct Block {
  std::string element;  // the XML line, without offset
  uint64_t bytes = 0;   // values only, without the count
  std::function<void(std::string&, size_t first, size_t count)>
      append;             // values [first, first+count) of `units`
  size_t units = 0;       // what `append` counts: vertices or faces
  size_t unit_bytes = 0;  // bytes per unit
};

template <typename T>
void AppendLittleEndian(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(T));
  out.append(bytes, sizeof(T));
}

template <typename T>
void AppendValues(std::string& out, std::span<const T> values) {
  if constexpr (std::endian::native == std::endian::little) {
    out.append(reinterpret_cast<const char*>(values.data()), values.size_bytes());
  } else {
    for (T v : values) AppendLittleEndian(out, v);
  }
}

std::string DataArrayLine(std::string_view type, std::string_view name, int components) {
  return "<DataArray type=\"" + std::string(type) + "\" Name=\"" + EscapeMarkup(name) +
         "\" NumberOfComponents=\"" + std::to_string(components) + "\" format=\"appended\"";
}

// The character codes of `value`, 0-ended: how VTK writes a String array in
// ascii format.
std::string StringFieldLine(const VtpStringField& field) {
  std::string line = "      <Array type=\"String\" Name=\"" + EscapeMarkup(field.name) +
                     "\" NumberOfTuples=\"1\" format=\"ascii\">\n        ";
  for (unsigned char c : field.value) line += std::to_string(int(c)) + " ";
  return line + "0\n      </Array>\n";
}

Status CheckArrays(const Mesh& mesh, const VtpWriteOptions& options) {
  std::set<std::string> names;
  if (mesh.has_normals()) names.insert("Normals");
  if (mesh.has_uvs()) names.insert("TCoords");
  if (mesh.has_colors()) names.insert("Colors");
  if (mesh.has_tangents()) names.insert("Tangents");
  const size_t n = mesh.vertex_count();
  for (const VtpPointArray& a : options.point_arrays) {
    if (a.name.empty()) return Status::Invalid("a point array has no name");
    if (!names.insert(a.name).second)
      return Status::Invalid("two point arrays are named '" + a.name + "'");
    if (a.components < 1)
      return Status::Invalid("point array '" + a.name + "': components must be >= 1");
    if (a.float32.empty() == a.uint8.empty() && n > 0)
      return Status::Invalid("point array '" + a.name + "': set exactly one of float32 and uint8");
    const size_t size = a.float32.empty() ? a.uint8.size() : a.float32.size();
    if (size != size_t(a.components) * n)
      return Status::Invalid("point array '" + a.name + "': " + std::to_string(size) +
                             " values for " + std::to_string(n) + " vertices x " +
                             std::to_string(a.components) + " components");
  }
  if (!options.active_scalars.empty() && names.count(options.active_scalars) == 0)
    return Status::Invalid("active_scalars '" + options.active_scalars + "' names no point array");
  for (const VtpStringField& f : options.field_data) {
    if (f.name.empty()) return Status::Invalid("a field data string has no name");
  }
  return Status::Ok();
}

// A point array of `components` values of T per vertex.
template <typename T>
Block PointBlock(std::string_view type, std::string_view name, int components,
                 std::span<const T> values) {
  Block block;
  block.element = DataArrayLine(type, name, components);
  block.units = values.size() / size_t(components);
  block.unit_bytes = sizeof(T) * size_t(components);
  block.bytes = values.size_bytes();
  block.append = [values, components](std::string& out, size_t first, size_t count) {
    AppendValues(out, values.subspan(first * size_t(components), count * size_t(components)));
  };
  return block;
}

}  // namespace

Status WriteVtp(const std::string& path, const Mesh& mesh, const VtpWriteOptions& options,
                uint64_t* bytes, Env* env) {
  PB_RETURN_IF_ERROR(Validate(mesh).WithContext("writing " + path));
  if (Status s = CheckArrays(mesh, options); !s.ok()) return s.WithContext("writing " + path);
  const size_t n = mesh.vertex_count(), faces = mesh.face_count();

  std::vector<Block> point_data;
  if (mesh.has_normals())
    point_data.push_back(PointBlock<float>("Float32", "Normals", 3, mesh.normals));
  if (mesh.has_uvs()) point_data.push_back(PointBlock<float>("Float32", "TCoords", 2, mesh.uvs));
  if (mesh.has_colors())
    point_data.push_back(PointBlock<uint8_t>("UInt8", "Colors", 3, mesh.colors));
  if (mesh.has_tangents())
    point_data.push_back(PointBlock<float>("Float32", "Tangents", 4, mesh.tangents));
  for (const VtpPointArray& a : options.point_arrays) {
    point_data.push_back(a.float32.empty()
                             ? PointBlock<uint8_t>("UInt8", a.name, a.components, a.uint8)
                             : PointBlock<float>("Float32", a.name, a.components, a.float32));
  }
  Block points;
  points.element = DataArrayLine("Float64", "Points", 3);
  points.units = n;
  points.unit_bytes = 3 * sizeof(double);
  points.bytes = uint64_t{n} * points.unit_bytes;
  points.append = [&mesh](std::string& out, size_t first, size_t count) {
    for (size_t i = first * 3; i < (first + count) * 3; ++i)
      AppendLittleEndian(out, mesh.origin[i % 3] + double(mesh.positions[i]));
  };
  Block connectivity;
  connectivity.element = DataArrayLine("Int64", "connectivity", 1);
  connectivity.units = faces;
  connectivity.unit_bytes = 3 * sizeof(int64_t);
  connectivity.bytes = uint64_t{faces} * connectivity.unit_bytes;
  connectivity.append = [&mesh](std::string& out, size_t first, size_t count) {
    for (size_t i = first * 3; i < (first + count) * 3; ++i)
      AppendLittleEndian(out, int64_t{mesh.indices[i]});
  };
  Block offsets;
  offsets.element = DataArrayLine("Int64", "offsets", 1);
  offsets.units = faces;
  offsets.unit_bytes = sizeof(int64_t);
  offsets.bytes = uint64_t{faces} * offsets.unit_bytes;
  offsets.append = [](std::string& out, size_t first, size_t count) {
    for (size_t f = first; f < first + count; ++f) AppendLittleEndian(out, int64_t(3 * (f + 1)));
  };

  // The XML part, with every block's offset.
  uint64_t offset = 0;
  const auto element = [&offset](const Block& block, const char* indent) {
    std::string line = indent + block.element + " offset=\"" + std::to_string(offset) + "\"/>\n";
    offset += sizeof(uint64_t) + block.bytes;
    return line;
  };
  std::string xml = "<?xml version=\"1.0\"?>\n<!-- pointbake vtp " + std::to_string(kVtpVersion) +
                    " -->\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
                    "header_type=\"UInt64\">\n  <PolyData>\n";
  if (!options.field_data.empty()) {
    xml += "    <FieldData>\n";
    for (const VtpStringField& f : options.field_data) xml += StringFieldLine(f);
    xml += "    </FieldData>\n";
  }
  xml += "    <Piece NumberOfPoints=\"" + std::to_string(n) +
         "\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"" +
         std::to_string(faces) + "\">\n      <PointData";
  if (!options.active_scalars.empty())
    xml += " Scalars=\"" + EscapeMarkup(options.active_scalars) + "\"";
  if (mesh.has_normals()) xml += " Normals=\"Normals\"";
  if (mesh.has_uvs()) xml += " TCoords=\"TCoords\"";
  xml += ">\n";
  for (const Block& b : point_data) xml += element(b, "        ");
  xml += "      </PointData>\n      <Points>\n";
  xml += element(points, "        ");
  xml += "      </Points>\n      <Polys>\n";
  xml += element(connectivity, "        ");
  xml += element(offsets, "        ");
  xml += "      </Polys>\n    </Piece>\n  </PolyData>\n  <AppendedData encoding=\"raw\">\n   _";

  // Companions first, synced but not renamed until the .vtp is complete.
  std::vector<std::unique_ptr<AtomicFile>> companions;
  for (const VtpCompanionFile& c : options.companions) {
    PB_ASSIGN_OR_RETURN(std::unique_ptr<AtomicFile> file, env->NewAtomicFile(c.path));
    PB_RETURN_IF_ERROR(
        file->Append({reinterpret_cast<const char*>(c.bytes.data()), c.bytes.size()}));
    PB_RETURN_IF_ERROR(file->Sync());
    companions.push_back(std::move(file));
  }
  PB_ASSIGN_OR_RETURN(std::unique_ptr<AtomicFile> file, env->NewAtomicFile(path));
  constexpr size_t kChunkBytes = size_t{1} << 20;
  std::string buffer = std::move(xml);
  uint64_t written = 0;
  const auto flush = [&](bool always) -> Status {
    if (buffer.empty() || (!always && buffer.size() < kChunkBytes)) return Status::Ok();
    PB_RETURN_IF_ERROR(file->Append(buffer));
    written += buffer.size();
    buffer.clear();
    return Status::Ok();
  };
  std::vector<const Block*> order;
  for (const Block& b : point_data) order.push_back(&b);
  order.insert(order.end(), {&points, &connectivity, &offsets});
  for (const Block* b : order) {
    AppendLittleEndian(buffer, b->bytes);
    const size_t per_chunk = std::max<size_t>(1, kChunkBytes / std::max<size_t>(1, b->unit_bytes));
    for (size_t first = 0; first < b->units; first += per_chunk) {
      b->append(buffer, first, std::min(per_chunk, b->units - first));
      PB_RETURN_IF_ERROR(flush(false));
    }
  }
  buffer += "\n  </AppendedData>\n</VTKFile>\n";
  PB_RETURN_IF_ERROR(flush(true));
  PB_RETURN_IF_ERROR(file->Sync());
  for (std::unique_ptr<AtomicFile>& c : companions) PB_RETURN_IF_ERROR(c->Commit());
  PB_RETURN_IF_ERROR(file->Commit());
  if (bytes) *bytes = written;
  return Status::Ok();
}

}  // namespace pb
