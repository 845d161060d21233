// Runs the mesh stages through a fake StageContext (no engine, no child
// processes): files go to a temporary directory.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>

#include "stages/builtin.h"
#include "stages/geometry/core/module.h"
#include "stages/geometry/mesh/poisson_module.h"
#include "stages/geometry/io/ply.h"
#include "stages/stage_test_util.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

class MeshStagesTest : public StageTest {
 protected:
  void SetUp() override {
    StageTest::SetUp();
    RegisterBuiltinStages(registry_);
  }

  // A 20 x 20 quad grid on z = 0 (800 faces) with colors, written as `name`.
  std::string WriteGrid(const std::string& name) {
    Mesh mesh;
    mesh.origin = {1000.0, 2000.0, 30.0};
    const int n = 20;
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i <= n; ++i) {
        mesh.positions.insert(mesh.positions.end(),
                              {static_cast<float>(i) / n, static_cast<float>(j) / n, 0.0f});
        mesh.colors.insert(mesh.colors.end(), {static_cast<uint8_t>(10 * j), 50, 200});
      }
    }
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
        mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
      }
    }
    const std::filesystem::path dir = dir_ / "input";
    std::filesystem::create_directories(dir);
    const std::string path = (dir / name).string();
    EXPECT_TRUE(WritePlyMesh(path, mesh).ok());
    return path;
  }
};

TEST_F(MeshStagesTest, DecimateIsWellFormed) {
  const StageType* type = registry_.Find("mesh.decimate");
  ASSERT_NE(type, nullptr);
  EXPECT_EQ(type->version, 6);
  const nlohmann::json schema = CheckedSchema(*type);
  EXPECT_EQ(schema["type"], "object");
  EXPECT_EQ(schema["properties"]["target_faces"]["type"], "integer");
  EXPECT_EQ(schema["properties"]["fill_hole_output_edges"]["default"], 8);
  EXPECT_EQ(schema["properties"]["fill_hole_reach"]["default"], 1);
  EXPECT_EQ(schema["properties"]["boundary_weight"]["default"], 1000);
  EXPECT_EQ(schema["properties"]["boundary_tolerance"]["default"], 0.2);
  EXPECT_EQ(schema["properties"]["boundary_erosion"]["default"], 0.5);
  EXPECT_EQ(schema["properties"]["min_normal_dot"]["default"], 0.2);
  EXPECT_EQ(schema["properties"]["seen_through_points"]["default"], 3);
  EXPECT_EQ(schema["properties"]["seen_through_clearance"]["default"], 0.25);
  EXPECT_EQ(schema["oneOf"].size(), 2u);
  ASSERT_EQ(type->inputs.size(), 2u);
  EXPECT_EQ(type->inputs[0].name, "mesh");
  EXPECT_EQ(type->inputs[0].type, "mesh");
  EXPECT_FALSE(type->inputs[0].optional);
  EXPECT_EQ(type->inputs[1].name, "points");
  EXPECT_EQ(type->inputs[1].type, "points");
  EXPECT_TRUE(type->inputs[1].optional);
  ASSERT_EQ(type->outputs.size(), 1u);
  EXPECT_EQ(type->outputs[0].name, "mesh");
  EXPECT_EQ(type->outputs[0].type, "mesh");
}

TEST_F(MeshStagesTest, DecimateToTargetFaces) {
  FakeContext ctx(dir_ / "run", {{"target_faces", 200}});
  ctx.AddInput("mesh", "mesh", WriteGrid("mesh.ply"), {{"source", "test"}});
  const Status status = Run("mesh.decimate", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["faces_in"], 800);
  EXPECT_LE(ctx.counters_["faces_out"], 200);
  EXPECT_GE(ctx.counters_["faces_out"], 190);
  EXPECT_EQ(ctx.counters_["holes_filled"], 0);  // the grid's border is no small hole
  EXPECT_EQ(ctx.phases_, (std::set<std::string>{"io", "compute"}));
  EXPECT_DOUBLE_EQ(ctx.last_progress_, 1.0);
  auto out = ReadPlyMesh(ctx.outputs_["mesh"]);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(std::filesystem::path(ctx.outputs_["mesh"]).filename(), "mesh.ply");
  EXPECT_EQ(out->mesh.origin, (std::array<double, 3>{1000.0, 2000.0, 30.0}));
  EXPECT_EQ(static_cast<double>(out->mesh.face_count()), ctx.counters_["faces_out"]);
  EXPECT_TRUE(out->mesh.has_colors());
  EXPECT_EQ(ctx.meta_["mesh"]["faces"], out->mesh.face_count());
  EXPECT_EQ(ctx.meta_["mesh"]["source"], "test");  // input meta passed on
}

// An n x n quad grid of the unit square on z = 0, two triangles a quad,
// without the quads (i, j) for which `skip` holds.
Mesh UnitGrid(int n, const std::function<bool(int i, int j)>& skip) {
  Mesh grid;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      grid.positions.insert(grid.positions.end(),
                            {static_cast<float>(i) / n, static_cast<float>(j) / n, 0.0f});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      if (skip(i, j)) continue;
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      grid.indices.insert(grid.indices.end(), {a, b, c, a, c, d});
    }
  }
  return grid;
}

// A 1 m grid with a round hole of radius 6 cm, decimated to 200 faces
// (output edge about 0.11 m): small enough to fill. Scanned from 1 m above
// the hole: when the scan also has a floor 0.5 m below, seen through the
// hole, the hole is real and stays open; without the floor (the scanner
// got nothing back through it, as over a gap in the scan) it is filled;
// without stations there is no telling, and it is filled with a warning.
// A few returns behind a hole the scan mostly saw as surface do not open it.
TEST_F(MeshStagesTest, DecimateKeepsAHoleTheScannerSawThroughOpen) {
  const int n = 40;
  Mesh holed = UnitGrid(n, [&](int i, int j) {
    const double x = (i + 0.5) / n - 0.5, y = (j + 0.5) / n - 0.5;
    return x * x + y * y < 0.06 * 0.06;
  });
  holed.origin = {500.0, 20.0, 3.0};
  // `floor_step`: a floor every that many cm (0: none); `in_hole`: points on
  // the plane inside the hole too (the mesh lost surface the scan has).
  const auto scan = [&](int floor_step, bool stations, bool in_hole = false) {
    PointCloud cloud;
    cloud.origin = {500.0, 20.0, 3.0};
    for (int j = 0; j <= 100; ++j) {
      for (int i = 0; i <= 100; ++i) {
        const double x = i / 100.0, y = j / 100.0;
        if (!in_hole && (x - 0.5) * (x - 0.5) + (y - 0.5) * (y - 0.5) < 0.07 * 0.07) continue;
        cloud.positions.insert(cloud.positions.end(),
                               {static_cast<float>(x), static_cast<float>(y), 0.0f});
      }
    }
    for (int j = 30; floor_step > 0 && j <= 70; j += floor_step) {
      for (int i = 30; i <= 70; i += floor_step) {
        cloud.positions.insert(cloud.positions.end(), {i / 100.0f, j / 100.0f, -0.5f});
      }
    }
    if (stations) {
      cloud.stations = {{500.5, 20.5, 4.0}};
      cloud.station_ids.assign(cloud.size(), 0);
    }
    return cloud;
  };
  const auto decimate = [&](const std::string& name, const PointCloud& points) {
    auto ctx = std::make_unique<FakeContext>(dir_ / name, nlohmann::json{{"target_faces", 200}});
    ctx->AddInput("mesh", "mesh", WriteInputMesh(name + "_mesh", holed));
    ctx->AddInput("points", "points", WriteInputPoints(name + "_points", points));
    const Status status = Run("mesh.decimate", *ctx);
    EXPECT_TRUE(status.ok()) << status.message();
    return ctx;
  };
  const auto seen = decimate("seen", scan(1, true));
  EXPECT_EQ(seen->counters_["holes_seen_through"], 1);
  EXPECT_EQ(seen->counters_["holes_filled"], 0);
  EXPECT_EQ(seen->meta_["mesh"]["decimate"]["holes_seen_through"], 1);
  const auto unseen = decimate("unseen", scan(0, true));
  EXPECT_EQ(unseen->counters_["holes_seen_through"], 0);
  EXPECT_EQ(unseen->counters_["holes_filled"], 1);
  EXPECT_TRUE(unseen->warnings_.empty());
  const auto blind = decimate("blind", scan(1, false));
  EXPECT_EQ(blind->counters_["holes_filled"], 1);
  ASSERT_EQ(blind->warnings_.size(), 1u);
  EXPECT_THAT(blind->warnings_[0], HasSubstr("no scanner stations"));
  // seen_through_points: 0 turns the test off.
  FakeContext off(dir_ / "off", {{"target_faces", 200}, {"seen_through_points", 0}});
  off.AddInput("mesh", "mesh", WriteInputMesh("off_mesh", holed));
  off.AddInput("points", "points", WriteInputPoints("off_points", scan(1, true)));
  ASSERT_TRUE(Run("mesh.decimate", off).ok());
  EXPECT_EQ(off.counters_["holes_filled"], 1);
  // The scan has surface in the hole and a few returns behind it (a sparse
  // floor, as an RGB-D camera's flying pixels past a depth step): the lines
  // ending on the patch outnumber those through it, and it is filled.
  const auto mixed = decimate("mixed", scan(4, true, true));
  EXPECT_EQ(mixed->counters_["holes_seen_through"], 0);
  EXPECT_EQ(mixed->counters_["holes_filled"], 1);

  // The scan is read only when a hole asks: a truncated points file fails
  // the decimation of the holed grid, naming the file, and does not matter
  // to a grid without holes.
  const std::filesystem::path truncated = dir_ / "truncated" / "points.ply";
  std::filesystem::create_directories(truncated.parent_path());
  {
    std::ofstream out(truncated);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\n"
           "property float y\nproperty float z\nend_header\n";
  }
  FakeContext broken(dir_ / "broken", {{"target_faces", 200}});
  broken.AddInput("mesh", "mesh", WriteInputMesh("broken_mesh", holed));
  broken.AddInput("points", "points", truncated.string());
  const Status broken_status = Run("mesh.decimate", broken);
  EXPECT_FALSE(broken_status.ok());
  EXPECT_THAT(broken_status.message(), HasSubstr("points.ply"));
  FakeContext whole(dir_ / "whole", {{"target_faces", 200}});
  whole.AddInput("mesh", "mesh", WriteGrid("whole.ply"));
  whole.AddInput("points", "points", truncated.string());
  EXPECT_TRUE(Run("mesh.decimate", whole).ok());
}

TEST_F(MeshStagesTest, DecimateByRatioFromAnyFileName) {
  FakeContext ctx(dir_ / "run", {{"ratio", 0.5}});
  ctx.AddInput("mesh", "mesh", WriteGrid("grid.ply"));
  const Status status = Run("mesh.decimate", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["faces_in"], 800);
  EXPECT_LE(ctx.counters_["faces_out"], 400);
  EXPECT_GE(ctx.counters_["faces_out"], 380);
}

// A budget above the input leaves the mesh unchanged, and says so.
TEST_F(MeshStagesTest, DecimateWithinBudgetWarns) {
  FakeContext ctx(dir_ / "run", {{"target_faces", 5000}});
  ctx.AddInput("mesh", "mesh", WriteGrid("grid.ply"));
  const Status status = Run("mesh.decimate", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["faces_out"], 800);
  EXPECT_EQ(ctx.warnings_, std::vector<std::string>{
                               "the input has 800 faces, within the budget of 5000: unchanged"});
  FakeContext halved(dir_ / "halved", {{"ratio", 0.5}});
  halved.AddInput("mesh", "mesh", WriteGrid("grid2.ply"));
  ASSERT_TRUE(Run("mesh.decimate", halved).ok());
  EXPECT_TRUE(halved.warnings_.empty());
}

TEST_F(MeshStagesTest, DecimateReadsMeshPlyOfMultiFileInput) {
  // Like synth.scan's truth (mesh.ply + scene.json), plus a file that sorts
  // before mesh.ply: the stage must pick mesh.ply by name.
  const std::string json = (dir_ / "input" / "aux.json").string();
  const std::string mesh = WriteGrid("mesh.ply");
  std::ofstream(json) << "{}";
  FakeContext ctx(dir_ / "run", {{"target_faces", 100}});
  ctx.AddInput("mesh", "mesh",
               std::map<std::string, std::string>{
                   {"aux.json", json}, {"mesh.ply", mesh}, {"scene.json", json}});
  const Status status = Run("mesh.decimate", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["faces_in"], 800);
  EXPECT_LE(ctx.counters_["faces_out"], 100);
  EXPECT_GE(ctx.counters_["faces_out"], 95);
}

TEST_F(MeshStagesTest, DecimateNeedsExactlyOneBudget) {
  const std::string input = WriteGrid("mesh.ply");
  FakeContext both(dir_ / "a", {{"ratio", 0.5}, {"target_faces", 10}});
  both.AddInput("mesh", "mesh", input);
  const Status both_status = Run("mesh.decimate", both);
  EXPECT_EQ(both_status.code(), Status::Code::kInvalid);
  EXPECT_THAT(both_status.message(),
              HasSubstr("mesh.decimate: give exactly one of 'target_faces' and 'ratio'"));
  FakeContext neither(dir_ / "b", nlohmann::json::object());
  neither.AddInput("mesh", "mesh", input);
  EXPECT_EQ(Run("mesh.decimate", neither).code(), Status::Code::kInvalid);
  FakeContext bad_ratio(dir_ / "c", {{"ratio", 1.5}});
  bad_ratio.AddInput("mesh", "mesh", input);
  EXPECT_THAT(Run("mesh.decimate", bad_ratio).message(), HasSubstr("'ratio' must be in (0, 1]"));
  EXPECT_TRUE(bad_ratio.outputs_.empty());
}

TEST_F(MeshStagesTest, DecimateReportsUnreadableInput) {
  FakeContext ctx(dir_ / "run", {{"target_faces", 10}});
  ctx.AddInput("mesh", "mesh", (dir_ / "missing" / "mesh.ply").string());
  const Status status = Run("mesh.decimate", ctx);
  EXPECT_FALSE(status.ok());
  EXPECT_THAT(status.message(), HasSubstr("mesh.ply"));
}


// A unit sphere of `n` oriented points (outward normals) around a far
// origin, red rising with z, written as points.ply.
std::string WriteSpherePoints(const std::filesystem::path& dir, int n, bool normals = true) {
  PointCloud cloud;
  cloud.origin = {500000.0, 4000000.0, 120.0};
  const double golden = 3.14159265358979 * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n;
    const double r = std::sqrt(1.0 - z * z);
    const double a = golden * i;
    const float p[3] = {static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)),
                        static_cast<float>(z)};
    cloud.positions.insert(cloud.positions.end(), p, p + 3);
    if (normals) cloud.normals.insert(cloud.normals.end(), p, p + 3);
    cloud.colors.insert(cloud.colors.end(),
                        {static_cast<uint8_t>(std::lround(127.5 * (z + 1))), 40, 200});
  }
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "points.ply").string();
  EXPECT_TRUE(WritePlyPoints(path, cloud).ok());
  return path;
}

TEST_F(MeshStagesTest, PoissonPicksTheDepthForAFaceBudgetAndReportsIt) {
  FakeContext ctx(dir_ / "run", {{"target_faces", 30000}, {"trim", 0}, {"threads", 1}});
  ctx.AddInput("points", "points", WriteSpherePoints(dir_ / "in", 40000), {{"spacing_m", 0.01}});
  const Status status = Run("mesh.poisson", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  const nlohmann::json& meta = ctx.meta_["mesh"];
  const int depth = meta["poisson"]["depth"];
  EXPECT_EQ(ctx.counters_["depth"], depth);
  EXPECT_EQ(meta["poisson"]["target_faces"], 30000);
  EXPECT_EQ(meta["spacing_m"], 0.01);
  auto mesh = ReadPlyMesh(ctx.outputs_["mesh"]);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  const double faces = static_cast<double>(mesh->mesh.face_count());
  EXPECT_EQ(meta["faces"], mesh->mesh.face_count());
  EXPECT_LT(std::abs(std::log(faces / 30000)), std::log(2.0)) << faces << " at depth " << depth;
  EXPECT_EQ(mesh->mesh.origin, (std::array<double, 3>{500000.0, 4000000.0, 120.0}));
  ASSERT_TRUE(mesh->mesh.has_colors());
  ASSERT_TRUE(mesh->mesh.has_normals());
  // On the sphere, red follows z and the normals point outward.
  double worst_radius = 0, worst_red = 0, sum_red = 0, worst_normal = 1;
  for (size_t v = 0; v < mesh->mesh.vertex_count(); ++v) {
    const float* p = &mesh->mesh.positions[3 * v];
    const float* n = &mesh->mesh.normals[3 * v];
    const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    worst_radius = std::max(worst_radius, std::abs(r - 1));
    const double red_error = std::abs(mesh->mesh.colors[3 * v] - 127.5 * (p[2] / r + 1));
    worst_red = std::max(worst_red, red_error);
    sum_red += red_error;
    worst_normal = std::min(worst_normal, (p[0] * n[0] + p[1] * n[1] + p[2] * n[2]) / r);
  }
  EXPECT_LT(worst_radius, 0.02);
  // Colors are splatted over a few cells: exact on average, smoothed at the
  // poles (measured: mean 1-2, worst 18 of 255).
  EXPECT_LT(sum_red / static_cast<double>(mesh->mesh.vertex_count()), 4);
  EXPECT_LT(worst_red, 30);
  EXPECT_GT(worst_normal, 0.9);
}

// The paper's low-mesh path: Poisson, clean, decimate to the budget; the
// budget is met within 5 % and colors survive.
TEST_F(MeshStagesTest, PoissonThenDecimateMeetsTheBudget) {
  FakeContext poisson(dir_ / "poisson", {{"depth", 7}});
  poisson.AddInput("points", "points", WriteSpherePoints(dir_ / "in", 30000));
  ASSERT_TRUE(Run("mesh.poisson", poisson).ok());
  FakeContext clean(dir_ / "clean", nlohmann::json::object());
  clean.AddInput("mesh", "mesh", poisson.outputs_["mesh"]);
  ASSERT_TRUE(Run("mesh.clean", clean).ok());
  FakeContext decimate(dir_ / "decimate", {{"target_faces", 12000}});
  decimate.AddInput("mesh", "mesh", clean.outputs_["mesh"]);
  ASSERT_TRUE(Run("mesh.decimate", decimate).ok());
  auto mesh = ReadPlyMesh(decimate.outputs_["mesh"]);
  ASSERT_TRUE(mesh.ok());
  EXPECT_GT(poisson.counters_["faces_out"], 12000);
  EXPECT_NEAR(static_cast<double>(mesh->mesh.face_count()), 12000, 0.05 * 12000);
  EXPECT_TRUE(mesh->mesh.has_colors());
  EXPECT_TRUE(mesh->mesh.has_normals());
}

// implementation: pcl through the stage: PCL's solver, the vertex attributes
// taken from the points (red follows z on this sphere), the meta says which.
TEST_F(MeshStagesTest, PoissonWithPclGivesAColoredSphere) {
  if (!ModuleSymbol(kPclModule, PB_PCL_POISSON_SYMBOL, "test").ok()) {
    GTEST_SKIP() << "this build has no pointbake-pcl.so";
  }
  FakeContext ctx(dir_ / "run", {{"depth", 6}, {"implementation", "pcl"}});
  ctx.AddInput("points", "points", WriteSpherePoints(dir_ / "in", 20000));
  const Status status = Run("mesh.poisson", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.meta_["mesh"]["poisson"]["implementation"], "PCL 1.13 (pcl::Poisson)");
  auto mesh = ReadPlyMesh(ctx.outputs_["mesh"]);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  ASSERT_GT(mesh->mesh.face_count(), 1000u);
  ASSERT_TRUE(mesh->mesh.has_colors());
  ASSERT_TRUE(mesh->mesh.has_normals());
  EXPECT_EQ(mesh->mesh.origin, (std::array<double, 3>{500000.0, 4000000.0, 120.0}));
  double worst_red = 0, worst_normal = 1;
  for (size_t v = 0; v < mesh->mesh.vertex_count(); ++v) {
    const float* p = &mesh->mesh.positions[3 * v];
    const float* n = &mesh->mesh.normals[3 * v];
    const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    worst_normal = std::min(worst_normal, (p[0] * n[0] + p[1] * n[1] + p[2] * n[2]) / r);
    worst_red = std::max(worst_red, std::abs(mesh->mesh.colors[3 * v] - 127.5 * (p[2] / r + 1)));
  }
  EXPECT_GT(worst_normal, 0.95);
  EXPECT_LT(worst_red, 12);
}

TEST_F(MeshStagesTest, PoissonExplainsWhatItNeeds) {
  FakeContext both(dir_ / "both", {{"depth", 7}, {"target_faces", 1000}});
  both.AddInput("points", "points", WriteSpherePoints(dir_ / "in", 2000));
  EXPECT_THAT(Run("mesh.poisson", both).message(), HasSubstr("not both"));

  FakeContext pcl_trim(dir_ / "pcl_trim", {{"depth", 6}, {"implementation", "pcl"}, {"trim", 0.02}});
  pcl_trim.AddInput("points", "points", WriteSpherePoints(dir_ / "in", 2000));
  EXPECT_THAT(Run("mesh.poisson", pcl_trim).message(), HasSubstr("follow with mesh.trim"));

  FakeContext bare(dir_ / "bare", {{"depth", 6}});
  bare.AddInput("points", "points", WriteSpherePoints(dir_ / "bare_in", 2000, false));
  const Status status = Run("mesh.poisson", bare);
  EXPECT_THAT(status.message(), HasSubstr("points.normals"));
  EXPECT_THAT(status.message(), HasSubstr("points.ply"));
}

// mesh.trim: a grid of 1 m^2 whose points leave a band 0.4 < x < 0.6
// unscanned; the band's faces go, the rest stays; the next stages learn
// the spacing from the meta; mesh.clean then fills a pin-hole, not the band.
TEST_F(MeshStagesTest, TrimRemovesUnsupportedFacesAndCleanFillsPinHoles) {
  const StageType* type = registry_.Find("mesh.trim");
  ASSERT_NE(type, nullptr);
  EXPECT_EQ(type->version, 1);
  const nlohmann::json schema = CheckedSchema(*type, true);
  EXPECT_EQ(schema["properties"]["max_distance_spacings"]["default"], 3);
  ASSERT_EQ(type->inputs.size(), 2u);
  EXPECT_EQ(type->inputs[1].name, "points");

  PointCloud points;
  for (int j = 0; j <= 100; ++j) {
    for (int i = 0; i <= 100; ++i) {
      if (i > 40 && i < 60) continue;
      points.positions.insert(points.positions.end(), {i / 100.0f, j / 100.0f, 0.0f});
    }
  }
  // A pin-hole in scanned surface at quad (5, 5).
  const int n = 50;
  const Mesh grid = UnitGrid(n, [](int i, int j) { return i == 5 && j == 5; });
  FakeContext trim(dir_ / "trim", nlohmann::json::object(), 2);
  trim.AddInput("mesh", "mesh", WriteInputMesh("grid", grid), {{"source", "test"}});
  trim.AddInput("points", "points", WriteInputPoints("points", points));
  const Status status = Run("mesh.trim", trim);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(trim.counters_["faces_in"], 2 * n * n - 2);
  EXPECT_GT(trim.counters_["faces_removed"], 200);
  EXPECT_EQ(trim.counters_["regions_removed"], 1);
  EXPECT_EQ(trim.phases_, (std::set<std::string>{"io", "compute"}));
  EXPECT_EQ(trim.meta_["mesh"]["source"], "test");
  EXPECT_NEAR(trim.meta_["mesh"]["spacing_m"].get<double>(), 0.01, 0.002);
  auto trimmed = ReadPlyMesh(trim.outputs_["mesh"]);
  ASSERT_TRUE(trimmed.ok());
  for (size_t f = 0; f < trimmed->mesh.face_count(); ++f) {
    double x = 0;
    for (int k = 0; k < 3; ++k) x += trimmed->mesh.positions[3 * trimmed->mesh.indices[3 * f + k]] / 3;
    EXPECT_FALSE(x > 0.45 && x < 0.55) << "face " << f << " at x " << x;
  }

  FakeContext clean(dir_ / "clean", nlohmann::json::object());
  clean.AddInput("mesh", "mesh", trim.outputs_["mesh"], trim.meta_["mesh"]);
  ASSERT_TRUE(Run("mesh.clean", clean).ok());
  EXPECT_EQ(clean.counters_["holes_filled"], 1);  // the pin-hole, not the band
  EXPECT_EQ(clean.counters_["hole_faces"], 2);
  EXPECT_EQ(clean.counters_["faces_out"], trim.counters_["faces_out"] + 2);
}

// mesh.fit: a grid 4 mm under points on z = 0 is lifted onto them, every
// vertex along its normal (free directions or not: the points ask nothing
// else of a plane); faces and colors are kept; the counters say so.
// Points that do not fit (too few) give a clear error naming the files.
TEST_F(MeshStagesTest, FitLiftsAMeshOntoItsPoints) {
  const StageType* type = registry_.Find("mesh.fit");
  ASSERT_NE(type, nullptr);
  EXPECT_EQ(type->version, 5);
  const nlohmann::json schema = CheckedSchema(*type, true);
  EXPECT_EQ(schema["properties"]["directions"]["default"], "free");
  EXPECT_EQ(schema["properties"]["tangent_weight"]["default"], 0.1);
  EXPECT_EQ(schema["properties"]["iterations"]["default"], 12);
  EXPECT_EQ(schema["properties"]["outside_weight"]["default"], 0.75);
  EXPECT_EQ(schema["properties"]["border_reach_edges"]["default"], 0.5);
  EXPECT_EQ(schema["properties"]["border_margin_spacings"]["default"], 0.5);
  ASSERT_EQ(type->inputs.size(), 2u);
  EXPECT_EQ(type->inputs[1].name, "points");

  PointCloud points;
  for (int j = 0; j <= 100; ++j) {
    for (int i = 0; i <= 100; ++i) {
      points.positions.insert(points.positions.end(), {i / 100.0f, j / 100.0f, 0.0f});
    }
  }
  Mesh grid;
  const int n = 10;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      grid.positions.insert(grid.positions.end(),
                            {static_cast<float>(i) / n, static_cast<float>(j) / n, -0.004f});
      grid.colors.insert(grid.colors.end(), {static_cast<uint8_t>(i), 7, 9});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      grid.indices.insert(grid.indices.end(), {a, b, c, a, c, d});
    }
  }
  // The border pass off (the rim lies on the outermost points already; the
  // pass would move it half a spacing past them, below).
  FakeContext fit(dir_ / "fit", {{"border_reach_edges", 0}}, 2);
  fit.AddInput("mesh", "mesh", WriteInputMesh("grid", grid), {{"source", "test"}});
  fit.AddInput("points", "points", WriteInputPoints("points", points));
  const Status status = Run("mesh.fit", fit);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_NEAR(fit.counters_["mean_abs_distance_before_m"], 0.004, 1e-4);
  EXPECT_LT(fit.counters_["mean_abs_distance_after_m"], 2e-4);
  EXPECT_EQ(fit.counters_["vertices_moved"], (n + 1) * (n + 1));
  EXPECT_NEAR(fit.counters_["max_move_m"], 0.004, 5e-4);
  EXPECT_EQ(fit.counters_["outside_fraction_before"], 1.0);  // every point above the grid
  EXPECT_LE(fit.counters_["outside_fraction_after"], 1.0);
  EXPECT_EQ(fit.phases_, (std::set<std::string>{"io", "compute"}));
  EXPECT_EQ(fit.meta_["mesh"]["source"], "test");
  auto fitted = ReadPlyMesh(fit.outputs_["mesh"]);
  ASSERT_TRUE(fitted.ok());
  EXPECT_EQ(fitted->mesh.indices, grid.indices);
  EXPECT_EQ(fitted->mesh.colors, grid.colors);
  for (size_t v = 0; v < fitted->mesh.vertex_count(); ++v) {
    EXPECT_NEAR(fitted->mesh.positions[3 * v + 2], 0.0, 2e-4) << "vertex " << v;
    EXPECT_NEAR(fitted->mesh.positions[3 * v], grid.positions[3 * v], 1e-6);
  }
  EXPECT_EQ(fit.counters_["border_vertices_moved"], 0);

  // Along the normals only (version 3's fit): the same lift.
  FakeContext normals(dir_ / "normals", {{"border_reach_edges", 0}, {"directions", "normals"}}, 2);
  normals.AddInput("mesh", "mesh", WriteInputMesh("grid4", grid));
  normals.AddInput("points", "points", WriteInputPoints("points4", points));
  ASSERT_TRUE(Run("mesh.fit", normals).ok());
  EXPECT_LT(normals.counters_["mean_abs_distance_after_m"], 2e-4);
  EXPECT_EQ(normals.counters_["vertices_moved"], (n + 1) * (n + 1));

  // With the defaults the rim moves out in the plane, past the outermost
  // points by a fraction of their spacing (1 cm).
  FakeContext border(dir_ / "border", nlohmann::json::object(), 2);
  border.AddInput("mesh", "mesh", WriteInputMesh("grid3", grid));
  border.AddInput("points", "points", WriteInputPoints("points3", points));
  ASSERT_TRUE(Run("mesh.fit", border).ok());
  EXPECT_EQ(border.counters_["border_vertices_moved"], 4 * n);
  auto bordered = ReadPlyMesh(border.outputs_["mesh"]);
  ASSERT_TRUE(bordered.ok());
  float min_x = 1, max_x = 0;
  for (size_t v = 0; v < bordered->mesh.vertex_count(); ++v) {
    min_x = std::min(min_x, bordered->mesh.positions[3 * v]);
    max_x = std::max(max_x, bordered->mesh.positions[3 * v]);
  }
  EXPECT_LT(min_x, -0.002f);
  EXPECT_GT(min_x, -0.012f);
  EXPECT_GT(max_x, 1.002f);
  EXPECT_LT(max_x, 1.012f);

  PointCloud few;
  few.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  FakeContext bad(dir_ / "bad", nlohmann::json::object(), 1);
  bad.AddInput("mesh", "mesh", WriteInputMesh("grid2", grid));
  bad.AddInput("points", "points", WriteInputPoints("few", few));
  const Status bad_status = Run("mesh.fit", bad);
  EXPECT_EQ(bad_status.code(), Status::Code::kInvalid);
  EXPECT_THAT(bad_status.message(), HasSubstr("mesh fit: needs more than 8 points"));
  EXPECT_THAT(bad_status.message(), HasSubstr("few"));
}

}  // namespace
}  // namespace pb
