// Runs bake.vertex_colors and bake.from_points through a fake StageContext
// (no engine, no child processes): files go to a temporary directory.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "stages/builtin.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/io/ply.h"
#include "stages/stage_test_util.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

class BakeStagesTest : public StageTest {
 protected:
  void SetUp() override {
    StageTest::SetUp();
    RegisterBuiltinStages(registry_);
  }

  // The unit square at z = 0 around a georeferenced origin, uv = xy.
  static Mesh Square() {
    Mesh mesh;
    mesh.origin = {350000.0, 5600000.0, 120.0};
    mesh.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    mesh.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
    mesh.colors = {200, 0, 0, 0, 200, 0, 0, 0, 200, 200, 200, 200};
    mesh.indices = {0, 1, 2, 0, 2, 3};
    return mesh;
  }

  // A 64 x 64 grid of points 1 mm above the square, white on the left half
  // and black on the right, normals up; same origin as Square().
  static PointCloud Points() {
    PointCloud cloud;
    cloud.origin = {350000.0, 5600000.0, 120.0};
    for (int j = 0; j < 64; ++j) {
      for (int i = 0; i < 64; ++i) {
        cloud.positions.insert(cloud.positions.end(), {(i + 0.5f) / 64, (j + 0.5f) / 64, 0.001f});
        const uint8_t gray = i < 32 ? 255 : 0;
        cloud.colors.insert(cloud.colors.end(), {gray, gray, gray});
        cloud.normals.insert(cloud.normals.end(), {0, 0, 1});
      }
    }
    return cloud;
  }
};

TEST_F(BakeStagesTest, SchemasAreWellFormed) {
  for (const char* id : {"bake.vertex_colors", "bake.from_points"}) {
    const StageType* type = registry_.Find(id);
    ASSERT_NE(type, nullptr) << id;
    const nlohmann::json schema = CheckedSchema(*type, /*defaults=*/true);
    EXPECT_EQ(schema["properties"]["size"]["default"], 4096);
    EXPECT_EQ(schema["properties"]["gutter"]["default"], 12);
    ASSERT_EQ(type->outputs.size(), 3u);
  }
  const nlohmann::json schema =
      nlohmann::json::parse(registry_.Find("bake.from_points")->params_schema);
  EXPECT_EQ(schema["properties"]["interpolation"]["default"], "delaunay");
  EXPECT_EQ(schema["properties"]["max_distance"]["default"], 4);
  EXPECT_EQ(schema["properties"]["neighbors"]["default"], true);
}

TEST_F(BakeStagesTest, VertexColorsWritesMeshWithTangentsAndBothMaps) {
  FakeContext ctx(dir_, {{"size", 32}, {"gutter", 2}, {"normal_format", "png"}});
  ctx.AddInput("mesh", "mesh", WriteInputMesh("mesh", Square()), {{"faces", 2}, {"uv", {{"charts", 1}}}});
  const Status status = Run("bake.vertex_colors", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  auto mesh = ReadPlyMesh(ctx.files_.at("mesh/mesh.ply"));
  ASSERT_TRUE(mesh.ok());
  EXPECT_TRUE(mesh->mesh.has_tangents());
  EXPECT_EQ(mesh->mesh.origin, Square().origin);
  auto color = ReadPng(ctx.files_.at("color/color.png"));
  auto normal = ReadPng(ctx.files_.at("normal/normal.png"));
  ASSERT_TRUE(color.ok() && normal.ok());
  EXPECT_EQ(color->width, 32);
  EXPECT_EQ(normal->at_u8(5, 5, 2), 255);
  EXPECT_EQ(ctx.counters_["covered_texels"], 32 * 32);
  // The mesh meta keeps what came before and says what the bake did.
  EXPECT_EQ(ctx.meta_["mesh"]["uv"]["charts"], 1);
  EXPECT_EQ(ctx.meta_["mesh"]["has_tangents"], true);
  EXPECT_EQ(ctx.meta_["mesh"]["bake"]["stage"], "bake.vertex_colors");
  EXPECT_EQ(ctx.meta_["normal"]["space"], "tangent");
}

TEST_F(BakeStagesTest, FromPointsBakesThePointsAndWritesExrOnRequest) {
  FakeContext ctx(dir_, {{"size", 32},
                         {"gutter", 0},
                         {"normal_format", "exr"},
                         {"interpolation", "delaunay"},
                         {"max_distance", 4.0},
                         {"max_angle_deg", 90.0},
                         {"idw_neighbors", 4},
                         {"neighbors", true},
                         {"splat_sigma", 1.0}});
  ctx.AddInput("mesh", "mesh", WriteInputMesh("mesh", Square()));
  ctx.AddInput("points", "points", WriteInputPoints("points", Points()), {{"spacing_m", 1.0 / 64}});
  const Status status = Run("bake.from_points", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  auto color = ReadPng(ctx.files_.at("color/color.png"));
  ASSERT_TRUE(color.ok());
  EXPECT_EQ(color->at_u8(4, 16, 0), 255);   // left half white
  EXPECT_EQ(color->at_u8(27, 16, 0), 0);    // right half black
  auto normal = ReadExr(ctx.files_.at("normal/normal.exr"));
  ASSERT_TRUE(normal.ok()) << normal.status().message();
  EXPECT_NEAR(normal->at_f32(10, 10, 2), 1.0f, 1e-6);
  EXPECT_EQ(ctx.counters_["points"], 64 * 64);
  EXPECT_EQ(ctx.counters_["points_assigned"], 64 * 64);
  // Each of the two faces borrows the other's points near their diagonal.
  EXPECT_GT(ctx.counters_["points_borrowed"], 0);
  EXPECT_EQ(ctx.meta_["color"]["bake"]["neighbors"], true);
  EXPECT_TRUE(ctx.warnings_.empty());
  EXPECT_EQ(ctx.meta_["color"]["bake"]["spacing_source"], "meta");
  EXPECT_NEAR(ctx.meta_["color"]["bake"]["max_distance_m"].get<double>(), 4.0 / 64, 1e-12);
}

// Points that do not belong to the mesh: the maps come from the vertex
// colors, and the stage says so through the warning channel.
TEST_F(BakeStagesTest, FromPointsWarnsWhenNoPointReachesTheMesh) {
  PointCloud far = Points();
  for (size_t i = 2; i < far.positions.size(); i += 3) far.positions[i] += 1.0f;  // 1 m above
  FakeContext ctx(dir_, {{"size", 16},
                         {"gutter", 0},
                         {"normal_format", "png"},
                         {"interpolation", "nearest"},
                         {"max_distance", 4.0},
                         {"max_angle_deg", 90.0},
                         {"idw_neighbors", 4},
                         {"neighbors", true},
                         {"splat_sigma", 1.0}});
  ctx.AddInput("mesh", "mesh", WriteInputMesh("mesh", Square()));
  ctx.AddInput("points", "points", WriteInputPoints("points", far), {{"spacing_m", 1.0 / 64}});
  ASSERT_TRUE(Run("bake.from_points", ctx).ok());
  EXPECT_EQ(ctx.counters_["points_assigned"], 0);
  ASSERT_EQ(ctx.warnings_.size(), 1u);
  EXPECT_THAT(ctx.warnings_[0],
              HasSubstr("no point lies within 62.5 mm and 90 degrees of the mesh"));
}

TEST_F(BakeStagesTest, FromPointsMeasuresSpacingWhenTheMetaHasNone) {
  FakeContext ctx(dir_, {{"size", 16}, {"gutter", 0}, {"normal_format", "png"},
                         {"interpolation", "nearest"}, {"max_distance", 4.0},
                         {"max_angle_deg", 90.0}, {"idw_neighbors", 4}, {"neighbors", false},
                         {"splat_sigma", 1.0}});
  ctx.AddInput("mesh", "mesh", WriteInputMesh("mesh", Square()));
  ctx.AddInput("points", "points", WriteInputPoints("points", Points()));
  ASSERT_TRUE(Run("bake.from_points", ctx).ok());
  EXPECT_EQ(ctx.meta_["color"]["bake"]["spacing_source"], "measured");
  EXPECT_EQ(ctx.counters_["points_borrowed"], 0);  // neighbors: false
  EXPECT_NEAR(ctx.meta_["color"]["bake"]["spacing_m"].get<double>(), 1.0 / 64, 1e-4);
}

TEST_F(BakeStagesTest, ErrorsNameTheStageAndFile) {
  {
    FakeContext ctx(dir_, {{"size", 16}});
    ctx.AddInput("mesh", "mesh", WriteInputMesh("mesh", Square()));
    const Status status = Run("bake.from_points", ctx);
    EXPECT_FALSE(status.ok());
    EXPECT_THAT(status.message(), HasSubstr("bake.from_points"));
  }
  {
    Mesh no_uvs = Square();
    no_uvs.uvs.clear();
    FakeContext ctx(dir_, {{"size", 16}});
    const std::string path = WriteInputMesh("mesh", no_uvs);
    ctx.AddInput("mesh", "mesh", path);
    const Status status = Run("bake.vertex_colors", ctx);
    EXPECT_FALSE(status.ok());
    EXPECT_THAT(status.message(), HasSubstr("no uvs"));
    EXPECT_THAT(status.message(), HasSubstr(path));
  }
  {
    PointCloud gray = Points();
    gray.colors.clear();
    FakeContext ctx(dir_, {{"size", 16}});
    ctx.AddInput("mesh", "mesh", WriteInputMesh("mesh", Square()));
    const std::string path = WriteInputPoints("points", gray);
    ctx.AddInput("points", "points", path);
    const Status status = Run("bake.from_points", ctx);
    EXPECT_FALSE(status.ok());
    EXPECT_THAT(status.message(), HasSubstr("colored"));
    EXPECT_THAT(status.message(), HasSubstr(path));
  }
}

}  // namespace
}  // namespace pb
