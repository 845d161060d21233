// Binary glTF 2.0 writer and reader (see gltf.h). Layout per the glTF 2.0
// specification, sections 3.6 (binary data), 3.7 (geometry) and 4.4 (GLB).
#include "stages/geometry/io/gltf.h"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>

#include "stages/geometry/io/ktx2.h"

namespace pb {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the GLB writer copies native floats and integers into the little-endian BIN chunk");

constexpr uint32_t kGlbMagic = 0x46546C67;      // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;     // "JSON"
constexpr uint32_t kChunkBin = 0x004E4942;      // "BIN\0"
constexpr int kFloat = 5126, kUnsignedShort = 5123, kUnsignedInt = 5125, kUnsignedByte = 5121;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

const uint8_t kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};

bool IsPng(const std::vector<uint8_t>& bytes) {
  return bytes.size() >= 8 && std::memcmp(bytes.data(), kPngSignature, 8) == 0;
}

float SrgbToLinear(uint8_t value) {
  const double c = value / 255.0;
  return static_cast<float>(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
}

uint8_t LinearToSrgb(double linear) {
  linear = std::clamp(linear, 0.0, 1.0);
  const double c = linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1 / 2.4) - 0.055;
  return static_cast<uint8_t>(std::lround(c * 255.0));
}

// The BIN chunk under construction, and the JSON that describes it.
class BinBuilder {
 public:
  // Appends a bufferView (4-byte aligned) and returns its index.
  int AddView(const void* data, size_t bytes, int target, int stride = 0) {
    while (bin_.size() % 4) bin_.push_back(0);
    nlohmann::json view = {{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", bytes}};
    if (target) view["target"] = target;
    if (stride) view["byteStride"] = stride;
    const uint8_t* begin = static_cast<const uint8_t*>(data);
    bin_.insert(bin_.end(), begin, begin + bytes);
    views_.push_back(std::move(view));
    return static_cast<int>(views_.size() - 1);
  }
  int AddAccessor(int view, int component_type, size_t count, const char* type,
                  bool normalized = false) {
    nlohmann::json accessor = {
        {"bufferView", view}, {"componentType", component_type}, {"count", count}, {"type", type}};
    if (normalized) accessor["normalized"] = true;
    accessors_.push_back(std::move(accessor));
    return static_cast<int>(accessors_.size() - 1);
  }
  nlohmann::json& accessor(int index) { return accessors_[index]; }
  std::vector<uint8_t>& bin() { return bin_; }
  nlohmann::json& views() { return views_; }
  nlohmann::json& accessors() { return accessors_; }

 private:
  std::vector<uint8_t> bin_;
  nlohmann::json views_ = nlohmann::json::array();
  nlohmann::json accessors_ = nlohmann::json::array();
};

void AppendU32(std::string* out, uint32_t value) {
  out->append(reinterpret_cast<const char*>(&value), 4);
}

// Writes `parts` one after the other as one durable file (env->NewAtomicFile),
// without joining them in memory first.
Status WriteParts(const std::string& path, const std::vector<std::string_view>& parts, Env* env) {
  PB_ASSIGN_OR_RETURN(std::unique_ptr<AtomicFile> file, env->NewAtomicFile(path));
  for (std::string_view part : parts) PB_RETURN_IF_ERROR(file->Append(part));
  return file->Commit();
}

// Normals to write: the mesh's, renormalized; computed where missing or zero.
std::vector<float> UnitNormals(const Mesh& mesh, bool* computed) {
  *computed = !mesh.has_normals();
  std::vector<float> computed_normals;
  if (*computed) return ComputeVertexNormals(mesh);
  std::vector<float> normals(mesh.normals);
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    float* n = &normals[3 * v];
    const double length = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
    if (length > 0 && std::isfinite(length)) {
      for (int k = 0; k < 3; ++k) n[k] = static_cast<float>(n[k] / length);
    } else {
      if (computed_normals.empty()) computed_normals = ComputeVertexNormals(mesh);
      std::copy_n(&computed_normals[3 * v], 3, n);
    }
  }
  return normals;
}

// Tangents to write: the mesh's (xyz renormalized, w = ±1), or computed when
// absent or not all finite and nonzero.
Expected<std::vector<float>> UnitTangents(const Mesh& mesh, GltfWriteReport* report) {
  if (mesh.has_tangents()) {
    std::vector<float> tangents(mesh.tangents);
    bool valid = true;
    for (size_t v = 0; v < mesh.vertex_count() && valid; ++v) {
      float* t = &tangents[4 * v];
      const double length = std::sqrt(double(t[0]) * t[0] + double(t[1]) * t[1] + double(t[2]) * t[2]);
      valid = length > 0 && std::isfinite(length) && std::isfinite(t[3]);
      if (!valid) break;
      for (int k = 0; k < 3; ++k) t[k] = static_cast<float>(t[k] / length);
      t[3] = t[3] < 0 ? -1.0f : 1.0f;
    }
    if (valid) return tangents;
  }
  report->computed_tangents = true;
  return ComputeTangents(mesh, &report->tangents);
}

}  // namespace

Status WriteGlb(const std::string& path, const Mesh& mesh, const GltfWriteOptions& options,
                GltfWriteReport* report, Env* env) {
  GltfWriteReport local;
  GltfWriteReport& out = report ? *report : local;
  out = GltfWriteReport{};
  const std::string context = "writing " + path;
  PB_RETURN_IF_ERROR(Validate(mesh).WithContext(context));
  if (mesh.face_count() == 0) return Status::Invalid(context + ": the mesh has no triangles");
  const bool has_color_texture = !options.base_color_png.empty() || !options.base_color_ktx2.empty();
  const bool has_normal_texture = !options.normal_png.empty() || !options.normal_ktx2.empty();
  if ((!options.base_color_png.empty() && !options.base_color_ktx2.empty()) ||
      (!options.normal_png.empty() && !options.normal_ktx2.empty())) {
    return Status::Invalid(context + ": a map is given both as PNG and as KTX2");
  }
  if ((has_color_texture || has_normal_texture) && !mesh.has_uvs()) {
    return Status::Invalid(context + ": textures need uvs, and the mesh has none (unwrap it first)");
  }
  if (!options.base_color_png.empty() && !IsPng(options.base_color_png)) {
    return Status::Invalid(context + ": the base color texture is not a PNG");
  }
  if (!options.normal_png.empty() && !IsPng(options.normal_png)) {
    return Status::Invalid(context + ": the normal texture is not a PNG");
  }
  if (!options.base_color_ktx2.empty() && !IsKtx2(options.base_color_ktx2)) {
    return Status::Invalid(context + ": the base color texture is not a KTX2 file");
  }
  if (!options.normal_ktx2.empty() && !IsKtx2(options.normal_ktx2)) {
    return Status::Invalid(context + ": the normal texture is not a KTX2 file");
  }
  const size_t n = mesh.vertex_count();
  // Normals are made unit length and tangents computed against the same
  // normals, so the written frame is orthonormal.
  Mesh framed;
  framed.positions = mesh.positions;
  framed.indices = mesh.indices;
  framed.uvs = mesh.uvs;
  framed.tangents = mesh.tangents;
  framed.normals = UnitNormals(mesh, &out.computed_normals);

  BinBuilder bin;
  nlohmann::json attributes;
  {
    const int view = bin.AddView(mesh.positions.data(), mesh.positions.size() * 4, kArrayBuffer);
    const int accessor = bin.AddAccessor(view, kFloat, n, "VEC3");
    std::array<float, 3> lo, hi;
    lo.fill(std::numeric_limits<float>::infinity());
    hi.fill(-std::numeric_limits<float>::infinity());
    for (size_t v = 0; v < n; ++v) {
      for (int k = 0; k < 3; ++k) {
        const float p = mesh.positions[3 * v + k];
        if (!std::isfinite(p)) {
          return Status::Invalid(context + ": vertex " + std::to_string(v) +
                                 " has a non-finite coordinate");
        }
        lo[k] = std::min(lo[k], p);
        hi[k] = std::max(hi[k], p);
      }
    }
    bin.accessor(accessor)["min"] = {double(lo[0]), double(lo[1]), double(lo[2])};
    bin.accessor(accessor)["max"] = {double(hi[0]), double(hi[1]), double(hi[2])};
    attributes["POSITION"] = accessor;
  }
  {
    const int view = bin.AddView(framed.normals.data(), framed.normals.size() * 4, kArrayBuffer);
    attributes["NORMAL"] = bin.AddAccessor(view, kFloat, n, "VEC3");
  }
  if (mesh.has_uvs()) {
    std::vector<float> flipped(mesh.uvs);
    for (size_t v = 0; v < n; ++v) flipped[2 * v + 1] = 1.0f - mesh.uvs[2 * v + 1];
    const int view = bin.AddView(flipped.data(), flipped.size() * 4, kArrayBuffer);
    attributes["TEXCOORD_0"] = bin.AddAccessor(view, kFloat, n, "VEC2");
    PB_ASSIGN_OR_RETURN(std::vector<float> tangents, UnitTangents(framed, &out));
    const int tangent_view = bin.AddView(tangents.data(), tangents.size() * 4, kArrayBuffer);
    attributes["TANGENT"] = bin.AddAccessor(tangent_view, kFloat, n, "VEC4");
    out.wrote_tangents = true;
  }
  if (mesh.has_colors() && options.vertex_colors && !has_color_texture) {
    std::vector<uint16_t> linear(4 * n, 0);  // 3 used + 1 pad: byteStride 8
    float table[256];
    for (int i = 0; i < 256; ++i) table[i] = SrgbToLinear(static_cast<uint8_t>(i));
    for (size_t v = 0; v < n; ++v) {
      for (int k = 0; k < 3; ++k) {
        linear[4 * v + k] = static_cast<uint16_t>(std::lround(table[mesh.colors[3 * v + k]] * 65535.0));
      }
    }
    const int view = bin.AddView(linear.data(), linear.size() * 2, kArrayBuffer, 8);
    attributes["COLOR_0"] = bin.AddAccessor(view, kUnsignedShort, n, "VEC3", true);
    out.wrote_colors = true;
  }
  int indices_accessor;
  if (n <= 65535) {
    std::vector<uint16_t> small(mesh.indices.begin(), mesh.indices.end());
    const int view = bin.AddView(small.data(), small.size() * 2, kElementArrayBuffer);
    indices_accessor = bin.AddAccessor(view, kUnsignedShort, small.size(), "SCALAR");
  } else {
    const int view = bin.AddView(mesh.indices.data(), mesh.indices.size() * 4, kElementArrayBuffer);
    indices_accessor = bin.AddAccessor(view, kUnsignedInt, mesh.indices.size(), "SCALAR");
  }

  nlohmann::json gltf;
  gltf["asset"] = {{"version", "2.0"},
                   {"generator", "pointbake"},
                   {"extras", {{"pointbake_glb_version", kGlbVersion}}}};
  nlohmann::json material = {{"name", options.name},
                             {"pbrMetallicRoughness", {{"metallicFactor", 0}, {"roughnessFactor", 1}}}};
  nlohmann::json images = nlohmann::json::array(), textures = nlohmann::json::array();
  bool basisu = false;
  auto add_texture = [&](const std::vector<uint8_t>& png, const std::vector<uint8_t>& ktx2) {
    if (!ktx2.empty()) {
      const int view = bin.AddView(ktx2.data(), ktx2.size(), 0);
      images.push_back({{"bufferView", view}, {"mimeType", "image/ktx2"}});
      textures.push_back({{"sampler", 0},
                          {"extensions", {{"KHR_texture_basisu", {{"source", images.size() - 1}}}}}});
      basisu = true;
      return static_cast<int>(textures.size() - 1);
    }
    const int view = bin.AddView(png.data(), png.size(), 0);
    images.push_back({{"bufferView", view}, {"mimeType", "image/png"}});
    textures.push_back({{"sampler", 0}, {"source", images.size() - 1}});
    return static_cast<int>(textures.size() - 1);
  };
  if (has_color_texture) {
    material["pbrMetallicRoughness"]["baseColorTexture"] = {
        {"index", add_texture(options.base_color_png, options.base_color_ktx2)}};
  }
  if (has_normal_texture) {
    material["normalTexture"] = {{"index", add_texture(options.normal_png, options.normal_ktx2)}};
  }
  if (basisu) {
    gltf["extensionsUsed"] = {"KHR_texture_basisu"};
    gltf["extensionsRequired"] = {"KHR_texture_basisu"};
  }
  if (!textures.empty()) {
    gltf["images"] = images;
    gltf["textures"] = textures;
    gltf["samplers"] = {{{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", 33071}, {"wrapT", 33071}}};
  }
  gltf["materials"] = {material};
  gltf["meshes"] = {{{"name", options.name},
                     {"primitives",
                      {{{"attributes", attributes},
                        {"indices", indices_accessor},
                        {"material", 0},
                        {"mode", 4}}}}}};
  // The origin sits on the root node, in glTF's y-up axes, and the z-up to
  // y-up rotation on the mesh node below it: engines compose node matrices in
  // float32, and a rotation above a large translation would add its rounding
  // (1e-7 of the origin's size: 0.7 m at 5.4e6 m, seen in Blender) to the
  // placement. The extras keep the z-up origin for readers.
  const std::array<double, 3>& o = mesh.origin;
  nlohmann::json root = {{"name", options.name},
                         {"extras", {{"pointbake_origin", {o[0], o[1], o[2]}}}}};
  if (options.z_up_to_y_up) {
    const double h = std::sqrt(0.5);
    root["translation"] = {o[0], o[2], o[1] == 0 ? 0.0 : -o[1]};
    root["children"] = {1};
    gltf["nodes"] = {root, {{"name", "z_up_to_y_up"}, {"rotation", {-h, 0.0, 0.0, h}}, {"mesh", 0}}};
  } else {
    root["translation"] = {o[0], o[1], o[2]};
    root["mesh"] = 0;
    gltf["nodes"] = {root};
  }
  gltf["scenes"] = {{{"nodes", {0}}}};
  gltf["scene"] = 0;
  while (bin.bin().size() % 4) bin.bin().push_back(0);
  gltf["buffers"] = {{{"byteLength", bin.bin().size()}}};
  gltf["bufferViews"] = bin.views();
  gltf["accessors"] = bin.accessors();

  // Doubles are written with 17 significant digits (nlohmann's round-trip
  // format), so the origin reads back bit for bit.
  std::string json = gltf.dump();
  while (json.size() % 4) json.push_back(' ');
  const uint64_t total = 12 + 8 + json.size() + 8 + bin.bin().size();
  if (total > std::numeric_limits<uint32_t>::max()) {
    return Status::Invalid(context + ": " + std::to_string(total) +
                           " bytes exceed the 4 GiB limit of a .glb");
  }
  std::string header;
  AppendU32(&header, kGlbMagic);
  AppendU32(&header, 2);
  AppendU32(&header, static_cast<uint32_t>(total));
  AppendU32(&header, static_cast<uint32_t>(json.size()));
  AppendU32(&header, kChunkJson);
  std::string bin_header;
  AppendU32(&bin_header, static_cast<uint32_t>(bin.bin().size()));
  AppendU32(&bin_header, kChunkBin);
  const std::string_view bin_view(reinterpret_cast<const char*>(bin.bin().data()), bin.bin().size());
  PB_RETURN_IF_ERROR(WriteParts(path, {header, json, bin_header, bin_view}, env));
  out.bytes = total;
  return Status::Ok();
}

namespace {

// A typed, bounds-checked view of one accessor's elements.
struct AccessorView {
  const uint8_t* data = nullptr;
  size_t count = 0;
  int component_type = 0;
  int components = 0;
  size_t stride = 0;
  bool normalized = false;

  double Get(size_t element, int component) const {
    const uint8_t* p = data + element * stride;
    switch (component_type) {
      case kFloat: {
        float value;
        std::memcpy(&value, p + 4 * component, 4);
        return value;
      }
      case kUnsignedInt: {
        uint32_t value;
        std::memcpy(&value, p + 4 * component, 4);
        return normalized ? value / 4294967295.0 : value;
      }
      case kUnsignedShort: {
        uint16_t value;
        std::memcpy(&value, p + 2 * component, 2);
        return normalized ? value / 65535.0 : value;
      }
      default: {  // kUnsignedByte
        const uint8_t value = p[component];
        return normalized ? value / 255.0 : value;
      }
    }
  }
};

class GlbParser {
 public:
  GlbParser(std::string path) : path_(std::move(path)) {}

  Expected<GlbModel> Run() {
    std::error_code error;
    if (!std::filesystem::exists(path_, error)) return Status::NotFound(path_ + ": no such file");
    FILE* file = std::fopen(path_.c_str(), "rb");
    if (!file) return Status::Errno(path_, "open");
    std::fseek(file, 0, SEEK_END);
    const long size = std::ftell(file);
    std::fseek(file, 0, SEEK_SET);
    bytes_.resize(size > 0 ? size_t(size) : 0);
    const size_t read = std::fread(bytes_.data(), 1, bytes_.size(), file);
    std::fclose(file);
    if (read != bytes_.size()) return Status::Errno(path_, "read");
    try {
      return Parse();
    } catch (const nlohmann::json::exception& e) {
      return Corrupt(std::string("unexpected JSON structure: ") + e.what());
    }
  }

 private:
  Status Corrupt(const std::string& what) const { return Status::Corrupt(path_ + ": " + what); }

  uint32_t U32(size_t offset) const {
    uint32_t value;
    std::memcpy(&value, bytes_.data() + offset, 4);
    return value;
  }

  Expected<GlbModel> Parse() {
    if (bytes_.size() < 20 || U32(0) != kGlbMagic) return Corrupt("not a binary glTF file (no 'glTF' magic)");
    if (U32(4) != 2) return Corrupt("glTF container version " + std::to_string(U32(4)) + ", expected 2");
    if (U32(8) != bytes_.size()) {
      return Corrupt("header says " + std::to_string(U32(8)) + " bytes, the file has " +
                     std::to_string(bytes_.size()));
    }
    const uint32_t json_length = U32(12);
    if (U32(16) != kChunkJson || 20 + uint64_t(json_length) > bytes_.size()) {
      return Corrupt("the first chunk is not a JSON chunk within the file");
    }
    const size_t bin_header = 20 + json_length;
    if (bin_header + 8 <= bytes_.size()) {
      const uint32_t bin_length = U32(bin_header);
      if (U32(bin_header + 4) != kChunkBin || bin_header + 8 + uint64_t(bin_length) > bytes_.size()) {
        return Corrupt("the second chunk is not a BIN chunk within the file");
      }
      bin_ = bytes_.data() + bin_header + 8;
      bin_size_ = bin_length;
    }
    gltf_ = nlohmann::json::parse(bytes_.begin() + 20, bytes_.begin() + bin_header, nullptr, false);
    if (gltf_.is_discarded() || !gltf_.is_object()) return Corrupt("the JSON chunk does not parse");
    if (gltf_.value("/asset/version"_json_pointer, std::string()) != "2.0") {
      return Corrupt("asset.version is not \"2.0\"");
    }
    GlbModel model;
    model.generator = gltf_.value("/asset/generator"_json_pointer, std::string());

    const nlohmann::json& meshes = gltf_.value("meshes", nlohmann::json::array());
    // at() throughout: a missing key must throw (caught above), never reach
    // the const operator[]'s undefined behaviour.
    if (!meshes.is_array() || meshes.size() != 1 || meshes.at(0).at("primitives").size() != 1) {
      return Corrupt("expected one mesh with one primitive (the subset pointbake writes)");
    }
    const nlohmann::json& primitive = meshes.at(0).at("primitives").at(0);
    if (primitive.value("mode", 4) != 4) return Corrupt("the primitive is not a triangle list");
    // The origin: the scene root's extras (what WriteGlb writes), else the
    // translation of the node holding the mesh.
    const nlohmann::json& nodes = gltf_.value("nodes", nlohmann::json::array());
    bool have_origin = false;
    if (!nodes.empty()) {
      model.name = nodes[0].value("name", std::string());
      const nlohmann::json* origin = nodes[0].contains("extras") ? &nodes[0].at("extras") : nullptr;
      if (origin && origin->contains("pointbake_origin")) {
        for (int k = 0; k < 3; ++k) model.mesh.origin[k] = (*origin)["pointbake_origin"].at(k).get<double>();
        have_origin = true;
      }
    }
    for (const nlohmann::json& node : nodes) {
      if (!have_origin && node.contains("mesh") && node["mesh"] == 0 && node.contains("translation")) {
        for (int k = 0; k < 3; ++k) model.mesh.origin[k] = node["translation"].at(k).get<double>();
      }
    }
    Mesh& mesh = model.mesh;
    const nlohmann::json& attributes = primitive.at("attributes");
    PB_ASSIGN_OR_RETURN(AccessorView positions, Accessor(attributes.at("POSITION"), {kFloat}, 3));
    const size_t n = positions.count;
    mesh.positions.resize(3 * n);
    for (size_t v = 0; v < n; ++v) {
      for (int k = 0; k < 3; ++k) mesh.positions[3 * v + k] = static_cast<float>(positions.Get(v, k));
    }
    if (attributes.contains("NORMAL")) {
      PB_ASSIGN_OR_RETURN(AccessorView view, Accessor(attributes["NORMAL"], {kFloat}, 3, n));
      mesh.normals.resize(3 * n);
      for (size_t v = 0; v < n; ++v) {
        for (int k = 0; k < 3; ++k) mesh.normals[3 * v + k] = static_cast<float>(view.Get(v, k));
      }
    }
    if (attributes.contains("TEXCOORD_0")) {
      PB_ASSIGN_OR_RETURN(AccessorView view, Accessor(attributes["TEXCOORD_0"], {kFloat}, 2, n));
      mesh.uvs.resize(2 * n);
      for (size_t v = 0; v < n; ++v) {
        mesh.uvs[2 * v] = static_cast<float>(view.Get(v, 0));
        mesh.uvs[2 * v + 1] = 1.0f - static_cast<float>(view.Get(v, 1));
      }
    }
    if (attributes.contains("TANGENT")) {
      PB_ASSIGN_OR_RETURN(AccessorView view, Accessor(attributes["TANGENT"], {kFloat}, 4, n));
      mesh.tangents.resize(4 * n);
      for (size_t v = 0; v < n; ++v) {
        for (int k = 0; k < 4; ++k) mesh.tangents[4 * v + k] = static_cast<float>(view.Get(v, k));
      }
    }
    if (attributes.contains("COLOR_0")) {
      PB_ASSIGN_OR_RETURN(AccessorView view, Accessor(attributes["COLOR_0"],
                                                      {kFloat, kUnsignedShort, kUnsignedByte}, 0, n));
      if (view.components != 3 && view.components != 4) return Corrupt("COLOR_0 is not VEC3 or VEC4");
      mesh.colors.resize(3 * n);
      for (size_t v = 0; v < n; ++v) {
        for (int k = 0; k < 3; ++k) mesh.colors[3 * v + k] = LinearToSrgb(view.Get(v, k));
      }
    }
    PB_ASSIGN_OR_RETURN(AccessorView indices, Accessor(primitive.at("indices"),
                                                       {kUnsignedByte, kUnsignedShort, kUnsignedInt}, 1));
    if (indices.count % 3 != 0) return Corrupt(std::to_string(indices.count) + " indices, not a multiple of 3");
    mesh.indices.resize(indices.count);
    for (size_t i = 0; i < indices.count; ++i) {
      const double index = indices.Get(i, 0);
      if (index >= double(n)) {
        return Corrupt("index " + std::to_string(i) + " names vertex " +
                       std::to_string(uint64_t(index)) + " of " + std::to_string(n));
      }
      mesh.indices[i] = static_cast<uint32_t>(index);
    }
    if (primitive.contains("material")) {
      const nlohmann::json& material = gltf_.at("materials").at(primitive["material"].get<size_t>());
      if (material.contains("pbrMetallicRoughness") &&
          material["pbrMetallicRoughness"].contains("baseColorTexture")) {
        PB_RETURN_IF_ERROR(Texture(material["pbrMetallicRoughness"]["baseColorTexture"],
                                   &model.base_color_png, &model.base_color_ktx2));
      }
      if (material.contains("normalTexture")) {
        PB_RETURN_IF_ERROR(Texture(material["normalTexture"], &model.normal_png, &model.normal_ktx2));
      }
    }
    return model;
  }

  // The bytes [offset, offset + length) of buffer view `index`, checked.
  Expected<std::pair<const uint8_t*, const nlohmann::json*>> View(size_t index, size_t* length) {
    const nlohmann::json& views = gltf_.at("bufferViews");
    if (index >= views.size()) return Corrupt("bufferView " + std::to_string(index) + " does not exist");
    const nlohmann::json& view = views[index];
    if (view.value("buffer", 0) != 0 || !bin_) return Corrupt("bufferView " + std::to_string(index) +
                                                               " is not in the BIN chunk");
    const uint64_t offset = view.value("byteOffset", uint64_t{0});
    *length = view.at("byteLength").get<size_t>();
    if (offset > bin_size_ || *length > bin_size_ - offset) {  // no wrap-around
      return Corrupt("bufferView " + std::to_string(index) + " ends past the BIN chunk");
    }
    return std::make_pair(bin_ + offset, &view);
  }

  // Accessor `ref` with one of `types` and `components` components (0: any),
  // and `count` elements (0: any).
  Expected<AccessorView> Accessor(const nlohmann::json& ref, std::initializer_list<int> types,
                                  int components, size_t count = 0) {
    const size_t index = ref.get<size_t>();
    const nlohmann::json& accessors = gltf_.at("accessors");
    if (index >= accessors.size()) return Corrupt("accessor " + std::to_string(index) + " does not exist");
    const nlohmann::json& a = accessors[index];
    const std::string name = "accessor " + std::to_string(index);
    AccessorView out;
    out.component_type = a.at("componentType").get<int>();
    out.count = a.at("count").get<size_t>();
    out.normalized = a.value("normalized", false);
    const std::string type = a.at("type").get<std::string>();
    out.components = type == "SCALAR" ? 1 : type == "VEC2" ? 2 : type == "VEC3" ? 3 : type == "VEC4" ? 4 : 0;
    if (out.components == 0) return Corrupt(name + ": unsupported type " + type);
    if (std::find(types.begin(), types.end(), out.component_type) == types.end()) {
      return Corrupt(name + ": unexpected componentType " + std::to_string(out.component_type));
    }
    if (components && out.components != components) {
      return Corrupt(name + ": " + type + ", expected " + std::to_string(components) + " components");
    }
    if (count && out.count != count) {
      return Corrupt(name + ": " + std::to_string(out.count) + " elements, expected " +
                     std::to_string(count));
    }
    if (!a.contains("bufferView")) return Corrupt(name + ": no bufferView (sparse accessors are not read)");
    size_t length = 0;
    PB_ASSIGN_OR_RETURN(auto view, View(a["bufferView"].get<size_t>(), &length));
    const size_t component_bytes = out.component_type == kUnsignedByte ? 1
                                   : out.component_type == kUnsignedShort ? 2 : 4;
    const size_t element_bytes = component_bytes * size_t(out.components);
    out.stride = view.second->value("byteStride", element_bytes);
    const size_t offset = a.value("byteOffset", size_t{0});
    // Written to not overflow on hostile sizes: the last element must end
    // within the view.
    if (out.stride < element_bytes || offset > length || element_bytes > length - offset ||
        (out.count > 0 && out.count - 1 > (length - offset - element_bytes) / out.stride)) {
      return Corrupt(name + ": its elements run past its bufferView");
    }
    out.data = view.first + offset;
    return out;
  }

  // The image of a texture: its KHR_texture_basisu source into `ktx2` when
  // it has one, else its source into `png`.
  Status Texture(const nlohmann::json& texture_ref, std::vector<uint8_t>* png, std::vector<uint8_t>* ktx2) {
    const nlohmann::json& texture = gltf_.at("textures").at(texture_ref.at("index").get<size_t>());
    const bool basisu = texture.contains("extensions") && texture["extensions"].contains("KHR_texture_basisu");
    const size_t source = basisu ? texture["extensions"]["KHR_texture_basisu"].at("source").get<size_t>()
                                 : texture.at("source").get<size_t>();
    const nlohmann::json& image = gltf_.at("images").at(source);
    if (!image.contains("bufferView")) return Corrupt("an image is not embedded in a bufferView");
    size_t length = 0;
    PB_ASSIGN_OR_RETURN(auto view, View(image["bufferView"].get<size_t>(), &length));
    (basisu ? ktx2 : png)->assign(view.first, view.first + length);
    return Status::Ok();
  }

  std::string path_;
  std::vector<uint8_t> bytes_;
  const uint8_t* bin_ = nullptr;
  size_t bin_size_ = 0;
  nlohmann::json gltf_;
};

}  // namespace

Expected<GlbModel> ReadGlb(const std::string& path) { return GlbParser(path).Run(); }

}  // namespace pb
