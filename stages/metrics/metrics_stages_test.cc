// Stage tests for mesh.clean and metrics.geometry through the fake context.
#include <gtest/gtest.h>

#include <fstream>

#include "stages/geometry/mesh/clean.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/synth/scene.h"
#include "stages/geometry/core/table.h"
#include "stages/builtin.h"
#include "stages/stage_test_util.h"

namespace pb {
namespace {

class MeshMetricsStagesTest : public StageTest {
 protected:
  void SetUp() override {
    StageTest::SetUp();
    RegisterBuiltinStages(registry_);
  }
  // The synth truth artifact: mesh.ply + scene.json in one directory.
  ArtifactView Truth(double cell_m, const std::string& name) {
    Expected<SynthScene> scene = MakeSynthScene("room", 1, {});
    EXPECT_TRUE(scene.ok());
    const std::filesystem::path d = dir_ / name;
    std::filesystem::create_directories(d);
    EXPECT_TRUE(WritePlyMesh((d / "mesh.ply").string(), SynthTruthMesh(*scene, cell_m)).ok());
    std::ofstream((d / "scene.json").string()) << ToJson(*scene).dump(2);
    ArtifactView view;
    view.type = "mesh";
    view.files = {{"mesh.ply", (d / "mesh.ply").string()}, {"scene.json", (d / "scene.json").string()}};
    return view;
  }
};

TEST_F(MeshMetricsStagesTest, GeometryOfTruthAgainstItselfIsTiny) {
  const ArtifactView truth = Truth(0.1, "truth");
  FakeContext ctx(dir_, {{"samples", 20000}, {"seed", 1}});
  ctx.AddInput("mesh", "mesh", truth.files.at("mesh.ply"));
  ctx.AddInput("truth", "mesh", truth.files);
  ASSERT_TRUE(Run("metrics.geometry", ctx).ok());
  Expected<Table> table = ReadTable(ctx.outputs_.at("table"));
  ASSERT_TRUE(table.ok()) << table.status().message();
  ASSERT_EQ(table->rows.size(), 3u);
  EXPECT_EQ(std::get<std::string>(table->get(0, "direction")), "mesh_to_truth");
  EXPECT_EQ(std::get<std::string>(table->get(0, "truth")), "analytic");
  EXPECT_LT(TableNumber(table->get(0, "mean_m")), 0.005);
  EXPECT_LT(TableNumber(table->get(1, "hausdorff_m")), 1e-5);
  EXPECT_EQ(TableNumber(table->get(1, "samples")), 20000);
  EXPECT_EQ(ctx.counters_.at("samples"), 20000);
  EXPECT_TRUE(ctx.phases_.count("io") && ctx.phases_.count("compute"));
  EXPECT_EQ(ctx.last_progress_, 1.0);
}

TEST_F(MeshMetricsStagesTest, CleanStageRemovesDefects) {
  Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 5, 5, 5};
  mesh.indices = {0, 1, 2, 1, 3, 2, 2, 1, 0, 0, 0, 1};
  const std::string path = (dir_ / "in.ply").string();
  ASSERT_TRUE(WritePlyMesh(path, mesh).ok());
  FakeContext ctx(dir_, {{"min_component_faces", 0}});
  ctx.AddInput("mesh", "mesh", path);
  ASSERT_TRUE(Run("mesh.clean", ctx).ok());
  EXPECT_EQ(ctx.counters_.at("duplicate_faces"), 1);
  EXPECT_EQ(ctx.counters_.at("degenerate_faces"), 1);
  EXPECT_EQ(ctx.counters_.at("unreferenced_vertices"), 1);
  EXPECT_EQ(ctx.counters_.at("faces_out"), 2);
  Expected<PlyMesh> out = ReadPlyMesh(ctx.outputs_.at("mesh"));
  ASSERT_TRUE(out.ok());
  EXPECT_EQ(out->mesh.face_count(), 2u);
  EXPECT_EQ(out->mesh.vertex_count(), 4u);
  EXPECT_TRUE(CheckManifold(out->mesh).ok());
  EXPECT_EQ(ctx.meta_.at("mesh").at("faces"), 2);
}

}  // namespace
}  // namespace pb
