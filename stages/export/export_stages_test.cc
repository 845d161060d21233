// Runs export.gltf and export.obj through a fake StageContext (no engine, no
// child processes): files go to a temporary directory.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <vector>

#include "stages/builtin.h"
#include "stages/export/export_io.h"
#include "stages/export/ktx2_encode.h"
#include "stages/geometry/io/gltf.h"
#include "stages/geometry/io/ktx2.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/io/obj.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/core/tangents.h"
#include "stages/stage_test_util.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

std::vector<uint8_t> FileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

class ExportStagesTest : public StageTest {
 protected:
  void SetUp() override {
    StageTest::SetUp();
    RegisterBuiltinStages(registry_);
    std::filesystem::create_directories(dir_ / "input");
  }

  std::string Input(const std::string& name) const { return (dir_ / "input" / name).string(); }

  // A 10 x 10 quad grid with colors (and uvs when asked), far from 0.
  std::string WriteMesh(bool uvs) {
    Mesh mesh;
    mesh.origin = {350000.5, 5800000.25, 42.0};
    const int n = 10;
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i <= n; ++i) {
        mesh.positions.insert(mesh.positions.end(), {float(i) / n, float(j) / n, 0.0f});
        mesh.colors.insert(mesh.colors.end(), {uint8_t(20 * i), uint8_t(20 * j), 200});
        if (uvs) mesh.uvs.insert(mesh.uvs.end(), {float(i) / n, float(j) / n});
      }
    }
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
        mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
      }
    }
    const std::string path = Input("mesh.ply");
    EXPECT_TRUE(WritePlyMesh(path, mesh).ok());
    return path;
  }

  std::string WriteImage(const std::string& name, Image::PixelType type, int width = 32,
                         int height = 16) {
    Image image = Image::Make(width, height, 3, type);
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        for (int c = 0; c < 3; ++c) {
          const double value = c == 2 ? 1.0 : (c == 0 ? x / (width - 1.0) : y / (height - 1.0));
          if (type == Image::PixelType::kU8) image.at_u8(x, y, c) = uint8_t(std::lround(value * 255));
          if (type == Image::PixelType::kU16) image.at_u16(x, y, c) = uint16_t(std::lround(value * 65535));
          if (type == Image::PixelType::kF32) image.at_f32(x, y, c) = float(2 * value - 1);
        }
      }
    }
    const std::string path = Input(name);
    EXPECT_TRUE(pb::WriteImage(path, image).ok());
    return path;
  }
};

TEST_F(ExportStagesTest, StagesAreWellFormed) {
  for (const char* id : {"export.gltf", "export.obj", "export.vtp"}) {
    const StageType* type = registry_.Find(id);
    ASSERT_NE(type, nullptr) << id;
    CheckedSchema(*type, /*defaults=*/true);
    ASSERT_EQ(type->inputs.size(), 3u);
    EXPECT_EQ(type->inputs[0].name, "mesh");
    EXPECT_FALSE(type->inputs[0].optional);
    EXPECT_EQ(type->inputs[1].name, "color");
    EXPECT_EQ(type->inputs[1].type, "image");
    EXPECT_TRUE(type->inputs[1].optional);
    EXPECT_EQ(type->inputs[2].name, "normal");
    EXPECT_TRUE(type->inputs[2].optional);
    ASSERT_EQ(type->outputs.size(), 1u);
    EXPECT_EQ(type->outputs[0].type, "model");
    EXPECT_THAT(type->doc, HasSubstr("Counters: `faces`, `vertices`, `bytes`"));
  }
}

TEST_F(ExportStagesTest, GltfEmbedsTexturesAndComputesTangents) {
  FakeContext ctx(dir_ / "run", {{"name", "wall"}});
  ctx.AddInput("mesh", "mesh", WriteMesh(true), {{"source", "test"}});
  const std::string color = WriteImage("color.png", Image::PixelType::kU8);
  const std::string normal = WriteImage("normal.png", Image::PixelType::kU8);
  ctx.AddInput("color", "image", color);
  ctx.AddInput("normal", "image", normal);
  const Status status = Run("export.gltf", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(std::filesystem::path(ctx.outputs_["model"]).filename(), "model.glb");
  EXPECT_EQ(ctx.counters_["faces"], 200);
  EXPECT_EQ(ctx.counters_["vertices"], 121);
  EXPECT_EQ(ctx.counters_["bytes"], std::filesystem::file_size(ctx.outputs_["model"]));
  EXPECT_EQ(ctx.phases_, (std::set<std::string>{"io"}));
  EXPECT_DOUBLE_EQ(ctx.last_progress_, 1.0);
  const nlohmann::json& meta = ctx.meta_["model"];
  EXPECT_EQ(meta["source"], "test");  // input meta passed on
  EXPECT_EQ(meta["format"], "glb");
  EXPECT_EQ(meta["tangents"], "computed");
  EXPECT_EQ(meta["normals"], "computed");
  EXPECT_EQ(meta["vertex_colors"], false);  // a color texture is given
  EXPECT_EQ(meta["color_texture"], true);
  EXPECT_EQ(meta["origin"][0], 350000.5);

  auto model = ReadGlb(ctx.outputs_["model"]);
  ASSERT_TRUE(model.ok()) << model.status().message();
  EXPECT_EQ(model->name, "wall");
  EXPECT_EQ(model->mesh.origin, (std::array<double, 3>{350000.5, 5800000.25, 42.0}));
  EXPECT_EQ(model->base_color_png, FileBytes(color));  // passed through byte for byte
  EXPECT_EQ(model->normal_png, FileBytes(normal));
  ASSERT_EQ(model->mesh.tangents.size(), 4u * 121);
  EXPECT_NEAR(model->mesh.tangents[0], 1, 1e-6);
  EXPECT_EQ(model->mesh.tangents[3], 1.0f);
}

// Where export.gltf finds its KTX2 encoder (ktx2_encode.h); empty when the
// npm packages are not installed (a visible skip locally, a failure in CI).
bool Ktx2EncoderInstalled() {
  if (!Ktx2EncoderVersion().empty()) return true;
  if (std::getenv("CI")) ADD_FAILURE() << "CI: tools/node_modules/ktx2-encoder is not installed";
  return false;
}

TEST_F(ExportStagesTest, GltfKtx2EmbedsBasisUniversalMapsAndDefaultIsUnchanged) {
  if (!Ktx2EncoderInstalled()) GTEST_SKIP() << "npm ci --prefix tools";
  const std::string mesh = WriteMesh(true);
  const std::string color = WriteImage("color.png", Image::PixelType::kU8);
  const std::string normal = WriteImage("normal.exr", Image::PixelType::kF32);
  FakeContext png(dir_ / "png", nlohmann::json::object());
  FakeContext ktx2(dir_ / "ktx2", {{"textures", "ktx2"}});
  for (FakeContext* ctx : {&png, &ktx2}) {
    ctx->AddInput("mesh", "mesh", mesh);
    ctx->AddInput("color", "image", color);
    ctx->AddInput("normal", "image", normal);
    const Status status = Run("export.gltf", *ctx);
    ASSERT_TRUE(status.ok()) << status.message();
  }
  // The default is the PNG model, its meta without the new keys.
  EXPECT_FALSE(png.meta_["model"].contains("textures"));
  EXPECT_FALSE(png.meta_["model"].contains("vertex_order"));
  EXPECT_EQ(ktx2.meta_["model"]["textures"], "ktx2");
  EXPECT_THAT(ktx2.meta_["model"]["ktx2_encoder"].get<std::string>(), HasSubstr("ktx2-encoder "));
  EXPECT_TRUE(ktx2.phases_.count("encode"));

  auto model = ReadGlb(ktx2.outputs_["model"]);
  ASSERT_TRUE(model.ok()) << model.status().message();
  EXPECT_TRUE(model->base_color_png.empty());
  EXPECT_TRUE(model->normal_png.empty());
  auto color_info = ReadKtx2Info(model->base_color_ktx2, "color");
  auto normal_info = ReadKtx2Info(model->normal_ktx2, "normal");
  ASSERT_TRUE(color_info.ok()) << color_info.status().message();
  ASSERT_TRUE(normal_info.ok()) << normal_info.status().message();
  EXPECT_EQ(color_info->codec, Ktx2Codec::kEtc1s);
  EXPECT_TRUE(color_info->srgb);
  EXPECT_EQ(normal_info->codec, Ktx2Codec::kUastc);
  EXPECT_FALSE(normal_info->srgb);
  EXPECT_EQ(color_info->width, 32);
  EXPECT_EQ(color_info->height, 16);
  EXPECT_EQ(color_info->levels, 6);  // 32x16 .. 1x1
  // Same geometry as the PNG model.
  auto png_model = ReadGlb(png.outputs_["model"]);
  ASSERT_TRUE(png_model.ok());
  EXPECT_EQ(model->mesh.positions, png_model->mesh.positions);
  EXPECT_EQ(model->mesh.indices, png_model->mesh.indices);

  // Deterministic: the same inputs give the same bytes (cache early cutoff).
  FakeContext again(dir_ / "again", {{"textures", "ktx2"}});
  again.AddInput("mesh", "mesh", mesh);
  again.AddInput("color", "image", color);
  again.AddInput("normal", "image", normal);
  ASSERT_TRUE(Run("export.gltf", again).ok());
  EXPECT_EQ(FileBytes(again.outputs_["model"]), FileBytes(ktx2.outputs_["model"]));

  // For the Khronos validator (ctest gltf_validator.ktx2).
  if (const char* out = std::getenv("PB_KTX2_SAMPLE")) {
    std::filesystem::copy_file(ktx2.outputs_["model"], out,
                               std::filesystem::copy_options::overwrite_existing);
  }
}

// A map above ktx2-encoder 0.6.0's 12 Mpix (it refuses a 4096² map; the
// scaling benchmark's 4096² maps failed) goes to ktx2-encoder-legacy, with
// the same settings, deterministically; the meta names each map's encoder.
TEST_F(ExportStagesTest, GltfKtx2EncodesAMapAboveTwelveMegapixels) {
  if (!Ktx2EncoderInstalled()) GTEST_SKIP() << "npm ci --prefix tools";
  const int64_t above = kKtx2CurrentEncoderMaxTexels + 1;
  ASSERT_FALSE(Ktx2EncoderVersion(above).empty()) << "tools/node_modules/ktx2-encoder-legacy";
  ASSERT_NE(Ktx2EncoderVersion(above), Ktx2EncoderVersion());
  const int side = 3600;  // 12.96 Mpix
  ASSERT_GT(int64_t{side} * side, kKtx2CurrentEncoderMaxTexels);
  const std::string mesh = WriteMesh(true);
  const std::string color = WriteImage("color.png", Image::PixelType::kU8);
  const std::string normal = WriteImage("normal.png", Image::PixelType::kU8, side, side);
  std::vector<std::string> glb;  // the two runs' model files
  for (const char* run : {"first", "again"}) {
    FakeContext ctx(dir_ / run, {{"textures", "ktx2"}});
    ctx.AddInput("mesh", "mesh", mesh);
    ctx.AddInput("color", "image", color);
    ctx.AddInput("normal", "image", normal);
    const Status status = Run("export.gltf", ctx);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_EQ(ctx.meta_["model"]["ktx2_encoder"].get<std::string>(),
              Ktx2EncoderVersion() + " (color), " + Ktx2EncoderVersion(above) + " (normal)");
    glb.push_back(ctx.outputs_["model"]);
  }
  EXPECT_EQ(FileBytes(glb[0]), FileBytes(glb[1]));  // deterministic: the cache's early cutoff holds
  auto model = ReadGlb(glb[0]);
  ASSERT_TRUE(model.ok()) << model.status().message();
  auto normal_info = ReadKtx2Info(model->normal_ktx2, "normal");
  ASSERT_TRUE(normal_info.ok()) << normal_info.status().message();
  EXPECT_EQ(normal_info->codec, Ktx2Codec::kUastc);
  EXPECT_FALSE(normal_info->srgb);
  EXPECT_EQ(normal_info->width, side);
  EXPECT_EQ(normal_info->height, side);
  EXPECT_EQ(normal_info->levels, 12);  // 3600 .. 1
  auto color_info = ReadKtx2Info(model->base_color_ktx2, "color");
  ASSERT_TRUE(color_info.ok()) << color_info.status().message();
  EXPECT_EQ(color_info->codec, Ktx2Codec::kEtc1s);
}

TEST_F(ExportStagesTest, GltfKtx2WithoutEncoderNamesWhatToInstall) {
  const char* previous = std::getenv("POINTBAKE_TOOLS_DIR");
  const std::string saved = previous ? previous : "";
  setenv("POINTBAKE_TOOLS_DIR", (dir_ / "no_tools").c_str(), 1);
  FakeContext ctx(dir_ / "run", {{"textures", "ktx2"}});
  ctx.AddInput("mesh", "mesh", WriteMesh(true));
  ctx.AddInput("color", "image", WriteImage("color.png", Image::PixelType::kU8));
  const Status status = Run("export.gltf", ctx);
  if (previous) setenv("POINTBAKE_TOOLS_DIR", saved.c_str(), 1); else unsetenv("POINTBAKE_TOOLS_DIR");
  EXPECT_EQ(status.code(), Status::Code::kNotFound);
  EXPECT_THAT(status.message(), HasSubstr("export.gltf: the color map: KTX2 encoding needs"));
  EXPECT_THAT(status.message(), HasSubstr("npm ci --prefix tools"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "run" / "model" / "model.glb"));
}

TEST_F(ExportStagesTest, GltfOptimizedVertexOrderKeepsTheTriangles) {
  FakeContext plain(dir_ / "plain", nlohmann::json::object());
  FakeContext optimized(dir_ / "optimized", {{"vertex_order", "optimized"}});
  const std::string mesh = WriteMesh(true);
  for (FakeContext* ctx : {&plain, &optimized}) {
    ctx->AddInput("mesh", "mesh", mesh);
    ASSERT_TRUE(Run("export.gltf", *ctx).ok());
  }
  const nlohmann::json& order = optimized.meta_["model"]["vertex_order"];
  EXPECT_LE(order["acmr_after"].get<double>(), order["acmr_before"].get<double>());
  EXPECT_EQ(optimized.counters_["acmr"], order["acmr_after"].get<double>());
  auto a = ReadGlb(plain.outputs_["model"]), b = ReadGlb(optimized.outputs_["model"]);
  ASSERT_TRUE(a.ok() && b.ok());
  // The same triangles as corner positions (rotated to start at the
  // smallest), in any order.
  auto triangles = [](const Mesh& m) {
    std::multiset<std::array<std::array<float, 5>, 3>> out;
    for (size_t f = 0; f < m.face_count(); ++f) {
      std::array<std::array<float, 5>, 3> t;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = m.indices[3 * f + k];
        t[k] = {m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2], m.uvs[2 * v],
                m.uvs[2 * v + 1]};
      }
      std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
      out.insert(t);
    }
    return out;
  };
  EXPECT_EQ(triangles(a->mesh), triangles(b->mesh));
  EXPECT_NE(a->mesh.indices, b->mesh.indices);  // the order did change
}

TEST_F(ExportStagesTest, GltfWithoutTexturesKeepsVertexColors) {
  FakeContext ctx(dir_ / "run", nlohmann::json::object());
  ctx.AddInput("mesh", "mesh", WriteMesh(false));
  const Status status = Run("export.gltf", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.meta_["model"]["vertex_colors"], true);
  EXPECT_EQ(ctx.meta_["model"]["tangents"], "none");
  auto model = ReadGlb(ctx.outputs_["model"]);
  ASSERT_TRUE(model.ok());
  EXPECT_EQ(model->mesh.colors.size(), 3u * 121);
  EXPECT_TRUE(model->mesh.uvs.empty());

  FakeContext off(dir_ / "off", {{"vertex_colors", false}});
  off.AddInput("mesh", "mesh", Input("mesh.ply"));
  ASSERT_TRUE(Run("export.gltf", off).ok());
  EXPECT_TRUE(ReadGlb(off.outputs_["model"])->mesh.colors.empty());
}

TEST_F(ExportStagesTest, ExrAndSixteenBitMapsAreConvertedToEightBitPng) {
  FakeContext ctx(dir_ / "run", nlohmann::json::object());
  ctx.AddInput("mesh", "mesh", WriteMesh(true));
  ctx.AddInput("color", "image", WriteImage("color16.png", Image::PixelType::kU16));
  ctx.AddInput("normal", "image", WriteImage("normal.exr", Image::PixelType::kF32));
  const Status status = Run("export.gltf", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  auto model = ReadGlb(ctx.outputs_["model"]);
  ASSERT_TRUE(model.ok());
  const std::string normal_png = (dir_ / "normal_out.png").string();
  std::ofstream(normal_png, std::ios::binary)
      .write(reinterpret_cast<const char*>(model->normal_png.data()), model->normal_png.size());
  auto normal = ReadPng(normal_png);
  ASSERT_TRUE(normal.ok());
  EXPECT_EQ(normal->type, Image::PixelType::kU8);
  EXPECT_EQ(normal->at_u8(0, 0, 0), 0);      // -1 -> 0
  EXPECT_EQ(normal->at_u8(31, 0, 0), 255);   // +1 -> 255
  EXPECT_EQ(normal->at_u8(0, 0, 2), 255);    // z = +1
  const std::string color_png = (dir_ / "color_out.png").string();
  std::ofstream(color_png, std::ios::binary)
      .write(reinterpret_cast<const char*>(model->base_color_png.data()), model->base_color_png.size());
  auto color = ReadPng(color_png);
  ASSERT_TRUE(color.ok());
  EXPECT_EQ(color->type, Image::PixelType::kU8);
  EXPECT_EQ(color->at_u8(31, 15, 0), 255);
  EXPECT_EQ(color->at_u8(0, 0, 0), 0);
}

// The map's header decides: a ".png" that holds an OpenEXR image, or is cut
// short, is an error naming the stage, the port and the file.
TEST_F(ExportStagesTest, MapThatIsNotAPngIsAClearError) {
  const std::string exr = WriteImage("color.exr", Image::PixelType::kF32);
  const std::string disguised = Input("disguised.png");
  std::filesystem::rename(exr, disguised);
  const std::string truncated = Write("truncated.png", "\x89PNG\r\n\x1a\n");
  for (const std::string& path : {disguised, truncated}) {
    FakeContext ctx(dir_ / "run", nlohmann::json::object());
    ctx.AddInput("mesh", "mesh", WriteMesh(true));
    ctx.AddInput("color", "image", path);
    const Status status = Run("export.gltf", ctx);
    EXPECT_EQ(status.code(), Status::Code::kCorrupt) << status.message();
    EXPECT_THAT(status.message(), HasSubstr("export.gltf: input 'color'"));
    EXPECT_THAT(status.message(), HasSubstr(path));
  }
}

TEST_F(ExportStagesTest, TextureWithoutUvsIsAClearError) {
  for (const char* id : {"export.gltf", "export.obj", "export.vtp"}) {
    FakeContext ctx(dir_ / id, nlohmann::json::object());
    ctx.AddInput("mesh", "mesh", WriteMesh(false));
    ctx.AddInput("normal", "image", WriteImage("normal.png", Image::PixelType::kU8));
    const Status status = Run(id, ctx);
    EXPECT_EQ(status.code(), Status::Code::kInvalid) << id;
    EXPECT_THAT(status.message(), HasSubstr(id));
    EXPECT_THAT(status.message(), HasSubstr("mesh.ply has none"));
    EXPECT_THAT(status.message(), HasSubstr("uv.unwrap"));
    EXPECT_FALSE(std::filesystem::exists(dir_ / id / "out"));  // nothing written
  }
}

// In the cache an artifact's files are stored under their content digest,
// without an extension: the format comes from the file's name.
TEST_F(ExportStagesTest, TexturesStoredWithoutExtensionAreFoundByName) {
  FakeContext ctx(dir_ / "run", nlohmann::json::object());
  ctx.AddInput("mesh", "mesh", WriteMesh(true));
  const std::string color = WriteImage("color.png", Image::PixelType::kU8);
  const std::string digest_path = Input("cc492b343d6c22103572169cc620c18d");
  std::filesystem::copy_file(color, digest_path);
  ctx.AddInput("color", "image", std::map<std::string, std::string>{{"color.png", digest_path}});
  const Status status = Run("export.gltf", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  auto model = ReadGlb(ctx.outputs_["model"]);
  ASSERT_TRUE(model.ok());
  EXPECT_EQ(model->base_color_png, FileBytes(color));
}

TEST_F(ExportStagesTest, BadTextureInputsAreClearErrors) {
  FakeContext ctx(dir_ / "run", nlohmann::json::object());
  ctx.AddInput("mesh", "mesh", WriteMesh(true));
  std::ofstream(Input("color.png")) << "not a png";
  ctx.AddInput("color", "image", Input("color.png"));
  Status status = Run("export.gltf", ctx);
  EXPECT_EQ(status.code(), Status::Code::kCorrupt);
  EXPECT_THAT(status.message(), HasSubstr("export.gltf: input 'color'"));
  EXPECT_THAT(status.message(), HasSubstr(Input("color.png")));

  FakeContext tiff(dir_ / "tiff", nlohmann::json::object());
  tiff.AddInput("mesh", "mesh", Input("mesh.ply"));
  std::ofstream(Input("color.tif")) << "II*";
  tiff.AddInput("color", "image", Input("color.tif"));
  status = Run("export.obj", tiff);
  EXPECT_EQ(status.code(), Status::Code::kUnsupported);
  EXPECT_THAT(status.message(), HasSubstr("expected a .png or .exr"));
}

TEST_F(ExportStagesTest, ObjWritesModelMaterialAndTextures) {
  FakeContext ctx(dir_ / "run", nlohmann::json::object());
  ctx.AddInput("mesh", "mesh", WriteMesh(true), {{"source", "test"}});
  const std::string color = WriteImage("color.png", Image::PixelType::kU8);
  ctx.AddInput("color", "image", color);
  ctx.AddInput("normal", "image", WriteImage("normal.png", Image::PixelType::kU8));
  const Status status = Run("export.obj", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  std::set<std::string> files;
  uint64_t bytes = 0;
  const auto out_dir = std::filesystem::path(ctx.outputs_["model"]).parent_path();
  for (const auto& entry : std::filesystem::directory_iterator(out_dir)) {
    files.insert(entry.path().filename().string());
    bytes += entry.file_size();
  }
  EXPECT_EQ(files, (std::set<std::string>{"model.obj", "model.mtl", "color.png", "normal.png"}));
  std::set<std::string> declared;  // the files the engine is told about
  for (const auto& [name, file] : ctx.files_) declared.insert(name);
  EXPECT_EQ(declared, (std::set<std::string>{"model/model.obj", "model/model.mtl", "model/color.png",
                                             "model/normal.png"}));
  EXPECT_EQ(ctx.counters_["bytes"], bytes);
  EXPECT_EQ(ctx.counters_["faces"], 200);
  EXPECT_EQ(ctx.counters_["vertices"], 121);
  EXPECT_EQ(ctx.meta_["model"]["format"], "obj");
  EXPECT_EQ(ctx.meta_["model"]["source"], "test");
  auto model = ReadObj((out_dir / "model.obj").string());
  ASSERT_TRUE(model.ok()) << model.status().message();
  EXPECT_EQ(model->mesh.origin, (std::array<double, 3>{350000.5, 5800000.25, 42.0}));
  EXPECT_EQ(model->mesh.face_count(), 200u);
  EXPECT_EQ(model->base_color_png, FileBytes(color));
  EXPECT_FALSE(model->normal_png.empty());
}

TEST_F(ExportStagesTest, ObjRelativeCoordinates) {
  FakeContext ctx(dir_ / "run", {{"coordinates", "relative"}});
  ctx.AddInput("mesh", "mesh", WriteMesh(false));
  ASSERT_TRUE(Run("export.obj", ctx).ok());
  EXPECT_EQ(ctx.meta_["model"]["coordinates"], "relative");
  EXPECT_EQ(ctx.files_.size(), 2u);  // model.obj, model.mtl: no textures
  const std::string obj = ctx.files_["model/model.obj"];
  std::ifstream in(obj);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_THAT(text, HasSubstr("\nv 1 1 0 "));  // the last grid corner, relative
  auto model = ReadObj(obj);
  ASSERT_TRUE(model.ok());
  EXPECT_EQ(model->mesh.origin, (std::array<double, 3>{350000.5, 5800000.25, 42.0}));

  FakeContext bad(dir_ / "bad", {{"coordinates", "local"}});
  bad.AddInput("mesh", "mesh", Input("mesh.ply"));
  EXPECT_THAT(Run("export.obj", bad).message(), HasSubstr("'coordinates' must be"));
}

TEST_F(ExportStagesTest, MissingMeshInputIsAnError) {
  FakeContext ctx(dir_ / "run", nlohmann::json::object());
  const Status status = Run("export.obj", ctx);
  EXPECT_FALSE(status.ok());
  EXPECT_THAT(status.message(), HasSubstr("export.obj: input 'mesh' is not connected"));
}

}  // namespace
}  // namespace pb
