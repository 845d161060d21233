#include "stages/geometry/io/gltf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "stages/geometry/core/image.h"
#include "stages/geometry/testing/test_data.h"
#include "base/testing/durable_write_check.h"

namespace pb {
namespace {

// An nx x ny grid over [0, 2] x [0, 1] in z = bump * sin(pi x / 2), uvs
// (x / 2, y), colors, far from the origin as scans are.
Mesh Grid(int nx, int ny, double bump = 0) {
  Mesh mesh;
  mesh.origin = {456789.125, 5432109.5, 312.75};
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      const double x = 2.0 * i / nx, y = double(j) / ny;
      mesh.positions.insert(mesh.positions.end(),
                            {float(x), float(y), float(bump * std::sin(M_PI * x / 2))});
      mesh.uvs.insert(mesh.uvs.end(), {float(x / 2), float(y)});
      mesh.colors.insert(mesh.colors.end(), {uint8_t(i * 255 / nx), uint8_t(j * 255 / ny), 7});
    }
  }
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const uint32_t a = j * (nx + 1) + i, b = a + 1, c = a + nx + 2, d = a + nx + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
    }
  }
  return mesh;
}

std::vector<uint8_t> Png(int width, int height, bool normal_map) {
  Image image = Image::Make(width, height, 3, Image::PixelType::kU8);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image.at_u8(x, y, 0) = normal_map ? 128 : uint8_t(x * 255 / width);
      image.at_u8(x, y, 1) = normal_map ? uint8_t(128 + (y % 8)) : uint8_t(y * 255 / height);
      image.at_u8(x, y, 2) = normal_map ? 255 : 90;
    }
  }
  auto png = EncodePng(image);
  EXPECT_TRUE(png.ok());
  return *png;
}

// The JSON chunk of a .glb, and its total size.
nlohmann::json JsonChunk(const std::string& path, size_t* size = nullptr) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (size) *size = bytes.size();
  uint32_t json_length;
  std::memcpy(&json_length, bytes.data() + 12, 4);
  return nlohmann::json::parse(bytes.substr(20, json_length));
}

class GltfTest : public testing::TempDirTest {};

TEST_F(GltfTest, TexturedMeshRoundTrips) {
  Mesh mesh = Grid(8, 4, 0.3);
  mesh.colors.clear();
  GltfWriteOptions options;
  options.name = "wall";
  options.base_color_png = Png(64, 32, false);
  options.normal_png = Png(32, 32, true);
  GltfWriteReport report;
  const std::string path = Path("model.glb");
  ASSERT_TRUE(WriteGlb(path, mesh, options, &report).ok());
  EXPECT_TRUE(report.computed_normals);
  EXPECT_TRUE(report.computed_tangents);
  EXPECT_TRUE(report.wrote_tangents);
  EXPECT_FALSE(report.wrote_colors);
  EXPECT_EQ(report.bytes, std::filesystem::file_size(path));
  EXPECT_EQ(report.bytes % 4, 0u);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));

  auto model = ReadGlb(path);
  ASSERT_TRUE(model.ok()) << model.status().message();
  EXPECT_EQ(model->generator, "pointbake");
  EXPECT_EQ(model->name, "wall");
  const Mesh& back = model->mesh;
  EXPECT_EQ(back.origin, mesh.origin);  // bit for bit through the JSON
  EXPECT_EQ(back.positions, mesh.positions);
  EXPECT_EQ(back.indices, mesh.indices);
  ASSERT_EQ(back.uvs.size(), mesh.uvs.size());
  for (size_t i = 0; i < mesh.uvs.size(); ++i) EXPECT_NEAR(back.uvs[i], mesh.uvs[i], 1e-7);
  const std::vector<float> normals = ComputeVertexNormals(mesh);
  ASSERT_EQ(back.normals.size(), normals.size());
  for (size_t i = 0; i < normals.size(); ++i) EXPECT_NEAR(back.normals[i], normals[i], 1e-7);
  Mesh with_normals = mesh;
  with_normals.normals = normals;
  auto tangents = ComputeTangents(with_normals);
  ASSERT_TRUE(tangents.ok());
  EXPECT_EQ(back.tangents, *tangents);
  EXPECT_TRUE(back.colors.empty());
  EXPECT_EQ(model->base_color_png, options.base_color_png);
  EXPECT_EQ(model->normal_png, options.normal_png);
}

TEST_F(GltfTest, LayoutFollowsTheSpec) {
  GltfWriteOptions options;
  options.base_color_png = Png(16, 16, false);
  options.normal_png = Png(16, 16, true);
  const Mesh mesh = Grid(2, 1);
  ASSERT_TRUE(WriteGlb(Path("m.glb"), mesh, options).ok());
  const nlohmann::json gltf = JsonChunk(Path("m.glb"));
  EXPECT_EQ(gltf["asset"]["version"], "2.0");
  EXPECT_EQ(gltf["asset"]["generator"], "pointbake");
  for (const auto& view : gltf["bufferViews"]) EXPECT_EQ(view["byteOffset"].get<size_t>() % 4, 0u);
  const auto& material = gltf["materials"][0];
  EXPECT_EQ(material["pbrMetallicRoughness"]["metallicFactor"], 0);
  EXPECT_EQ(material["pbrMetallicRoughness"]["roughnessFactor"], 1);
  EXPECT_EQ(material["pbrMetallicRoughness"]["baseColorTexture"]["index"], 0);
  EXPECT_EQ(material["normalTexture"]["index"], 1);
  for (const auto& image : gltf["images"]) EXPECT_EQ(image["mimeType"], "image/png");
  // The root carries the origin in y-up axes, the mesh node the rotation.
  EXPECT_EQ(gltf["nodes"][0]["children"][0], 1);
  EXPECT_EQ(gltf["nodes"][0]["translation"],
            nlohmann::json({mesh.origin[0], mesh.origin[2], -mesh.origin[1]}));
  EXPECT_EQ(gltf["nodes"][0]["extras"]["pointbake_origin"],
            nlohmann::json({mesh.origin[0], mesh.origin[1], mesh.origin[2]}));
  EXPECT_NEAR(gltf["nodes"][1]["rotation"][0].get<double>(), -std::sqrt(0.5), 1e-15);
  EXPECT_EQ(gltf["nodes"][1]["mesh"], 0);
  // Without the rotation: one node, translation = origin; read back the same.
  GltfWriteOptions z_up;
  z_up.z_up_to_y_up = false;
  ASSERT_TRUE(WriteGlb(Path("z.glb"), mesh, z_up).ok());
  const nlohmann::json plain = JsonChunk(Path("z.glb"));
  ASSERT_EQ(plain["nodes"].size(), 1u);
  EXPECT_EQ(plain["nodes"][0]["translation"], nlohmann::json({mesh.origin[0], mesh.origin[1], mesh.origin[2]}));
  EXPECT_EQ(ReadGlb(Path("z.glb"))->mesh.origin, mesh.origin);
  const auto& attributes = gltf["meshes"][0]["primitives"][0]["attributes"];
  const auto& position = gltf["accessors"][attributes["POSITION"].get<int>()];
  EXPECT_EQ(position["min"], nlohmann::json({0.0, 0.0, 0.0}));
  EXPECT_EQ(position["max"], nlohmann::json({2.0, 1.0, 0.0}));
  EXPECT_FALSE(attributes.contains("COLOR_0"));  // the base color texture has the colors
  const auto& indices = gltf["accessors"][gltf["meshes"][0]["primitives"][0]["indices"].get<int>()];
  EXPECT_EQ(indices["componentType"], 5123);  // uint16 for few vertices
}

TEST_F(GltfTest, TangentFrameRendersTheNormalMapAsBakedInOurConvention) {
  // Non-mirrored layout: v (ours) grows along +y. In the file, v' = 1 - v, so
  // the image's top row (v' = 0) is at y = 1: "up" in the normal map is +y.
  // A glTF renderer's bitangent w * cross(n, t) must point there too.
  const Mesh mesh = Grid(2, 1);
  ASSERT_TRUE(WriteGlb(Path("m.glb"), mesh, GltfWriteOptions{}).ok());
  auto model = ReadGlb(Path("m.glb"));
  ASSERT_TRUE(model.ok());
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    const float* t = &model->mesh.tangents[4 * v];
    EXPECT_NEAR(t[0], 1, 1e-6);  // +u is +x
    EXPECT_EQ(t[3], 1.0f);       // cross(+z, +x) = +y: image up
  }
  // Mirror u: the tangent turns to -x and w to -1, so the bitangent stays +y.
  Mesh mirrored = mesh;
  for (size_t v = 0; v < mesh.vertex_count(); ++v) mirrored.uvs[2 * v] = 1 - mesh.uvs[2 * v];
  ASSERT_TRUE(WriteGlb(Path("mirrored.glb"), mirrored, GltfWriteOptions{}).ok());
  model = ReadGlb(Path("mirrored.glb"));
  ASSERT_TRUE(model.ok());
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    EXPECT_NEAR(model->mesh.tangents[4 * v], -1, 1e-6);
    EXPECT_EQ(model->mesh.tangents[4 * v + 3], -1.0f);
  }
}

TEST_F(GltfTest, VertexColorsWithoutTextureAndLargeMeshesUseUint32) {
  const Mesh mesh = Grid(300, 220);  // 66521 vertices > 65535
  GltfWriteReport report;
  ASSERT_TRUE(WriteGlb(Path("c.glb"), mesh, GltfWriteOptions{}, &report).ok());
  EXPECT_TRUE(report.wrote_colors);
  const nlohmann::json gltf = JsonChunk(Path("c.glb"));
  const auto& primitive = gltf["meshes"][0]["primitives"][0];
  EXPECT_EQ(gltf["accessors"][primitive["indices"].get<int>()]["componentType"], 5125);
  EXPECT_FALSE(gltf.contains("images"));
  auto model = ReadGlb(Path("c.glb"));
  ASSERT_TRUE(model.ok()) << model.status().message();
  EXPECT_EQ(model->mesh.colors, mesh.colors);  // sRGB -> linear u16 -> sRGB is exact
  EXPECT_EQ(model->mesh.indices, mesh.indices);

  GltfWriteOptions no_colors;
  no_colors.vertex_colors = false;
  ASSERT_TRUE(WriteGlb(Path("n.glb"), mesh, no_colors, &report).ok());
  EXPECT_FALSE(report.wrote_colors);
  EXPECT_TRUE(ReadGlb(Path("n.glb"))->mesh.colors.empty());
}

TEST_F(GltfTest, GivenTangentsAndNormalsAreKept) {
  Mesh mesh = Grid(2, 2);
  mesh.normals.assign(3 * mesh.vertex_count(), 0.0f);
  mesh.tangents.assign(4 * mesh.vertex_count(), 0.0f);
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    mesh.normals[3 * v + 2] = 2.0f;  // not unit: renormalized
    mesh.tangents[4 * v + 1] = 1.0f;  // unusual but valid: +y
    mesh.tangents[4 * v + 3] = -1.0f;
  }
  GltfWriteReport report;
  ASSERT_TRUE(WriteGlb(Path("t.glb"), mesh, GltfWriteOptions{}, &report).ok());
  EXPECT_FALSE(report.computed_normals);
  EXPECT_FALSE(report.computed_tangents);
  auto model = ReadGlb(Path("t.glb"));
  ASSERT_TRUE(model.ok());
  EXPECT_EQ(model->mesh.tangents, mesh.tangents);
  EXPECT_EQ(model->mesh.normals[2], 1.0f);
}

TEST_F(GltfTest, TextureWithoutUvsIsAnError) {
  Mesh mesh = Grid(2, 1);
  mesh.uvs.clear();
  GltfWriteOptions options;
  options.base_color_png = Png(4, 4, false);
  const Status status = WriteGlb(Path("m.glb"), mesh, options);
  EXPECT_EQ(status.code(), Status::Code::kInvalid);
  EXPECT_NE(status.message().find("uvs"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find(Path("m.glb")), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(Path("m.glb")));
  options.base_color_png = {1, 2, 3};
  EXPECT_EQ(WriteGlb(Path("m.glb"), Grid(2, 1), options).code(), Status::Code::kInvalid);
  EXPECT_EQ(WriteGlb(Path("m.glb"), Mesh{}, GltfWriteOptions{}).code(), Status::Code::kInvalid);
}

TEST_F(GltfTest, UnwritableFolderNamesThePathAndLeavesNoFile) {
  const std::string path = Path("missing/model.glb");
  const Status status = WriteGlb(path, Grid(2, 1), GltfWriteOptions{});
  EXPECT_EQ(status.code(), Status::Code::kIo);
  EXPECT_NE(status.message().find(path), std::string::npos) << status.message();
  EXPECT_TRUE(std::filesystem::is_empty(dir_));
}

TEST_F(GltfTest, FailedWritesKeepTheEarlierFile) {
  ASSERT_TRUE(WriteGlb(Path("model.glb"), Grid(2, 1), GltfWriteOptions{}).ok());
  GltfWriteOptions textured;
  textured.base_color_png = Png(8, 8, false);
  EXPECT_EQ(testing::ExpectFailedWritesKeepEarlierFiles(dir_, [&](Env* env) {
              return WriteGlb(Path("model.glb"), Grid(3, 2), textured, nullptr, env);
            }),
            1);
}

TEST_F(GltfTest, ReaderRejectsDamagedFiles) {
  ASSERT_TRUE(WriteGlb(Path("m.glb"), Grid(2, 1), GltfWriteOptions{}).ok());
  std::ifstream in(Path("m.glb"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto truncated = ReadGlb(Write("t.glb", bytes.substr(0, bytes.size() - 8)));
  EXPECT_EQ(truncated.status().code(), Status::Code::kCorrupt);
  EXPECT_NE(truncated.status().message().find("t.glb"), std::string::npos);
  EXPECT_EQ(ReadGlb(Write("x.glb", "not a glb at all, really")).status().code(), Status::Code::kCorrupt);
  EXPECT_EQ(ReadGlb(Path("none.glb")).status().code(), Status::Code::kNotFound);
}

TEST_F(GltfTest, ReaderSurvivesCorruptedBytesAndHostileJson) {
  GltfWriteOptions options;
  options.base_color_png = Png(8, 8, false);
  ASSERT_TRUE(WriteGlb(Path("m.glb"), Grid(3, 2), options).ok());
  std::ifstream in(Path("m.glb"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Every byte of the file set to 0xFF in turn, and the file cut at every 7th
  // length: an error or a mesh that passes Validate, never a crash (run under
  // the sanitizer build too).
  int failures = 0;
  for (size_t i = 0; i < bytes.size(); ++i) {
    std::string damaged = bytes;
    damaged[i] = char(0xFF);
    auto model = ReadGlb(Write("d.glb", damaged));
    if (!model.ok()) {
      ++failures;
      EXPECT_NE(model.status().message().find("d.glb"), std::string::npos) << model.status().message();
    } else {
      EXPECT_TRUE(Validate(model->mesh).ok()) << i;
    }
  }
  EXPECT_GT(failures, 0);
  for (size_t n = 0; n < bytes.size(); n += 7) {
    EXPECT_FALSE(ReadGlb(Write("t.glb", bytes.substr(0, n))).ok()) << n;
  }
  // Hostile offsets and counts in otherwise valid JSON.
  uint32_t json_length;
  std::memcpy(&json_length, bytes.data() + 12, 4);
  const std::string json = bytes.substr(20, json_length);
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"\"byteOffset\":0", "\"byteOffset\":18446744073709551615"},
           {"\"count\":12", "\"count\":4611686018427387904"},
           {"\"count\":12", "\"count\":-1"},
           {"\"primitives\"", "\"primitive\""},
           {"\"meshes\":[", "\"meshes\":3,\"x\":["},
           {"\"version\":\"2.0\"", "\"version\":2"}}) {
    const size_t at = json.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    std::string edited = json;
    edited.replace(at, from.size(), to);
    while (edited.size() % 4) edited.push_back(' ');
    std::string file = bytes.substr(0, 20) + edited + bytes.substr(20 + json_length);
    const uint32_t total = uint32_t(file.size()), length = uint32_t(edited.size());
    std::memcpy(file.data() + 8, &total, 4);
    std::memcpy(file.data() + 12, &length, 4);
    auto model = ReadGlb(Write("h.glb", file));
    EXPECT_EQ(model.status().code(), Status::Code::kCorrupt) << to;
  }
}

// Writes the files the Khronos validator checks (ctest `gltf_validator`):
// into $PB_GLTF_SAMPLE_DIR when set, else into the test's folder.
TEST_F(GltfTest, ValidatorSamples) {
  const char* env = std::getenv("PB_GLTF_SAMPLE_DIR");
  const std::filesystem::path out = env ? std::filesystem::path(env) : dir_;
  std::filesystem::create_directories(out);
  Mesh curved = Grid(40, 20, 0.3);
  curved.colors.clear();
  GltfWriteOptions options;
  options.base_color_png = Png(256, 256, false);
  options.normal_png = Png(256, 128, true);
  GltfWriteReport report;
  ASSERT_TRUE(WriteGlb((out / "textured.glb").string(), curved, options, &report).ok());
  EXPECT_TRUE(report.wrote_tangents);
  Mesh mirrored = Grid(10, 10, 0.1);
  for (size_t v = 0; v < mirrored.vertex_count(); ++v) mirrored.uvs[2 * v] = 1 - mirrored.uvs[2 * v];
  ASSERT_TRUE(WriteGlb((out / "colored_mirrored.glb").string(), mirrored, GltfWriteOptions{}, &report).ok());
  EXPECT_TRUE(report.wrote_colors);
  ASSERT_TRUE(WriteGlb((out / "large_uint32.glb").string(), Grid(300, 220, 0.2), GltfWriteOptions{}).ok());
  for (const char* name : {"textured.glb", "colored_mirrored.glb", "large_uint32.glb"}) {
    EXPECT_TRUE(ReadGlb((out / name).string()).ok()) << name;
  }
  // broken.glb: textured.glb with its first position moved outside the
  // declared max, which the validator must report (ACCESSOR_MAX_MISMATCH).
  std::ifstream in(out / "textured.glb", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  uint32_t json_length;
  std::memcpy(&json_length, bytes.data() + 12, 4);
  const float outside = 1000.0f;
  std::memcpy(bytes.data() + 20 + json_length + 8, &outside, 4);  // bufferView 0 = POSITION
  std::ofstream(out / "broken.glb", std::ios::binary) << bytes;
  EXPECT_TRUE(ReadGlb((out / "broken.glb").string()).ok());  // readable, but invalid
}

}  // namespace
}  // namespace pb
