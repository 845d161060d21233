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

TEST_F(MeshMetricsStagesTest, GeometrySchemaAndPorts) {
  const StageType* type = registry_.Find("metrics.geometry");
  ASSERT_NE(type, nullptr);
  const nlohmann::json schema = CheckedSchema(*type, true);
  EXPECT_EQ(schema["properties"]["spacing_factor"]["default"], 3);
  EXPECT_EQ(schema["properties"]["k"]["default"], 8);
  ASSERT_EQ(type->inputs.size(), 3u);
  EXPECT_TRUE(type->inputs[1].optional);
  EXPECT_EQ(type->inputs[2].name, "points");
  EXPECT_TRUE(type->inputs[2].optional);
  EXPECT_EQ(type->version, 9);  // 9: points another station saw through are strays
  ASSERT_EQ(type->outputs.size(), 2u);
  EXPECT_EQ(type->outputs[1].name, "errors");
}

TEST_F(MeshMetricsStagesTest, GeometryAgainstTheScanWithoutTruth) {
  // A 1 m square of 2 x 10 x 10 faces; the scan covers its left half on a
  // 1 cm grid, plus 51 points half a meter above (missing from the mesh).
  Mesh mesh;
  for (int j = 0; j <= 10; ++j)
    for (int i = 0; i <= 10; ++i) mesh.positions.insert(mesh.positions.end(), {i / 10.0f, j / 10.0f, 0.0f});
  for (uint32_t j = 0; j < 10; ++j)
    for (uint32_t i = 0; i < 10; ++i) {
      const uint32_t a = j * 11 + i;
      mesh.indices.insert(mesh.indices.end(), {a, a + 1, a + 12, a, a + 12, a + 11});
    }
  PointCloud scan;
  for (int j = 0; j <= 100; ++j)
    for (int i = 0; i <= 30; ++i) scan.positions.insert(scan.positions.end(), {i * 0.01f, j * 0.01f, 0.0f});
  for (int j = 0; j <= 50; ++j) scan.positions.insert(scan.positions.end(), {0.1f, j * 0.01f, 0.5f});
  FakeContext ctx(dir_, {{"samples", 50000}, {"k", 4}});
  ctx.AddInput("mesh", "mesh", WriteInputMesh("grid", mesh));
  ctx.AddInput("points", "points", WriteInputPoints("scan", scan));
  const Status status = Run("metrics.geometry", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  Expected<Table> table = ReadTable(ctx.outputs_.at("table"));
  ASSERT_TRUE(table.ok()) << table.status().message();
  ASSERT_EQ(table->rows.size(), 2u);
  EXPECT_EQ(std::get<std::string>(table->get(0, "direction")), "mesh_to_scan");
  EXPECT_EQ(std::get<std::string>(table->get(1, "direction")), "scan_to_mesh");
  // Mean edge 0.114 m > 3 spacings: seen up to x = 0.3 + 0.114.
  EXPECT_NEAR(TableNumber(table->get(0, "beyond_fraction")), 1 - 0.414, 0.01);
  EXPECT_DOUBLE_EQ(TableNumber(table->get(1, "beyond_fraction")), 51.0 / (101 * 31 + 51));
  EXPECT_DOUBLE_EQ(TableNumber(table->get(0, "boundary_edges_per_1000_faces")), 40.0 / 200 * 1000);
  EXPECT_EQ(ctx.counters_.count("invented_area_fraction"), 1u);
  EXPECT_TRUE(ctx.phases_.count("scan"));

  FakeContext neither(dir_, nlohmann::json::object());
  neither.AddInput("mesh", "mesh", WriteInputMesh("grid2", mesh));
  const Status none = Run("metrics.geometry", neither);
  EXPECT_FALSE(none.ok());
  EXPECT_NE(none.message().find("'points'"), std::string::npos) << none.message();
}

}  // namespace
}  // namespace pb
