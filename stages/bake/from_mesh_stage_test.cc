// Runs bake.from_mesh through a fake StageContext (no engine, no child
// processes): files go to a temporary directory.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <string>

#include "stages/builtin.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/io/ply.h"
#include "stages/stage_test_util.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

class FromMeshStageTest : public StageTest {
 protected:
  void SetUp() override {
    StageTest::SetUp();
    RegisterBuiltinStages(registry_);
  }

  // The unit square at z = 0, two triangles, uvs = (x, y), gray vertex
  // colors, stored around a georeferenced origin.
  static Mesh Low() {
    Mesh mesh;
    mesh.origin = {350000.0, 5600000.0, 120.0};
    mesh.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    mesh.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
    mesh.colors = {90, 90, 90, 90, 90, 90, 90, 90, 90, 90, 90, 90};
    mesh.indices = {0, 1, 2, 0, 2, 3};
    return mesh;
  }

  // 1/64 m above Low(): red where x < 0.5, blue where x > 0.5 (two strips
  // of 2 x 8 triangles meeting at x = 0.5), reaching past the square;
  // stored around another origin (positions shifted to match).
  static Mesh High() {
    Mesh mesh;
    mesh.origin = {350010.0, 5599990.0, 121.0};
    const double shift[3] = {-10.0, 10.0, -1.0};  // Low().origin - origin
    for (int strip = 0; strip < 2; ++strip) {
      const uint32_t base = uint32_t(mesh.vertex_count());
      const double x0 = strip == 0 ? -0.25 : 0.5, x1 = strip == 0 ? 0.5 : 1.25;
      for (int j = 0; j <= 4; ++j) {
        for (int i = 0; i <= 1; ++i) {
          const double p[3] = {i == 0 ? x0 : x1, -0.25 + 1.5 * j / 4, 1.0 / 64};
          for (int k = 0; k < 3; ++k) mesh.positions.push_back(float(p[k] + shift[k]));
          mesh.colors.insert(mesh.colors.end(),
                             {uint8_t(strip == 0 ? 255 : 0), 0, uint8_t(strip == 0 ? 0 : 255)});
        }
      }
      for (uint32_t j = 0; j < 4; ++j) {
        const uint32_t a = base + 2 * j, b = a + 1, c = a + 3, d = a + 2;
        mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
      }
    }
    return mesh;
  }
};

TEST_F(FromMeshStageTest, IsWellFormed) {
  const StageType* type = registry_.Find("bake.from_mesh");
  ASSERT_NE(type, nullptr);
  EXPECT_EQ(type->version, 1);
  const nlohmann::json schema = CheckedSchema(*type, /*defaults=*/true);
  for (const char* common : {"size", "gutter", "normal_format"}) {
    EXPECT_TRUE(schema["properties"].contains(common)) << common;
  }
  EXPECT_EQ(schema["properties"]["cage"]["default"], 0.05);
  EXPECT_EQ(schema["properties"]["cage"]["exclusiveMinimum"], 0);
  ASSERT_EQ(type->inputs.size(), 2u);
  EXPECT_EQ(type->inputs[0].name, "mesh");
  EXPECT_EQ(type->inputs[1].name, "source");
  EXPECT_EQ(type->inputs[1].type, "mesh");
  ASSERT_EQ(type->outputs.size(), 3u);
  EXPECT_EQ(type->outputs[0].name, "mesh");
  EXPECT_EQ(type->outputs[1].name, "color");
  EXPECT_EQ(type->outputs[2].name, "normal");
  EXPECT_THAT(type->doc, HasSubstr("texels_hit"));
  EXPECT_THAT(type->doc, HasSubstr("texels_fallback"));
}

TEST_F(FromMeshStageTest, BakesColorNormalAndMeshWithTangents) {
  FakeContext ctx(dir_ / "run", {{"size", 32}, {"gutter", 2}}, 2);
  ctx.AddInput("mesh", "mesh", WriteInputMesh("low", Low()), {{"source", "test"}});
  ctx.AddInput("source", "mesh", WriteInputMesh("high", High()));
  const Status status = Run("bake.from_mesh", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.phases_, (std::set<std::string>{"io", "compute"}));
  EXPECT_DOUBLE_EQ(ctx.last_progress_, 1.0);
  EXPECT_EQ(ctx.counters_["texels_hit"], 32 * 32);
  EXPECT_EQ(ctx.counters_["texels_fallback"], 0);
  EXPECT_EQ(ctx.counters_["covered_texels"], 32 * 32);

  auto mesh = ReadPlyMesh(ctx.outputs_["mesh"]);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_EQ(std::filesystem::path(ctx.outputs_["mesh"]).filename(), "mesh.ply");
  EXPECT_TRUE(mesh->mesh.has_tangents());
  EXPECT_TRUE(mesh->mesh.has_normals());
  EXPECT_TRUE(mesh->mesh.has_uvs());
  EXPECT_EQ(mesh->mesh.origin, Low().origin);

  EXPECT_EQ(std::filesystem::path(ctx.outputs_["color"]).filename(), "color.png");
  auto color = ReadPng(ctx.outputs_["color"]);
  ASSERT_TRUE(color.ok()) << color.status().message();
  ASSERT_EQ(color->width, 32);
  ASSERT_EQ(color->channels, 3);
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 32; ++x) {
      const std::array<int, 3> expected =
          x < 16 ? std::array<int, 3>{255, 0, 0} : std::array<int, 3>{0, 0, 255};
      for (int k = 0; k < 3; ++k) ASSERT_EQ(color->at_u8(x, y, k), expected[k]) << x << "," << y;
    }
  }
  EXPECT_EQ(std::filesystem::path(ctx.outputs_["normal"]).filename(), "normal.png");
  auto normal = ReadPng(ctx.outputs_["normal"]);
  ASSERT_TRUE(normal.ok()) << normal.status().message();
  EXPECT_EQ(normal->at_u8(7, 9, 0), 128);
  EXPECT_EQ(normal->at_u8(7, 9, 1), 128);
  EXPECT_EQ(normal->at_u8(7, 9, 2), 255);

  const nlohmann::json& bake = ctx.meta_["mesh"]["bake"];
  EXPECT_EQ(ctx.meta_["mesh"]["source"], "test");
  EXPECT_EQ(bake["stage"], "bake.from_mesh");
  EXPECT_EQ(bake["cage_m"], 0.05);
  EXPECT_EQ(bake["texels_hit"], 32 * 32);
  EXPECT_EQ(bake["texels_fallback"], 0);
  EXPECT_NEAR(bake["mean_hit_distance_m"].get<double>(), 1.0 / 64, 1e-6);
}

TEST_F(FromMeshStageTest, ExrNormalsAndASmallCage) {
  // A 1 cm cage does not reach the sheet 1.56 cm away: all fallback, the
  // low mesh's gray, flat float normals.
  FakeContext ctx(dir_ / "run", {{"size", 16}, {"normal_format", "exr"}, {"cage", 0.01}});
  ctx.AddInput("mesh", "mesh", WriteInputMesh("low", Low()));
  ctx.AddInput("source", "mesh", WriteInputMesh("high", High()));
  const Status status = Run("bake.from_mesh", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["texels_hit"], 0);
  EXPECT_EQ(ctx.counters_["texels_fallback"], 16 * 16);
  EXPECT_EQ(ctx.meta_["mesh"]["bake"]["cage_m"], 0.01);
  EXPECT_EQ(std::filesystem::path(ctx.outputs_["normal"]).filename(), "normal.exr");
  auto normal = ReadExr(ctx.outputs_["normal"]);
  ASSERT_TRUE(normal.ok()) << normal.status().message();
  EXPECT_FLOAT_EQ(normal->at_f32(3, 4, 0), 0.0f);
  EXPECT_FLOAT_EQ(normal->at_f32(3, 4, 2), 1.0f);
  auto color = ReadPng(ctx.outputs_["color"]);
  ASSERT_TRUE(color.ok()) << color.status().message();
  EXPECT_EQ(color->at_u8(12, 2, 0), 90);
  EXPECT_EQ(color->at_u8(12, 2, 2), 90);
}

TEST_F(FromMeshStageTest, ClearErrors) {
  const std::string low = WriteInputMesh("low", Low());
  FakeContext no_source(dir_ / "a", {{"size", 16}});
  no_source.AddInput("mesh", "mesh", low);
  const Status missing = Run("bake.from_mesh", no_source);
  ASSERT_FALSE(missing.ok());
  EXPECT_THAT(missing.message(), HasSubstr("bake.from_mesh"));
  EXPECT_THAT(missing.message(), HasSubstr("source"));

  Mesh uncolored = High();
  uncolored.colors.clear();
  FakeContext no_colors(dir_ / "b", {{"size", 16}});
  no_colors.AddInput("mesh", "mesh", low);
  no_colors.AddInput("source", "mesh", WriteInputMesh("uncolored", uncolored));
  const Status colors = Run("bake.from_mesh", no_colors);
  EXPECT_EQ(colors.code(), Status::Code::kInvalid);
  EXPECT_THAT(colors.message(), HasSubstr("bake.from_mesh"));
  EXPECT_THAT(colors.message(), HasSubstr("no vertex colors"));

  FakeContext cage(dir_ / "c", {{"size", 16}, {"cage", 0}});
  cage.AddInput("mesh", "mesh", low);
  cage.AddInput("source", "mesh", WriteInputMesh("high", High()));
  EXPECT_THAT(Run("bake.from_mesh", cage).message(), HasSubstr("'cage' must be > 0"));

  Mesh no_uvs = Low();
  no_uvs.uvs.clear();
  FakeContext uvs(dir_ / "d", {{"size", 16}});
  uvs.AddInput("mesh", "mesh", WriteInputMesh("no_uvs", no_uvs));
  uvs.AddInput("source", "mesh", WriteInputMesh("high", High()));
  const Status uv_status = Run("bake.from_mesh", uvs);
  EXPECT_EQ(uv_status.code(), Status::Code::kInvalid);
  EXPECT_THAT(uv_status.message(), HasSubstr("uvs"));
}

}  // namespace
}  // namespace pb
