// Tests of the frame-rate model (fps_model.h), its Oculus Go calibration on
// the paper's Table 4, device-file errors, and the estimate.fps stage.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "stages/geometry/core/image.h"
#include "stages/geometry/core/table.h"
#include "stages/estimate/fps_model.h"
#include "stages/geometry/io/gltf.h"
#include "stages/geometry/testing/ktx2_sample.h"
#include "stages/builtin.h"
#include "stages/stage_test_util.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

// The paper's Table 2 (faces) and Table 4 (FPS on Oculus Go): D11v3,
// NETower, D31.
constexpr uint64_t kHighFaces[] = {4352296, 6857430, 3690788};
constexpr double kHighFps[] = {16, 10, 17};
constexpr uint64_t kLowFaces[] = {240000, 442900, 224476};

Expected<DeviceProfile> ShippedOculusGo() {
  const char* source = std::getenv("PB_SOURCE_DIR");
  if (!source) return Status::NotFound("PB_SOURCE_DIR not set");
  return ReadDeviceProfile(std::string(source) + "/configs/devices/oculus-go.yaml");
}

TEST(FpsModelTest, OculusGoReproducesTable4) {
  Expected<DeviceProfile> go = ShippedOculusGo();
  if (!go.ok() && go.status().message() == "PB_SOURCE_DIR not set") GTEST_SKIP() << "run with ctest";
  ASSERT_TRUE(go.ok()) << go.status().message();
  EXPECT_EQ(go->name, "oculus-go");
  EXPECT_EQ(go->refresh_hz, 60);
  for (int i = 0; i < 3; ++i) {
    const double fps = EstimateFps(*go, kHighFaces[i]);
    EXPECT_LT(std::abs(fps - kHighFps[i]) / kHighFps[i], 0.10)
        << kHighFaces[i] << " faces: " << fps << " FPS, measured " << kHighFps[i];
    EXPECT_EQ(EstimateFps(*go, kLowFaces[i]), 60.0) << kLowFaces[i] << " faces";
  }
}

// The shipped throughput is the least-squares fit on relative error:
// minimizing sum (T / (n_i f_i) - 1)^2 gives T = sum a_i / sum a_i^2 with
// a_i = 1 / (n_i f_i) (docs/fps.md), rounded to three digits.
TEST(FpsModelTest, OculusGoThroughputIsTheRelativeLeastSquaresFit) {
  Expected<DeviceProfile> go = ShippedOculusGo();
  if (!go.ok() && go.status().message() == "PB_SOURCE_DIR not set") GTEST_SKIP() << "run with ctest";
  ASSERT_TRUE(go.ok()) << go.status().message();
  double sum_a = 0, sum_a2 = 0;
  for (int i = 0; i < 3; ++i) {
    const double a = 1.0 / (static_cast<double>(kHighFaces[i]) * kHighFps[i]);
    sum_a += a;
    sum_a2 += a * a;
  }
  const double fit = sum_a / sum_a2;
  EXPECT_NEAR(fit, 66.70e6, 0.01e6);
  EXPECT_NEAR(go->triangles_per_s, fit, 0.001 * fit);
}

TEST(FpsModelTest, FpsIsThroughputOverTrianglesCappedByRefresh) {
  DeviceProfile device;
  device.triangles_per_s = 1000;
  device.refresh_hz = 72;
  EXPECT_EQ(EstimateFps(device, 100), 10.0);
  EXPECT_EQ(EstimateFps(device, 10), 72.0);
  EXPECT_EQ(EstimateFps(device, 0), 72.0);
}

TEST(FpsModelTest, TextureMemoryOfTwo8kMapsWithMips) {
  DeviceProfile device;  // RGBA8, mips
  // 8192^2 + 4096^2 + ... + 1 = (4^14 - 1) / 3 texels per map.
  EXPECT_EQ(TextureTexels({8192, 8192}, true), 89478485u);
  EXPECT_EQ(TextureTexels({8192, 8192}, false), 67108864u);
  const std::vector<TextureSize> maps = {{8192, 8192}, {8192, 8192}};
  EXPECT_EQ(TextureBytes(device, maps), 2u * 4u * 89478485u);  // 715,827,880 B = 683 MiB
  device.texture_bytes_per_texel = 1;  // e.g. ASTC 4x4
  EXPECT_EQ(TextureBytes(device, maps), 2u * 89478485u);
  device.mipmaps = false;
  EXPECT_EQ(TextureBytes(device, maps), 2u * 67108864u);
}

TEST(FpsModelTest, MipChainOfNonSquareMapsStopsAt1x1) {
  // 5x3, 2x1, 1x1.
  EXPECT_EQ(TextureTexels({5, 3}, true), 15u + 2u + 1u);
  // 64x4, 32x2, 16x1, 8x1, 4x1, 2x1, 1x1.
  EXPECT_EQ(TextureTexels({64, 4}, true), 256u + 64u + 16u + 8u + 4u + 2u + 1u);
  EXPECT_EQ(TextureTexels({0, 16}, true), 0u);
}

TEST(FpsModelTest, EstimateReportsLargestMapAndBudget) {
  DeviceProfile device;
  device.triangles_per_s = 600;
  device.refresh_hz = 60;
  device.texture_budget_bytes = 4 * (4 + 1) + 4 * (16 + 4 + 1);
  const std::vector<TextureSize> maps = {{2, 2}, {4, 4}};
  FpsEstimate estimate = EstimateFrameRate(device, 20, maps);
  EXPECT_EQ(estimate.fps, 30.0);
  EXPECT_EQ(estimate.texture_width, 4);
  EXPECT_EQ(estimate.texture_height, 4);
  EXPECT_EQ(estimate.texture_bytes, 104u);
  EXPECT_TRUE(estimate.fits_texture_budget);
  device.texture_budget_bytes = 103;
  EXPECT_FALSE(EstimateFrameRate(device, 20, maps).fits_texture_budget);
}

TEST(DeviceProfileTest, ParsesAllKeysCommentsAndQuotes) {
  Expected<DeviceProfile> device = ParseDeviceProfile(
      "# a headset\n---\nname: 'test''s device'  # trailing comment\n"
      "description: \"says \\\"hi\\\" # not a comment\"\ntriangles_per_s: 1.5e7\n"
      "refresh_hz: 72\ntexture_budget_bytes: 1e9\ntexture_bytes_per_texel: 0.5\nmipmaps: false\n",
      "dev.yaml");
  ASSERT_TRUE(device.ok()) << device.status().message();
  EXPECT_EQ(device->name, "test's device");
  EXPECT_EQ(device->description, "says \"hi\" # not a comment");
  EXPECT_EQ(device->triangles_per_s, 1.5e7);
  EXPECT_EQ(device->refresh_hz, 72);
  EXPECT_EQ(device->texture_budget_bytes, 1000000000);
  EXPECT_EQ(device->texture_bytes_per_texel, 0.5);
  EXPECT_FALSE(device->mipmaps);
}

// Each malformed profile fails with the expected place and words.
TEST(DeviceProfileTest, BadFilesNameFileLineAndProblem) {
  const std::string ok_tail = "refresh_hz: 60\ntexture_budget_bytes: 100\n";
  struct Case {
    std::string text;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"name: d\ntriangles_per_s: 0\n" + ok_tail, "d.yaml:2:18: 'triangles_per_s' must be > 0, got 0"},
      {"name: d\ntriangles_per_s: -5\n" + ok_tail, "d.yaml:2:18: 'triangles_per_s' must be > 0"},
      {"name: d\ntriangles_per_s: fast\n" + ok_tail, "d.yaml:2:18: 'triangles_per_s' must be a number, got \"fast\""},
      {"name: d\ntriangles_per_s: \"100\"\n" + ok_tail, "d.yaml:2:18: 'triangles_per_s' must be a number"},
      {"name: d\ntriangles_per_s: 100\nrefresh_hz: 0\ntexture_budget_bytes: 1\n",
       "d.yaml:3:13: 'refresh_hz' must be > 0"},
      {"name: d\ntriangles_per_s: 100\nrefresh_hz: 60\ntexture_budget_bytes: 1.5\n",
       "d.yaml:4:23: 'texture_budget_bytes' must be a whole number >= 0"},
      {"name: d\ntriangles_per_s: 100\n" + ok_tail + "texture_bytes_per_texel: 0\n",
       "d.yaml:5:26: 'texture_bytes_per_texel' must be > 0"},
      {"name: d\ntriangles_per_s: 100\n" + ok_tail + "mipmaps: yes\n",
       "d.yaml:5:10: 'mipmaps' must be true or false"},
      {"name: d\n" + ok_tail, "d.yaml: missing required key 'triangles_per_s'"},
      {"name: d\ntriangle_per_s: 100\n" + ok_tail, "d.yaml:2:1: unknown key 'triangle_per_s'"},
      {"name: d\nname: e\n", "d.yaml:2:1: duplicate key 'name'"},
      {"name: d\ntriangles_per_s: { fast: 1 }\n" + ok_tail, "d.yaml:2:18: 'triangles_per_s' must be a number"},
      {"name: d\n  refresh_hz: 60\n", "d.yaml:2:"},
      {"- name: d\n", "d.yaml:1:1: a device profile is a mapping"},
      {"name: [a, b]\n" + std::string("triangles_per_s: 1\n") + ok_tail, "d.yaml:1:7: 'name' must be text"},
  };
  for (const Case& c : cases) {
    Expected<DeviceProfile> device = ParseDeviceProfile(c.text, "d.yaml");
    ASSERT_FALSE(device.ok()) << c.text;
    EXPECT_EQ(device.status().code(), Status::Code::kInvalid) << c.text;
    EXPECT_THAT(device.status().message(), HasSubstr(c.expected)) << c.text;
  }
}

TEST(DeviceProfileTest, MissingFileIsNotFound) {
  Expected<DeviceProfile> device = ReadDeviceProfile("/nonexistent/device.yaml");
  ASSERT_FALSE(device.ok());
  EXPECT_EQ(device.status().code(), Status::Code::kNotFound);
  EXPECT_THAT(device.status().message(), HasSubstr("/nonexistent/device.yaml"));
}

class FpsStageTest : public StageTest {
 protected:
  void SetUp() override {
    StageTest::SetUp();
    RegisterBuiltinStages(registry_);
  }
  // Two triangles (a unit quad).
  std::string QuadMesh() {
    Mesh mesh;
    mesh.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    mesh.indices = {0, 1, 2, 0, 2, 3};
    return WriteInputMesh("quad", mesh);
  }
  std::string Device(const std::string& name, int64_t budget_bytes) {
    const std::string path = Path(name);
    std::ofstream(path) << "name: tiny\ntriangles_per_s: 100\nrefresh_hz: 60\n"
                        << "texture_budget_bytes: " << budget_bytes << "\n";
    return path;
  }
  std::string Png(const std::string& name, int width, int height) {
    EXPECT_TRUE(WritePng(Path(name), Image::Make(width, height, 3, Image::PixelType::kU8)).ok());
    return Path(name);
  }
};

// 64x32 with mips: 2048+512+128+32+8+2+1 = 2731 texels; 16x16: 341; RGBA8.
constexpr int64_t kQuadTextureBytes = 4 * (2731 + 341);

TEST_F(FpsStageTest, WritesOneRowWithTheReportColumns) {
  FakeContext ctx(dir_, {{"device", Device("tiny.yaml", kQuadTextureBytes)}});
  ctx.AddInput("mesh", "mesh", QuadMesh());
  ctx.AddInput("color", "image", Png("color.png", 64, 32));
  ctx.AddInput("normal", "image", Png("normal.png", 16, 16));
  const Status status = Run("estimate.fps", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  Expected<Table> table = ReadTable(ctx.outputs_.at("table"));
  ASSERT_TRUE(table.ok()) << table.status().message();
  EXPECT_EQ(table->columns,
            (std::vector<std::string>{"device", "triangles", "texture_width", "texture_height",
                                      "texture_bytes", "texture_budget_bytes",
                                      "fits_texture_budget", "triangles_per_s", "refresh_hz",
                                      "fps"}));
  ASSERT_EQ(table->rows.size(), 1u);
  EXPECT_EQ(std::get<std::string>(table->get(0, "device")), "tiny");
  EXPECT_EQ(TableNumber(table->get(0, "triangles")), 2);
  EXPECT_EQ(TableNumber(table->get(0, "texture_width")), 64);
  EXPECT_EQ(TableNumber(table->get(0, "texture_height")), 32);
  EXPECT_EQ(TableNumber(table->get(0, "texture_bytes")), kQuadTextureBytes);
  EXPECT_EQ(TableNumber(table->get(0, "texture_budget_bytes")), kQuadTextureBytes);
  EXPECT_EQ(std::get<bool>(table->get(0, "fits_texture_budget")), true);
  EXPECT_EQ(TableNumber(table->get(0, "triangles_per_s")), 100);
  EXPECT_EQ(TableNumber(table->get(0, "refresh_hz")), 60);
  EXPECT_EQ(TableNumber(table->get(0, "fps")), 50);
  EXPECT_EQ(ctx.counters_.at("fps"), 50);
  EXPECT_EQ(ctx.counters_.at("triangles"), 2);
  EXPECT_EQ(ctx.counters_.at("texture_bytes"), kQuadTextureBytes);
  EXPECT_EQ(ctx.meta_.at("table").at("device"), "tiny");
  EXPECT_TRUE(ctx.phases_.count("io") && ctx.phases_.count("compute"));
  EXPECT_EQ(ctx.last_progress_, 1.0);
}

TEST_F(FpsStageTest, Ktx2MapsOfTheModelCountWithTheirBlockSizes) {
  // The model's color map is ETC1S 64x32 with 7 levels (ETC2: 8 bytes a 4x4
  // block), its normal map UASTC 16x16 with 5 levels (ASTC 4x4: 16 bytes).
  Mesh quad;
  quad.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  quad.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  quad.indices = {0, 1, 2, 0, 2, 3};
  GltfWriteOptions options;
  options.base_color_ktx2 = testing::Ktx2Sample(163, 64, 32, 7, true);
  options.normal_ktx2 = testing::Ktx2Sample(166, 16, 16, 5, false);
  ASSERT_TRUE(WriteGlb(Path("model.glb"), quad, options).ok());
  // Color blocks: 16x8, 8x4, 4x2, 2x1, 1x1, 1x1, 1x1 = 128+32+8+2+3; normal: 16+4+1+1+1.
  constexpr int64_t kKtx2Bytes = 8 * (128 + 32 + 8 + 2 + 3) + 16 * (16 + 4 + 1 + 1 + 1);
  FakeContext ctx(dir_, {{"device", Device("tiny.yaml", kQuadTextureBytes)}});
  ctx.AddInput("mesh", "mesh", QuadMesh());
  ctx.AddInput("color", "image", Png("color.png", 64, 32));
  ctx.AddInput("normal", "image", Png("normal.png", 16, 16));
  ctx.AddInput("model", "model", Path("model.glb"));
  const Status status = Run("estimate.fps", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  Expected<Table> table = ReadTable(ctx.outputs_.at("table"));
  ASSERT_TRUE(table.ok());
  EXPECT_EQ(TableNumber(table->get(0, "texture_bytes")), kKtx2Bytes);
  EXPECT_LT(kKtx2Bytes * 3, kQuadTextureBytes);
  EXPECT_EQ(TableNumber(table->get(0, "texture_width")), 64);
  EXPECT_EQ(ctx.meta_.at("table").at("texture_format"), "ktx2");

  // A PNG model changes nothing: the image inputs count with the profile.
  ASSERT_TRUE(WriteGlb(Path("png.glb"), quad, GltfWriteOptions{}).ok());
  FakeContext png(dir_ / "png", {{"device", Device("tiny.yaml", kQuadTextureBytes)}});
  png.AddInput("mesh", "mesh", QuadMesh());
  png.AddInput("color", "image", Png("color.png", 64, 32));
  png.AddInput("normal", "image", Png("normal.png", 16, 16));
  png.AddInput("model", "model", Path("png.glb"));
  ASSERT_TRUE(Run("estimate.fps", png).ok());
  Expected<Table> png_table = ReadTable(png.outputs_.at("table"));
  ASSERT_TRUE(png_table.ok());
  EXPECT_EQ(TableNumber(png_table->get(0, "texture_bytes")), kQuadTextureBytes);
  EXPECT_EQ(png.meta_.at("table").at("texture_format"), "profile");

  // A model that is not a glb is an error naming the input and file.
  FakeContext bad(dir_ / "bad", {{"device", Device("tiny.yaml", 0)}});
  bad.AddInput("mesh", "mesh", QuadMesh());
  bad.AddInput("model", "model", Png("not_a_model.png", 4, 4));
  const Status bad_status = Run("estimate.fps", bad);
  EXPECT_EQ(bad_status.code(), Status::Code::kCorrupt);
  EXPECT_THAT(bad_status.message(), HasSubstr("estimate.fps: input 'model'"));
  EXPECT_THAT(bad_status.message(), HasSubstr("not_a_model.png"));
}

TEST_F(FpsStageTest, OneByteOverBudgetDoesNotFit) {
  FakeContext ctx(dir_, {{"device", Device("tiny.yaml", kQuadTextureBytes - 1)}});
  ctx.AddInput("mesh", "mesh", QuadMesh());
  ctx.AddInput("color", "image", Png("color.png", 64, 32));
  ctx.AddInput("normal", "image", Png("normal.png", 16, 16));
  ASSERT_TRUE(Run("estimate.fps", ctx).ok());
  Expected<Table> table = ReadTable(ctx.outputs_.at("table"));
  ASSERT_TRUE(table.ok());
  EXPECT_EQ(std::get<bool>(table->get(0, "fits_texture_budget")), false);
}

TEST_F(FpsStageTest, ReadsExrSizeAndWorksWithoutMaps) {
  const std::string exr = Path("normal.exr");
  ASSERT_TRUE(WriteExr(exr, Image::Make(20, 10, 3, Image::PixelType::kF32)).ok());
  FakeContext ctx(dir_, {{"device", Device("tiny.yaml", 0)}});
  ctx.AddInput("mesh", "mesh", QuadMesh());
  ctx.AddInput("normal", "image", exr);
  ASSERT_TRUE(Run("estimate.fps", ctx).ok());
  Expected<Table> table = ReadTable(ctx.outputs_.at("table"));
  ASSERT_TRUE(table.ok());
  EXPECT_EQ(TableNumber(table->get(0, "texture_width")), 20);
  EXPECT_EQ(TableNumber(table->get(0, "texture_height")), 10);
  // 20x10, 10x5, 5x2, 2x1, 1x1.
  EXPECT_EQ(TableNumber(table->get(0, "texture_bytes")), 4 * (200 + 50 + 10 + 2 + 1));

  FakeContext bare(dir_ / "bare", {{"device", Device("tiny.yaml", 0)}});
  bare.AddInput("mesh", "mesh", QuadMesh());
  ASSERT_TRUE(Run("estimate.fps", bare).ok());
  Expected<Table> bare_table = ReadTable(bare.outputs_.at("table"));
  ASSERT_TRUE(bare_table.ok());
  EXPECT_EQ(TableNumber(bare_table->get(0, "texture_bytes")), 0);
  EXPECT_EQ(TableNumber(bare_table->get(0, "texture_width")), 0);
  EXPECT_EQ(std::get<bool>(bare_table->get(0, "fits_texture_budget")), true);
}

TEST_F(FpsStageTest, BadDeviceFileAndBadImageFailWithPlace) {
  const std::string bad = Path("bad.yaml");
  std::ofstream(bad) << "name: x\ntriangles_per_s: 0\nrefresh_hz: 60\ntexture_budget_bytes: 1\n";
  FakeContext ctx(dir_, {{"device", bad}});
  ctx.AddInput("mesh", "mesh", QuadMesh());
  Status status = Run("estimate.fps", ctx);
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(status.message(), HasSubstr("estimate.fps: " + bad + ":2:18: 'triangles_per_s' must be > 0"));

  FakeContext missing(dir_, {{"device", Path("nope.yaml")}});
  missing.AddInput("mesh", "mesh", QuadMesh());
  status = Run("estimate.fps", missing);
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(status.message(), HasSubstr(Path("nope.yaml")));

  const std::string text = Path("color.png");
  std::ofstream(text) << "not an image";
  FakeContext not_image(dir_, {{"device", Device("tiny.yaml", 0)}});
  not_image.AddInput("mesh", "mesh", QuadMesh());
  not_image.AddInput("color", "image", text);
  status = Run("estimate.fps", not_image);
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(status.message(), HasSubstr("neither PNG nor OpenEXR"));

  const std::string truncated = Path("short.png");
  std::ofstream(truncated, std::ios::binary) << "\x89PNG\r\n\x1a\n";
  FakeContext short_png(dir_, {{"device", Device("tiny.yaml", 0)}});
  short_png.AddInput("mesh", "mesh", QuadMesh());
  short_png.AddInput("color", "image", truncated);
  status = Run("estimate.fps", short_png);
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(status.message(), HasSubstr("truncated PNG"));
}

}  // namespace
}  // namespace pb
