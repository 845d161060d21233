// Runs uv.unwrap through a fake StageContext (no engine, no child
// processes): files go to a temporary directory.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "stages/builtin.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/uv/atlas.h"
#include "stages/stage_test_util.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

class UvStagesTest : public StageTest {
 protected:
  void SetUp() override {
    StageTest::SetUp();
    RegisterBuiltinStages(registry_);
  }

  std::string WriteMesh(const std::string& name, const Mesh& mesh) {
    const std::filesystem::path dir = dir_ / "input";
    std::filesystem::create_directories(dir);
    const std::string path = (dir / name).string();
    EXPECT_TRUE(WritePlyMesh(path, mesh).ok());
    return path;
  }

  // A closed unit cube, 12 faces facing out, colors per corner, no normals.
  static Mesh Cube() {
    Mesh mesh;
    mesh.origin = {500.0, 600.0, 7.0};
    for (int i = 0; i < 8; ++i) {
      mesh.positions.insert(mesh.positions.end(),
                            {float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)});
      mesh.colors.insert(mesh.colors.end(), {uint8_t(30 * i), 7, 200});
    }
    // Quads (counter-clockwise seen from outside), two triangles each.
    const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                  {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
      mesh.indices.insert(mesh.indices.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
    }
    return mesh;
  }

  static std::string Slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    return bytes.str();
  }
};

TEST_F(UvStagesTest, UnwrapIsWellFormed) {
  const StageType* type = registry_.Find("uv.unwrap");
  ASSERT_NE(type, nullptr);
  EXPECT_EQ(type->version, 9);
  const nlohmann::json schema = CheckedSchema(*type, /*defaults=*/true);
  EXPECT_EQ(schema["properties"]["method"]["default"], "conformal");
  EXPECT_EQ(schema["properties"]["method"]["enum"],
            nlohmann::json::array({"charts", "conformal", "per_triangle", "auto"}));
  EXPECT_EQ(schema["properties"]["cone_deg"]["default"], 45);
  EXPECT_EQ(schema["properties"]["max_chart_stretch"]["default"], 1.03);
  EXPECT_EQ(schema["properties"]["size"]["default"], 4096);
  EXPECT_EQ(schema["properties"]["size"]["minimum"], 64);
  EXPECT_EQ(schema["properties"]["size"]["maximum"], 16384);
  EXPECT_EQ(schema["properties"]["gutter"]["default"], 4);
  EXPECT_EQ(schema["properties"]["max_angle_deg"]["default"], 66);
  ASSERT_EQ(type->inputs.size(), 1u);
  EXPECT_EQ(type->inputs[0].name, "mesh");
  EXPECT_EQ(type->inputs[0].type, "mesh");
  ASSERT_EQ(type->outputs.size(), 1u);
  EXPECT_EQ(type->outputs[0].name, "mesh");
  EXPECT_EQ(type->outputs[0].type, "mesh");
  EXPECT_THAT(type->doc, HasSubstr("stretch_l2"));
}

TEST_F(UvStagesTest, CubeGetsSixChartsCountersAndMeta) {
  FakeContext ctx(dir_ / "run", {{"size", 256}, {"gutter", 2}});
  ctx.AddInput("mesh", "mesh", WriteMesh("mesh.ply", Cube()), {{"source", "test"}});
  const Status status = Run("uv.unwrap", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.phases_, (std::set<std::string>{"io", "compute"}));
  EXPECT_DOUBLE_EQ(ctx.last_progress_, 1.0);
  EXPECT_EQ(ctx.counters_["charts"], 6);
  EXPECT_NEAR(ctx.counters_["stretch_l2"], 1.0, 1e-4);
  EXPECT_NEAR(ctx.counters_["stretch_linf"], 1.0, 1e-3);
  EXPECT_NEAR(ctx.counters_["seam_length_m"], 12.0, 1e-4);  // every cube edge is cut
  EXPECT_GT(ctx.counters_["coverage"], 0.3);
  EXPECT_EQ(ctx.counters_["vertices_out"], 24);  // 4 corners per face
  auto out = ReadPlyMesh(ctx.outputs_["mesh"]);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(std::filesystem::path(ctx.outputs_["mesh"]).filename(), "mesh.ply");
  ASSERT_TRUE(out->mesh.has_uvs());
  EXPECT_TRUE(out->mesh.has_colors());
  EXPECT_FALSE(out->mesh.has_normals());
  EXPECT_EQ(out->mesh.origin, Cube().origin);
  MeasureOptions measure;
  measure.check_overlaps = true;
  const AtlasReport report = MeasureAtlas(out->mesh, 256, measure);
  EXPECT_EQ(report.overlapping_faces, 0u);
  EXPECT_EQ(report.faces_outside, 0u);
  EXPECT_EQ(report.faces_not_ccw, 0u);
  EXPECT_GE(report.min_chart_gap_texels, 2 - 1e-3);
  const nlohmann::json& meta = ctx.meta_["mesh"];
  EXPECT_EQ(meta["source"], "test");  // input meta passed on
  EXPECT_EQ(meta["faces"], 12);
  EXPECT_EQ(meta["vertices"], 24);
  EXPECT_EQ(meta["has_uvs"], true);
  EXPECT_EQ(meta["uv"]["method"], "conformal");
  EXPECT_EQ(meta["uv"]["cone_deg"], 45);
  EXPECT_EQ(meta["uv"]["max_chart_stretch"], 1.03);
  EXPECT_EQ(meta["uv"]["size"], 256);
  EXPECT_EQ(meta["uv"]["gutter"], 2);
  EXPECT_EQ(meta["uv"]["charts"], 6);
  EXPECT_DOUBLE_EQ(meta["uv"]["coverage"].get<double>(), ctx.counters_["coverage"]);
  EXPECT_DOUBLE_EQ(meta["uv"]["stretch_l2"].get<double>(), ctx.counters_["stretch_l2"]);
  EXPECT_GT(meta["uv"]["texels_per_meter"].get<double>(), 0.0);
}

TEST_F(UvStagesTest, PerTriangleBaseline) {
  FakeContext ctx(dir_ / "run", {{"method", "per_triangle"}, {"size", 64}});
  ctx.AddInput("mesh", "mesh", WriteMesh("mesh.ply", Cube()));
  const Status status = Run("uv.unwrap", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["charts"], 12);
  EXPECT_EQ(ctx.counters_["vertices_out"], 36);
  EXPECT_EQ(ctx.meta_["mesh"]["uv"]["method"], "per_triangle");
}

TEST_F(UvStagesTest, PlanarChartsStayAvailable) {
  FakeContext ctx(dir_ / "run", {{"method", "charts"}, {"size", 256}, {"gutter", 2}});
  ctx.AddInput("mesh", "mesh", WriteMesh("mesh.ply", Cube()));
  const Status status = Run("uv.unwrap", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["charts"], 6);
  EXPECT_EQ(ctx.meta_["mesh"]["uv"]["method"], "charts");
}

// A bumpy sheet of 7,200 faces: many planar charts.
Mesh WavySheet() {
  Mesh wavy;
  const int n = 60;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      wavy.positions.insert(
          wavy.positions.end(),
          {float(i) / n, float(j) / n, 0.1f * float(std::sin(i * 0.5) * std::cos(j * 0.4))});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      wavy.indices.insert(wavy.indices.end(), {a, b, c, a, c, d});
    }
  }
  return wavy;
}

TEST_F(UvStagesTest, AutoIsPlanarChartsOrConformalOnesWhenThoseDoNotFit) {
  // A cube: its six planar charts fit, and auto is charts.
  FakeContext cube(dir_ / "cube", {{"method", "auto"}, {"size", 256}, {"gutter", 2}});
  cube.AddInput("mesh", "mesh", WriteMesh("cube.ply", Cube()));
  Status status = Run("uv.unwrap", cube);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(cube.counters_["charts"], 6);
  EXPECT_EQ(cube.counters_["conformal_fallback"], 0);
  EXPECT_EQ(cube.meta_["mesh"]["uv"]["method"], "charts");
  EXPECT_EQ(cube.meta_["mesh"]["uv"]["method_asked"], "auto");
  EXPECT_TRUE(cube.warnings_.empty());
  // The bumpy sheet's 541 planar charts do not fit 96 texels with a gutter
  // of 4 (17 x 17 cells of 5 texels at the least); its 159 conformal charts
  // do.
  const std::string input = WriteMesh("mesh.ply", WavySheet());
  auto small = [](const char* method) { return nlohmann::json{{"size", 96}, {"gutter", 4}, {"method", method}}; };
  FakeContext planar(dir_ / "planar", small("charts"));
  planar.AddInput("mesh", "mesh", input);
  status = Run("uv.unwrap", planar);
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(status.message(), HasSubstr("do not fit"));
  FakeContext conformal(dir_ / "conformal", small("conformal"));
  conformal.AddInput("mesh", "mesh", input);
  ASSERT_TRUE(Run("uv.unwrap", conformal).ok());
  FakeContext automatic(dir_ / "auto", small("auto"));
  automatic.AddInput("mesh", "mesh", input);
  status = Run("uv.unwrap", automatic);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(automatic.counters_["conformal_fallback"], 1);
  EXPECT_EQ(automatic.meta_["mesh"]["uv"]["method"], "conformal");
  ASSERT_EQ(automatic.warnings_.size(), 1u);
  EXPECT_THAT(automatic.warnings_[0], HasSubstr("do not fit"));
  EXPECT_EQ(Slurp(automatic.outputs_["mesh"]), Slurp(conformal.outputs_["mesh"])) << "the conformal atlas itself";
  // Neither fits: one error that says both.
  FakeContext neither(dir_ / "neither", {{"method", "auto"}, {"size", 64}, {"gutter", 16}});
  neither.AddInput("mesh", "mesh", input);
  status = Run("uv.unwrap", neither);
  EXPECT_EQ(status.code(), Status::Code::kInvalid);
  EXPECT_THAT(status.message(), HasSubstr("planar charts failed"));
  EXPECT_THAT(status.message(), HasSubstr("conformal charts failed too"));
  EXPECT_TRUE(neither.outputs_.empty());
}

TEST_F(UvStagesTest, SameBytesWithOneOrTwoThreads) {
  const std::string input = WriteMesh("mesh.ply", WavySheet());
  for (const char* method : {"charts", "conformal"}) {
    SCOPED_TRACE(method);
    FakeContext one(dir_ / (std::string("one_") + method), {{"size", 1024}, {"method", method}}, 1);
    FakeContext two(dir_ / (std::string("two_") + method), {{"size", 1024}, {"method", method}}, 2);
    one.AddInput("mesh", "mesh", input);
    two.AddInput("mesh", "mesh", input);
    ASSERT_TRUE(Run("uv.unwrap", one).ok());
    ASSERT_TRUE(Run("uv.unwrap", two).ok());
    EXPECT_GT(one.counters_["charts"], 1);
    EXPECT_EQ(Slurp(one.outputs_["mesh"]), Slurp(two.outputs_["mesh"]));
    EXPECT_EQ(one.counters_, two.counters_);
  }
}

TEST_F(UvStagesTest, NonManifoldInputIsUnwrappedWithSeams) {
  // Three faces on one edge, which mesh.clean would reduce to two: the
  // unwrapper cuts there instead of failing.
  Mesh fin;
  fin.positions = {0, 0, 0, 1, 0, 0, 0.5f, 1, 0, 0.5f, -1, 0, 0.5f, 0, 1};
  fin.indices = {0, 1, 2, 1, 0, 3, 1, 0, 4};
  FakeContext ctx(dir_ / "run", {{"size", 128}});
  ctx.AddInput("mesh", "mesh", WriteMesh("mesh.ply", fin));
  const Status status = Run("uv.unwrap", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["charts"], 3);
}

TEST_F(UvStagesTest, ClearErrors) {
  const std::string input = WriteMesh("mesh.ply", Cube());
  FakeContext method(dir_ / "a", {{"method", "lscm"}});
  method.AddInput("mesh", "mesh", input);
  EXPECT_THAT(Run("uv.unwrap", method).message(),
              HasSubstr("'method' must be 'charts', 'conformal', 'per_triangle' or 'auto'"));
  FakeContext size(dir_ / "b", {{"size", 32}});
  size.AddInput("mesh", "mesh", input);
  const Status size_status = Run("uv.unwrap", size);
  EXPECT_EQ(size_status.code(), Status::Code::kInvalid);
  EXPECT_THAT(size_status.message(), HasSubstr("size"));
  FakeContext angle(dir_ / "c", {{"max_angle_deg", 120}});
  angle.AddInput("mesh", "mesh", input);
  EXPECT_THAT(Run("uv.unwrap", angle).message(), HasSubstr("'max_angle_deg' must be in (0, 90)"));
  FakeContext stretch(dir_ / "s", {{"max_stretch", 0.5}});
  stretch.AddInput("mesh", "mesh", input);
  EXPECT_THAT(Run("uv.unwrap", stretch).message(), HasSubstr("'max_stretch' must be >= 1"));
  FakeContext cone(dir_ / "f", {{"cone_deg", 90}});
  cone.AddInput("mesh", "mesh", input);
  EXPECT_THAT(Run("uv.unwrap", cone).message(), HasSubstr("'cone_deg' must be in (0, 90)"));
  FakeContext bound(dir_ / "g", {{"max_chart_stretch", 1.0}});
  bound.AddInput("mesh", "mesh", input);
  EXPECT_THAT(Run("uv.unwrap", bound).message(), HasSubstr("'max_chart_stretch' must be > 1"));
  // 12 faces, one per cell, in 64 texels with a 15-texel gutter: no room.
  FakeContext crowded(dir_ / "d", {{"method", "per_triangle"}, {"size", 64}, {"gutter", 15}});
  crowded.AddInput("mesh", "mesh", input);
  const Status crowded_status = Run("uv.unwrap", crowded);
  EXPECT_EQ(crowded_status.code(), Status::Code::kInvalid);
  EXPECT_THAT(crowded_status.message(), HasSubstr("mesh.ply"));
  EXPECT_THAT(crowded_status.message(), HasSubstr("raise `size`"));
  EXPECT_TRUE(crowded.outputs_.empty());
  FakeContext missing(dir_ / "e", nlohmann::json::object());
  missing.AddInput("mesh", "mesh", (dir_ / "input" / "nope.ply").string());
  EXPECT_FALSE(Run("uv.unwrap", missing).ok());
}

}  // namespace
}  // namespace pb
