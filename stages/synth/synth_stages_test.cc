// Runs synth.scan through a fake StageContext (no engine): files go to a
// temporary directory.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "stages/geometry/io/ply.h"
#include "stages/geometry/synth/scene.h"
#include "stages/stage_test_util.h"
#include "stages/builtin.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

class SynthStagesTest : public StageTest {
 protected:
  void SetUp() override {
    StageTest::SetUp();
    RegisterBuiltinStages(registry_);
  }
};

TEST_F(SynthStagesTest, RegistersSynthScan) {
  const StageType* type = registry_.Find("synth.scan");
  ASSERT_NE(type, nullptr);
  EXPECT_EQ(type->version, 1);
  EXPECT_TRUE(type->inputs.empty());
  ASSERT_EQ(type->outputs.size(), 2u);
  EXPECT_EQ(type->outputs[0].name, "points");
  EXPECT_EQ(type->outputs[0].type, "points");
  EXPECT_EQ(type->outputs[1].name, "truth");
  EXPECT_EQ(type->outputs[1].type, "mesh");
  const nlohmann::json schema = CheckedSchema(*type);
  EXPECT_EQ(schema["properties"]["preset"]["enum"], nlohmann::json({"room", "tower", "vault", "facade", "sculpture"}));
  EXPECT_EQ(schema["properties"]["points"]["default"], 2000000);
  EXPECT_EQ(schema["properties"]["points"]["minimum"], 1000);
  EXPECT_EQ(schema["properties"]["stations"]["maximum"], 16);
  EXPECT_EQ(schema["properties"]["truth_cell_mm"]["default"], 10);
}

TEST_F(SynthStagesTest, ScansARoomWithTruth) {
  FakeContext ctx(dir_, {{"preset", "room"}, {"points", 100000}, {"seed", 5}, {"stations", 2},
                         {"truth_cell_mm", 25}},
                  /*threads=*/2);
  const Status status = Run("synth.scan", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.phases_, (std::set<std::string>{"scan", "truth", "io"}));
  EXPECT_DOUBLE_EQ(ctx.last_progress_, 1.0);
  EXPECT_NEAR(ctx.counters_["points"], 100000, 10000);
  EXPECT_EQ(ctx.counters_["stations"], 2);
  EXPECT_GT(ctx.counters_["truth_faces"], 100000);

  auto points = ReadPlyPoints(ctx.files_["points/points.ply"]);
  ASSERT_TRUE(points.ok()) << points.status().message();
  EXPECT_EQ(static_cast<double>(points->points.size()), ctx.counters_["points"]);
  EXPECT_TRUE(points->points.has_colors());
  EXPECT_EQ(ctx.meta_["points"]["stations"], 2);
  EXPECT_EQ(ctx.meta_["points"]["preset"], "room");
  EXPECT_GT(ctx.meta_["points"]["spacing_m"].get<double>(), 0.002);
  EXPECT_LT(ctx.meta_["points"]["spacing_m"].get<double>(), 0.05);

  auto mesh = ReadPlyMesh(ctx.files_["truth/mesh.ply"]);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_EQ(static_cast<double>(mesh->mesh.face_count()), ctx.counters_["truth_faces"]);
  EXPECT_TRUE(mesh->mesh.has_colors());
  EXPECT_TRUE(mesh->mesh.has_normals());
  EXPECT_EQ(ctx.meta_["truth"]["kind"], "synthetic_truth");
  auto scene = ReadSynthScene(ctx.files_["truth/scene.json"]);
  ASSERT_TRUE(scene.ok()) << scene.status().message();
  EXPECT_EQ(scene->preset, "room");
  EXPECT_EQ(scene->seed, 5u);
  // The scene file reproduces the ground truth the points were made from.
  size_t far = 0;
  const PointCloud& cloud = points->points;
  for (size_t i = 0; i < cloud.size(); i += 7) {
    const Vec3 p = {cloud.positions[3 * i], cloud.positions[3 * i + 1], cloud.positions[3 * i + 2]};
    if (std::abs(SampleSurface(scene.value(), p).distance_m) > 0.01) ++far;
  }
  EXPECT_LE(far, 2u);
}

TEST_F(SynthStagesTest, ScansTheOpenFacadeFromOneStation) {
  FakeContext ctx(dir_, {{"preset", "facade"}, {"points", 40000}, {"stations", 1}, {"truth_cell_mm", 40}},
                  /*threads=*/2);
  const Status status = Run("synth.scan", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["stations"], 1);
  EXPECT_EQ(ctx.meta_["points"]["preset"], "facade");
  auto points = ReadPlyPoints(ctx.files_["points/points.ply"]);
  ASSERT_TRUE(points.ok()) << points.status().message();
  ASSERT_EQ(points->points.stations.size(), 1u);
  auto scene = ReadSynthScene(ctx.files_["truth/scene.json"]);
  ASSERT_TRUE(scene.ok()) << scene.status().message();
  EXPECT_EQ(scene->preset, "facade");
  ASSERT_NE(scene->objects, nullptr);
  size_t far = 0;
  const PointCloud& cloud = points->points;
  for (size_t i = 0; i < cloud.size(); i += 7) {
    const Vec3 p = {cloud.positions[3 * i], cloud.positions[3 * i + 1], cloud.positions[3 * i + 2]};
    if (std::abs(SampleSurface(scene.value(), p).distance_m) > 0.01) ++far;
  }
  EXPECT_LE(far, 2u);
  FakeContext sized(dir_ / "sized", {{"preset", "sculpture"}, {"points", 5000}, {"size_m", {2, 2, 2}}});
  EXPECT_THAT(Run("synth.scan", sized).message(), HasSubstr("preset 'sculpture' has a fixed size"));
  FakeContext crowded(dir_ / "crowded", {{"preset", "facade"}, {"points", 5000}, {"stations", 8}});
  EXPECT_THAT(Run("synth.scan", crowded).message(), HasSubstr("at most 5 stations"));
}

TEST_F(SynthStagesTest, SameParametersSameBytes) {
  const nlohmann::json params = {{"preset", "vault"}, {"points", 20000}, {"truth_cell_mm", 50}};
  FakeContext a(dir_ / "a", params, /*threads=*/2), b(dir_ / "b", params, /*threads=*/2);
  ASSERT_TRUE(Run("synth.scan", a).ok());
  ASSERT_TRUE(Run("synth.scan", b).ok());
  for (const char* file : {"points/points.ply", "truth/mesh.ply", "truth/scene.json"}) {
    std::ifstream fa(a.files_[file], std::ios::binary), fb(b.files_[file], std::ios::binary);
    const std::string ca((std::istreambuf_iterator<char>(fa)), {}), cb((std::istreambuf_iterator<char>(fb)), {});
    EXPECT_FALSE(ca.empty()) << file;
    EXPECT_EQ(ca, cb) << file;
  }
}

TEST_F(SynthStagesTest, RejectsBadParameters) {
  FakeContext tower(dir_, {{"preset", "tower"}, {"points", 5000}, {"size_m", {6, 4, 6}}});
  EXPECT_THAT(Run("synth.scan", tower).message(), HasSubstr("must be equal"));
  FakeContext few(dir_, {{"points", 10}});
  EXPECT_THAT(Run("synth.scan", few).message(), HasSubstr("points >= 1000"));
  FakeContext size(dir_, {{"points", 5000}, {"size_m", {6, 4}}});
  EXPECT_THAT(Run("synth.scan", size).message(),
              HasSubstr("'size_m' must be [width, depth, height]"));
}

}  // namespace
}  // namespace pb
