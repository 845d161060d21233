// Runs the io and points stages through a fake StageContext (no engine, no
// child processes): files go to a temporary directory.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>

#include "stages/builtin.h"
#include "stages/geometry/core/module.h"
#include "stages/geometry/core/table.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/points/module_calls.h"
#include "stages/geometry/io/e57_test_writer.h"
#include "stages/geometry/testing/clouds.h"
#include "stages/geometry/synth/scan_without_stations.h"
#include "stages/geometry/testing/test_data.h"
#include "stages/stage_test_util.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

std::string SharedData() { return pb::testing::SharedDataDir(); }

class PointsStagesTest : public StageTest {
 protected:
  void SetUp() override {
    StageTest::SetUp();
    RegisterBuiltinStages(registry_);
  }
};

TEST_F(PointsStagesTest, RegistersWellFormedTypes) {
  const std::vector<const StageType*> all = registry_.All();
  // Other families register here too; check that ours are all present.
  for (const char* id : {"io.read_points", "points.downsample", "points.stats", "points.outliers",
                         "points.normals", "points.spacing", "points.smooth"}) {
    EXPECT_NE(registry_.Find(id), nullptr) << id;
  }
  for (const StageType* type : all) {
    SCOPED_TRACE(type->id);
    EXPECT_GE(type->version, 1);
    EXPECT_FALSE(type->summary.empty());
    EXPECT_FALSE(type->doc.empty());
    EXPECT_TRUE(type->run);
    const nlohmann::json schema = CheckedSchema(*type);
    EXPECT_EQ(schema["type"], "object");
  }
  const nlohmann::json read_schema = nlohmann::json::parse(registry_.Find("io.read_points")->params_schema);
  EXPECT_EQ(read_schema["required"], nlohmann::json({"path"}));
  EXPECT_EQ(read_schema["properties"]["path"]["x-path"], true);
  EXPECT_EQ(read_schema["properties"]["format"]["enum"],
            nlohmann::json({"auto", "ply", "pcd", "xyz", "ptx", "e57", "las"}));
  const nlohmann::json downsample_schema =
      nlohmann::json::parse(registry_.Find("points.downsample")->params_schema);
  EXPECT_EQ(downsample_schema["properties"]["voxel"]["exclusiveMinimum"], 0);
  for (const char* id : {"points.outliers", "points.normals", "points.spacing"}) {
    SCOPED_TRACE(id);
    const StageType* type = registry_.Find(id);
    const nlohmann::json schema = nlohmann::json::parse(type->params_schema);
    for (const auto& [name, property] : schema["properties"].items()) {
      EXPECT_TRUE(property.contains("default")) << name;
    }
    ASSERT_EQ(type->inputs.size(), 1u);
    EXPECT_EQ(type->inputs[0].name, "points");
    EXPECT_EQ(type->inputs[0].type, "points");
    ASSERT_EQ(type->outputs.size(), 1u);
    EXPECT_EQ(type->outputs[0].name, "points");
    EXPECT_EQ(type->outputs[0].type, "points");
  }
  const nlohmann::json normals_schema = nlohmann::json::parse(registry_.Find("points.normals")->params_schema);
  EXPECT_EQ(normals_schema["properties"]["k"]["default"], 16);
  EXPECT_EQ(normals_schema["properties"]["k"]["minimum"], 3);
  EXPECT_EQ(normals_schema["properties"]["k"]["maximum"], 100);
  EXPECT_EQ(normals_schema["properties"]["orientation"]["enum"],
            nlohmann::json({"auto", "stations", "input", "propagate", "none"}));
  const nlohmann::json outliers_schema = nlohmann::json::parse(registry_.Find("points.outliers")->params_schema);
  EXPECT_EQ(outliers_schema["properties"]["std_ratio"]["default"], 2.0);
  const nlohmann::json spacing_schema = nlohmann::json::parse(registry_.Find("points.spacing")->params_schema);
  EXPECT_EQ(spacing_schema["properties"]["sample"]["default"], 100000);
}

TEST_F(PointsStagesTest, DownsampleThenStats) {
  PointCloud cloud;
  cloud.origin = {500000.0, 4000000.0, 100.0};
  // Two 1 m voxels: 3 points in one, 1 in the other.
  cloud.positions = {0.1f, 0.1f, 0.1f, 0.3f, 0.3f, 0.3f, 0.5f, 0.2f, 0.8f, 1.5f, 0.5f, 0.5f};
  cloud.colors = {0, 0, 0, 30, 60, 90, 60, 120, 180, 255, 255, 255};
  const std::string input = (dir_ / "in.ply").string();
  ASSERT_TRUE(WritePlyPoints(input, cloud).ok());

  FakeContext downsample(dir_ / "d", {{"voxel", 1.0}});
  downsample.AddInput("points", "points", input);
  ASSERT_TRUE(Run("points.downsample", downsample).ok());
  EXPECT_EQ(downsample.counters_["points_in"], 4);
  EXPECT_EQ(downsample.counters_["points_out"], 2);
  EXPECT_EQ(downsample.phases_, (std::set<std::string>{"io", "compute"}));
  EXPECT_DOUBLE_EQ(downsample.last_progress_, 1.0);
  auto out = ReadPlyPoints(downsample.outputs_["points"]);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(out->points.origin, cloud.origin);
  ASSERT_EQ(out->points.size(), 2u);
  EXPECT_FLOAT_EQ(out->points.positions[0], 0.3f);
  EXPECT_FLOAT_EQ(out->points.positions[2], 0.4f);
  EXPECT_EQ(out->points.colors, (std::vector<uint8_t>{30, 60, 90, 255, 255, 255}));
  EXPECT_EQ(downsample.meta_["points"]["points"], 2);

  FakeContext stats(dir_ / "s", nlohmann::json::object());
  stats.AddInput("points", "points", downsample.outputs_["points"]);
  ASSERT_TRUE(Run("points.stats", stats).ok());
  auto table = ReadTable(stats.outputs_["table"]);
  ASSERT_TRUE(table.ok()) << table.status().message();
  ASSERT_EQ(table->rows.size(), 1u);
  EXPECT_EQ(std::get<int64_t>(table->get(0, "points")), 2);
  EXPECT_NEAR(TableNumber(table->get(0, "min_x_m")), 500000.3, 1e-6);
  EXPECT_NEAR(TableNumber(table->get(0, "max_x_m")), 500001.5, 1e-6);
  EXPECT_NEAR(TableNumber(table->get(0, "centroid_y_m")), 4000000.35, 1e-6);
  EXPECT_EQ(std::get<bool>(table->get(0, "has_colors")), true);
  EXPECT_EQ(std::get<bool>(table->get(0, "has_normals")), false);
  EXPECT_DOUBLE_EQ(TableNumber(table->get(0, "mean_red")), 142.5);
}

TEST_F(PointsStagesTest, DownsampleRejectsBadVoxel) {
  PointCloud cloud;
  cloud.positions = {0, 0, 0};
  const std::string input = (dir_ / "in.ply").string();
  ASSERT_TRUE(WritePlyPoints(input, cloud).ok());
  FakeContext ctx(dir_ / "d", {{"voxel", -1.0}});
  ctx.AddInput("points", "points", input);
  EXPECT_EQ(Run("points.downsample", ctx).code(), Status::Code::kInvalid);
}

TEST_F(PointsStagesTest, ReadPointsBunny) {
  const std::string data = SharedData();
  if (data.empty()) GTEST_SKIP() << "shared data not found";
  const std::string path = data + "/bunny/bun_zipper.ply";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not found";
  FakeContext ctx(dir_, {{"path", path}, {"format", "auto"}, {"drop_invalid", false}});
  const Status status = Run("io.read_points", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["points"], 35947);
  EXPECT_EQ(ctx.counters_["dropped_points"], 0);
  EXPECT_EQ(ctx.phases_, (std::set<std::string>{"read", "write"}));
  EXPECT_DOUBLE_EQ(ctx.last_progress_, 1.0);
  auto read = ReadPlyPoints(ctx.outputs_["points"]);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.size(), 35947u);
  EXPECT_EQ(read->report.pointbake_kind, "points");
}

// A grid cell without a return (PTX 0 0 0) is the format's normal way to say
// "nothing measured here": counted, not warned about.
TEST_F(PointsStagesTest, ReadPointsCountsCellsWithoutAReturnQuietly) {
  const std::string path = (dir_ / "grid.ptx").string();
  std::ofstream(path) << "2\n1\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"
                         "1 2 3 0.5\n0 0 0 0.5\n";
  FakeContext ctx(dir_ / "c", {{"path", path}, {"uncolored", "none"}});
  ASSERT_TRUE(Run("io.read_points", ctx).ok());
  EXPECT_EQ(ctx.counters_["points"], 1);
  EXPECT_EQ(ctx.counters_["no_return_points"], 1);
  EXPECT_EQ(ctx.counters_["dropped_points"], 0);
  EXPECT_TRUE(ctx.warnings_.empty()) << ctx.warnings_.front();
}

TEST_F(PointsStagesTest, ReadPointsDropsInvalid) {
  const std::string path = (dir_ / "scan.PLY").string();
  std::ofstream(path) << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                         "property float y\nproperty float z\nend_header\n1 2 3\nnan 0 0\n4 5 6\n";
  FakeContext strict(dir_ / "a", {{"path", path}});
  const Status failed = Run("io.read_points", strict);
  EXPECT_THAT(failed.message(), HasSubstr("scan.PLY:9: vertex 1 has a non-finite coordinate"));

  // (uncolored: none, or the grey paint's warning would join the list.)
  FakeContext lenient(dir_ / "b", {{"path", path}, {"drop_invalid", true}, {"uncolored", "none"}});
  ASSERT_TRUE(Run("io.read_points", lenient).ok());
  EXPECT_EQ(lenient.counters_["points"], 2);
  EXPECT_EQ(lenient.counters_["dropped_points"], 1);
  // Said through the warning channel (run.json, progress line), naming the file.
  EXPECT_EQ(lenient.warnings_, std::vector<std::string>{
                                   path + ": dropped 1 points with NaN or infinite coordinates (drop_invalid)"});
  EXPECT_TRUE(strict.warnings_.empty());
}

// A scan without colors is painted grey so that the bakes can run: by its
// intensities, stretched between their 1st and 99th percentiles, else
// uniformly; `uncolored: none` keeps today's uncolored points.
TEST_F(PointsStagesTest, ReadPointsPaintsUncoloredScansGrey) {
  const std::string path = (dir_ / "grey.ply").string();
  std::ofstream(path) << "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\n"
                         "property float y\nproperty float z\nproperty float intensity\n"
                         "end_header\n0 0 0 0\n1 0 0 250\n2 0 0 500\n3 0 0 750\n4 0 0 1000\n";
  FakeContext by_intensity(dir_ / "a", {{"path", path}});
  ASSERT_TRUE(Run("io.read_points", by_intensity).ok());
  auto read = ReadPlyPoints(by_intensity.outputs_["points"]);
  ASSERT_TRUE(read.ok()) << read.status().message();
  // 1st percentile 0, 99th 750 (of five values): 0, 1/3, 2/3, 1, clamped 1.
  EXPECT_EQ(read->points.colors, (std::vector<uint8_t>{0, 0, 0, 85, 85, 85, 170, 170, 170, 255,
                                                       255, 255, 255, 255, 255}));
  EXPECT_EQ(by_intensity.meta_["points"]["colors_from"], "intensity");
  EXPECT_EQ(by_intensity.meta_["points"]["has_colors"], true);
  EXPECT_EQ(by_intensity.counters_["painted_points"], 5);
  EXPECT_EQ(by_intensity.counters_["uniform_grey"], 0);
  ASSERT_EQ(by_intensity.warnings_.size(), 1u);
  EXPECT_THAT(by_intensity.warnings_[0], HasSubstr("grey.ply: the scan has no colors"));

  FakeContext grey(dir_ / "b", {{"path", path}, {"uncolored", "grey"}});
  ASSERT_TRUE(Run("io.read_points", grey).ok());
  read = ReadPlyPoints(grey.outputs_["points"]);
  ASSERT_TRUE(read.ok());
  EXPECT_EQ(read->points.colors, std::vector<uint8_t>(15, 180));
  EXPECT_EQ(grey.meta_["points"]["colors_from"], "uniform grey");
  EXPECT_EQ(grey.counters_["uniform_grey"], 1);

  FakeContext none(dir_ / "c", {{"path", path}, {"uncolored", "none"}});
  ASSERT_TRUE(Run("io.read_points", none).ok());
  read = ReadPlyPoints(none.outputs_["points"]);
  ASSERT_TRUE(read.ok());
  EXPECT_FALSE(read->points.has_colors());
  EXPECT_EQ(none.meta_["points"]["colors_from"], "none");
  EXPECT_TRUE(none.warnings_.empty());

  // A non-finite intensity neither joins the percentiles nor breaks them:
  // its point gets the middle grey.
  const std::string with_nan = (dir_ / "nan.ply").string();
  std::ofstream(with_nan) << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                             "property float y\nproperty float z\nproperty float intensity\n"
                             "end_header\n0 0 0 0\n1 0 0 nan\n2 0 0 0.5\n3 0 0 1\n";
  FakeContext nan_ctx(dir_ / "e", {{"path", with_nan}});
  ASSERT_TRUE(Run("io.read_points", nan_ctx).ok());
  read = ReadPlyPoints(nan_ctx.outputs_["points"]);
  ASSERT_TRUE(read.ok());
  // 1st percentile 0, 99th 0.5 (of the three finite values).
  EXPECT_EQ(read->points.colors,
            (std::vector<uint8_t>{0, 0, 0, 128, 128, 128, 255, 255, 255, 255, 255, 255}));

  // A colored file keeps its colors, without a warning.
  const std::string colored = (dir_ / "colored.ply").string();
  std::ofstream(colored) << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                            "property float y\nproperty float z\nproperty uchar red\n"
                            "property uchar green\nproperty uchar blue\nend_header\n0 0 0 1 2 3\n";
  FakeContext keep(dir_ / "d", {{"path", colored}});
  ASSERT_TRUE(Run("io.read_points", keep).ok());
  read = ReadPlyPoints(keep.outputs_["points"]);
  ASSERT_TRUE(read.ok());
  EXPECT_EQ(read->points.colors, (std::vector<uint8_t>{1, 2, 3}));
  EXPECT_EQ(keep.meta_["points"]["colors_from"], "file");
  EXPECT_EQ(keep.counters_["painted_points"], 0);
  EXPECT_TRUE(keep.warnings_.empty());
}

// `units`: a file in millimeters (or cm, ft, in) is converted to meters:
// origin, offsets and stations; normals are directions and stay.
TEST_F(PointsStagesTest, ReadPointsConvertsTheFilesUnitsToMeters) {
  const std::string pcd = (dir_ / "mm.pcd").string();
  std::ofstream(pcd) << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
                        "COUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 1000 2000 3000 1 0 0 0\n"
                        "POINTS 2\nDATA ascii\n10 20 30\n-500 0 250\n";
  const auto absolute = [](const PointCloud& points, size_t i, int c) {
    return points.origin[c] + points.positions[3 * i + c];
  };
  for (const auto& [unit, meters] : std::vector<std::pair<std::string, double>>{
           {"m", 1.0}, {"mm", 0.001}, {"ft", 0.3048}}) {
    FakeContext ctx(dir_ / unit, {{"path", pcd}, {"units", unit}, {"uncolored", "none"}});
    ASSERT_TRUE(Run("io.read_points", ctx).ok()) << unit;
    auto read = ReadPlyPoints(ctx.outputs_["points"]);
    ASSERT_TRUE(read.ok()) << read.status().message();
    const PointCloud& points = read->points;
    const double want[2][3] = {{1010, 2020, 3030}, {500, 2000, 3250}};
    for (size_t i = 0; i < 2; ++i)
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(absolute(points, i, c), want[i][c] * meters, 1e-6 * meters * 3250) << unit;
    ASSERT_EQ(points.stations.size(), 1u);
    EXPECT_NEAR(points.stations[0][0], 1000 * meters, 1e-9);
    EXPECT_NEAR(points.stations[0][2], 3000 * meters, 1e-9);
    EXPECT_EQ(ctx.meta_["points"]["file_units"], unit);
  }

  const std::string ply = (dir_ / "normals.ply").string();
  std::ofstream(ply) << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                        "property float y\nproperty float z\nproperty float nx\nproperty float ny\n"
                        "property float nz\nend_header\n1000 0 -20 0 0.6 0.8\n";
  FakeContext mm(dir_ / "n", {{"path", ply}, {"units", "mm"}, {"uncolored", "none"}});
  ASSERT_TRUE(Run("io.read_points", mm).ok());
  auto read = ReadPlyPoints(mm.outputs_["points"]);
  ASSERT_TRUE(read.ok());
  EXPECT_NEAR(absolute(read->points, 0, 0), 1.0, 1e-6);
  EXPECT_NEAR(absolute(read->points, 0, 2), -0.02, 1e-6);
  EXPECT_EQ(read->points.normals, (std::vector<float>{0, 0.6f, 0.8f}));

  FakeContext bad(dir_ / "bad", {{"path", ply}, {"units", "yd"}});
  EXPECT_EQ(Run("io.read_points", bad).code(), Status::Code::kInvalid);
}

// `station`: one declared where the file says nothing (in the file's
// coordinates and units), the file's dropped, or replaced with a warning.
TEST_F(PointsStagesTest, ReadPointsDeclaresOrDropsTheStation) {
  const std::string xyz = (dir_ / "scan.xyz").string();
  std::ofstream(xyz) << "0 0 0\n1000 0 0\n0 1000 0\n0 0 1000\n";
  const auto read_back = [](FakeContext& ctx) {
    auto read = ReadPlyPoints(ctx.outputs_["points"]);
    EXPECT_TRUE(read.ok()) << read.status().message();
    return read.ok() ? std::move(read->points) : PointCloud();
  };
  {
    FakeContext ctx(dir_ / "none", {{"path", xyz}, {"uncolored", "none"}});
    ASSERT_TRUE(Run("io.read_points", ctx).ok());
    EXPECT_FALSE(read_back(ctx).has_stations());
    EXPECT_EQ(ctx.meta_["points"]["stations_from"], "none");
  }
  for (const nlohmann::json& station :
       {nlohmann::json::array({500, 250, 1500}), nlohmann::json("500,2.5e2,+1500")}) {
    SCOPED_TRACE(station.dump());
    FakeContext ctx(dir_ / "declared",
                    {{"path", xyz}, {"units", "mm"}, {"uncolored", "none"}, {"station", station}});
    ASSERT_TRUE(Run("io.read_points", ctx).ok());
    const PointCloud points = read_back(ctx);
    ASSERT_EQ(points.stations.size(), 1u);
    EXPECT_NEAR(points.stations[0][0], 0.5, 1e-12);  // millimeters to meters, as the points
    EXPECT_NEAR(points.stations[0][1], 0.25, 1e-12);
    EXPECT_NEAR(points.stations[0][2], 1.5, 1e-12);
    EXPECT_EQ(points.station_ids, std::vector<uint16_t>(4, 0));
    EXPECT_EQ(ctx.meta_["points"]["stations_from"], "declared");
    EXPECT_TRUE(ctx.warnings_.empty());
  }
  // A station far off the scan: most likely another frame or unit.
  FakeContext far(
      dir_ / "far",
      {{"path", xyz}, {"uncolored", "none"}, {"station", nlohmann::json::array({0, 0, 100000})}});
  ASSERT_TRUE(Run("io.read_points", far).ok());
  ASSERT_EQ(far.warnings_.size(), 1u);
  EXPECT_THAT(far.warnings_[0], HasSubstr("the declared station lies 9.9e+04 from the scan's "
                                          "bounding box, farther than its diagonal"));

  // A file with its own station (a PCD VIEWPOINT): dropped, or replaced.
  const std::string pcd = (dir_ / "posed.pcd").string();
  std::ofstream(pcd) << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                        "WIDTH 2\nHEIGHT 1\nVIEWPOINT 5 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
                        "1 0 0\n0 1 0\n";
  FakeContext dropped(dir_ / "dropped",
                      {{"path", pcd}, {"uncolored", "none"}, {"station", "none"}});
  ASSERT_TRUE(Run("io.read_points", dropped).ok());
  const PointCloud without = read_back(dropped);
  EXPECT_TRUE(without.stations.empty());
  EXPECT_TRUE(without.station_ids.empty());
  FakeContext kept(dir_ / "kept", {{"path", pcd}, {"uncolored", "none"}});
  ASSERT_TRUE(Run("io.read_points", kept).ok());
  EXPECT_EQ(read_back(kept).stations, (std::vector<std::array<double, 3>>{{5, 0, 0}}));
  EXPECT_EQ(kept.meta_["points"]["stations_from"], "file");
  FakeContext replaced(dir_ / "replaced",
                       {{"path", pcd}, {"uncolored", "none"}, {"station", "6,0,0"}});
  ASSERT_TRUE(Run("io.read_points", replaced).ok());
  EXPECT_EQ(read_back(replaced).stations, (std::vector<std::array<double, 3>>{{6, 0, 0}}));
  EXPECT_THAT(replaced.warnings_,
              ::testing::Contains(HasSubstr("the file's 1 station(s) replaced by the declared")));

  for (const nlohmann::json& bad : {nlohmann::json("1,2"), nlohmann::json("1,2,x"),
                                    nlohmann::json::array({1, 2}), nlohmann::json("here")}) {
    FakeContext ctx(dir_ / "bad", {{"path", xyz}, {"station", bad}});
    const Status status = Run("io.read_points", ctx);
    EXPECT_EQ(status.code(), Status::Code::kInvalid) << bad.dump();
    EXPECT_THAT(status.message(), HasSubstr("parameter 'station' must be")) << bad.dump();
    EXPECT_TRUE(ctx.outputs_.empty());
  }
}

// Colors an E57 marks as no measurement (isColorInvalid: typically black
// where no photo covered the point) take their nearest valid point's.
TEST_F(PointsStagesTest, ReadPointsFillsColorsTheFileMarksInvalid) {
  using pb::testing::Float64;
  using pb::testing::Integer;
  const auto write = [&](const std::string& name, std::vector<double> invalid) {
    pb::testing::TestScan scan;
    scan.fields = {Float64("cartesianX", {0, 0.4, 2, 2.9, 4}),
                   Float64("cartesianY", {0, 0, 0, 0, 0}),
                   Float64("cartesianZ", {0, 0, 0, 0, 0}),
                   Integer("colorRed", 0, 255, {10, 0, 30, 0, 50}),
                   Integer("colorGreen", 0, 255, {11, 0, 31, 0, 51}),
                   Integer("colorBlue", 0, 255, {12, 0, 32, 0, 52}),
                   Integer("isColorInvalid", 0, 1, std::move(invalid))};
    const std::vector<uint8_t> bytes = pb::testing::BuildE57({scan});
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    return path;
  };
  FakeContext ctx(dir_ / "filled", {{"path", write("some.e57", {0, 1, 0, 1, 0})}});
  ASSERT_TRUE(Run("io.read_points", ctx).ok());
  auto read = ReadPlyPoints(ctx.outputs_["points"]);
  ASSERT_TRUE(read.ok()) << read.status().message();
  // Point 1 (x 0.4) is nearest to point 0, point 3 (x 2.9) to point 2.
  EXPECT_EQ(read->points.colors,
            (std::vector<uint8_t>{10, 11, 12, 10, 11, 12, 30, 31, 32, 30, 31, 32, 50, 51, 52}));
  EXPECT_EQ(ctx.meta_["points"]["colors_from"], "file");
  ASSERT_EQ(ctx.warnings_.size(), 1u);
  EXPECT_THAT(ctx.warnings_[0], HasSubstr("2 points (40.00 %) have no valid color in the file "
                                          "(E57 isColorInvalid): each took its nearest valid "
                                          "point's"));
  // No valid color at all: the colors go, and the scan is painted grey.
  FakeContext none(dir_ / "none", {{"path", write("none.e57", {1, 1, 1, 1, 1})}});
  ASSERT_TRUE(Run("io.read_points", none).ok());
  EXPECT_EQ(none.meta_["points"]["colors_from"], "uniform grey");
  EXPECT_THAT(none.warnings_,
              ::testing::Contains(
                  HasSubstr("no point has a valid color (E57 isColorInvalid): colors dropped")));
  // Intensities alike (a scan without colors, painted grey by them).
  pb::testing::TestScan grey;
  grey.fields = {Float64("cartesianX", {0, 0.4, 2, 2.9, 4}), Float64("cartesianY", {0, 0, 0, 0, 0}),
                 Float64("cartesianZ", {0, 0, 0, 0, 0}),
                 Float64("intensity", {0.1, 0.9, 0.5, 0.0, 0.8}),
                 Integer("isIntensityInvalid", 0, 1, {0, 1, 0, 1, 0})};
  const std::vector<uint8_t> bytes = pb::testing::BuildE57({grey});
  const std::string grey_path = (dir_ / "grey.e57").string();
  std::ofstream(grey_path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  FakeContext painted(dir_ / "painted", {{"path", grey_path}});
  ASSERT_TRUE(Run("io.read_points", painted).ok());
  read = ReadPlyPoints(painted.outputs_["points"]);
  ASSERT_TRUE(read.ok());
  EXPECT_EQ(read->points.intensities, (std::vector<float>{0.1f, 0.1f, 0.5f, 0.5f, 0.8f}));
  EXPECT_EQ(painted.meta_["points"]["colors_from"], "intensity");
  EXPECT_THAT(painted.warnings_,
              ::testing::Contains(HasSubstr("2 points (40.00 %) have no valid intensity in the "
                                            "file (E57 isIntensityInvalid)")));
}

// A reader's warnings reach the warning channel, each naming the file once.
TEST_F(PointsStagesTest, ReadPointsPassesReaderWarningsOn) {
  const std::string data = SharedData();
  if (data.empty()) GTEST_SKIP() << "shared data not found";
  const std::string path = data + "/ptx/multiple-and-transform.ptx";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not found";
  FakeContext ctx(dir_, {{"path", path}, {"uncolored", "none"}});
  const Status status = Run("io.read_points", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.warnings_, std::vector<std::string>{path + ": 2 scans merged"});
  EXPECT_EQ(ctx.counters_["warnings"], 1);
}

// The pump's decoded PLY (row and col per point, no station): the stage says
// where it took the scanner, and the station is the file's.
TEST_F(PointsStagesTest, ReadPointsFindsTheScannerOfAPlysGrid) {
  const std::string data = SharedData();
  if (data.empty()) GTEST_SKIP() << "shared data not found";
  const std::string path = data + "/pump_e57/pumpA.ply";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not found";
  FakeContext ctx(dir_, {{"path", path}});
  const Status status = Run("io.read_points", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(ctx.warnings_.size(), 1u);
  EXPECT_THAT(ctx.warnings_[0], HasSubstr(path + ": structured scan (row and column per point) "
                                                 "without a station: its scanner taken at its "
                                                 "frame's origin"));
  EXPECT_EQ(ctx.meta_["points"]["stations"], 1);
  EXPECT_EQ(ctx.meta_["points"]["stations_from"], "file");
}

// With `station` set the file's grid is not tested: no warning says where the
// scanner was taken to be, or that it could not be found.
TEST_F(PointsStagesTest, ReadPointsSaysNothingOfTheFilesStationsWhenOneIsDeclared) {
  const std::string data = SharedData();
  if (data.empty()) GTEST_SKIP() << "shared data not found";
  const auto about_stations = [](const std::vector<std::string>& warnings) {
    int count = 0;
    for (const std::string& warning : warnings) {
      count += warning.find("scanner") != std::string::npos ||
               warning.find("sensor") != std::string::npos ||
               warning.find("station") != std::string::npos;
    }
    return count;
  };
  int i = 0;
  for (const char* file : {"pump_e57/pumpAVisualReferenceImage.e57", "pump_e57/pumpA.ply"}) {
    const std::string path = data + "/" + file;
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not found";
    FakeContext found(dir_ / std::to_string(i++), {{"path", path}});
    ASSERT_TRUE(Run("io.read_points", found).ok()) << file;
    EXPECT_EQ(about_stations(found.warnings_), 1) << file;
    EXPECT_EQ(found.meta_["points"]["stations_from"], "file") << file;
    for (const nlohmann::json& station : {nlohmann::json("none"), nlohmann::json("0,0,0.5")}) {
      FakeContext ctx(dir_ / std::to_string(i++), {{"path", path}, {"station", station}});
      const Status status = Run("io.read_points", ctx);
      ASSERT_TRUE(status.ok()) << file << ": " << status.message();
      EXPECT_EQ(about_stations(ctx.warnings_), 0) << file << " " << station;
      EXPECT_EQ(ctx.meta_["points"]["stations_from"], station == "none" ? "none" : "declared")
          << file;
      EXPECT_EQ(ctx.counters_["points"], found.counters_["points"]) << file;
    }
  }
}

TEST_F(PointsStagesTest, ReadPointsUnsupportedExtension) {
  FakeContext ctx(dir_, {{"path", (dir_ / "foo.obj").string()}, {"format", "auto"}});
  const Status status = Run("io.read_points", ctx);
  EXPECT_EQ(status.code(), Status::Code::kUnsupported);
  EXPECT_THAT(status.message(), HasSubstr("unsupported extension '.obj'"));
  EXPECT_THAT(status.message(), HasSubstr("formats supported now: ply (.ply), pcd (.pcd), xyz "
                                          "(.xyz .txt .pts .csv), ptx (.ptx), e57 (.e57), las "
                                          "(.las .laz)"));
  EXPECT_TRUE(ctx.outputs_.empty());
}

TEST_F(PointsStagesTest, ReadPointsEveryFormatByExtension) {
  const std::string shared = SharedData();
  if (shared.empty()) GTEST_SKIP() << "shared data not found";
  const std::filesystem::path data = shared;
  const std::pair<const char*, double> cases[] = {
      {"pump_e57/pumpAVisualReferenceImage.e57", 155201}, {"bunny/bunnyDouble.e57", 30571},
      {"office_kinect/office1.pcd", 254456},             {"livingroom_fragment/fragment.pcd", 113662},
      {"ptx/1.2-with-color.ptx", 1065},                  {"bunny/bun_zipper.ply", 35947}};
  int i = 0;
  for (const auto& [file, points] : cases) {
    FakeContext ctx(dir_ / std::to_string(i++), {{"path", (data / file).string()}});
    const Status status = Run("io.read_points", ctx);
    ASSERT_TRUE(status.ok()) << file << ": " << status.message();
    EXPECT_EQ(ctx.counters_["points"], points) << file;
  }
}

// A 30 x 30 grid 2 mm apart on z = 0 with a color per point, plus `far`
// points well off the plane.
PointCloud GridCloud(int far) {
  PointCloud cloud;
  cloud.origin = {500000.0, 4000000.0, 100.0};
  for (int y = 0; y < 30; ++y) {
    for (int x = 0; x < 30; ++x) {
      cloud.positions.insert(cloud.positions.end(), {0.002f * x, 0.002f * y, 0.0f});
      cloud.colors.insert(cloud.colors.end(), {static_cast<uint8_t>(x), static_cast<uint8_t>(y), 200});
    }
  }
  for (int i = 0; i < far; ++i) {
    cloud.positions.insert(cloud.positions.end(), {0.03f, 0.03f, 0.5f + 0.3f * i});
    cloud.colors.insert(cloud.colors.end(), {255, 0, 0});
  }
  return cloud;
}

TEST_F(PointsStagesTest, OutliersRemovesFarPoints) {
  const PointCloud cloud = GridCloud(2);
  const std::string input = (dir_ / "in.ply").string();
  ASSERT_TRUE(WritePlyPoints(input, cloud).ok());
  FakeContext ctx(dir_ / "o", {{"k", 16}, {"std_ratio", 2.0}});
  ctx.AddInput("points", "points", input, {{"scene", "grid"}, {"points", 902}});
  const Status status = Run("points.outliers", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["points_in"], 902);
  EXPECT_EQ(ctx.counters_["points_out"], 900);
  EXPECT_EQ(ctx.counters_["removed"], 2);
  EXPECT_EQ(ctx.phases_, (std::set<std::string>{"io", "compute"}));
  EXPECT_DOUBLE_EQ(ctx.last_progress_, 1.0);
  EXPECT_EQ(ctx.meta_["points"]["scene"], "grid");
  EXPECT_EQ(ctx.meta_["points"]["points"], 900);
  EXPECT_EQ(ctx.meta_["points"]["outliers_removed"], 2);
  auto out = ReadPlyPoints(ctx.outputs_["points"]);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(out->points.origin, cloud.origin);
  EXPECT_EQ(out->points.positions, std::vector<float>(cloud.positions.begin(), cloud.positions.begin() + 2700));
  EXPECT_EQ(out->points.colors, std::vector<uint8_t>(cloud.colors.begin(), cloud.colors.begin() + 2700));
}

TEST_F(PointsStagesTest, OutliersAirRemovesReturnsInTheAirAndNothingOfACleanScan) {
  // The 30 x 30 grid alone: nothing goes, no warning, the same points.
  const PointCloud clean = GridCloud(0);
  const std::string clean_path = (dir_ / "clean.ply").string();
  ASSERT_TRUE(WritePlyPoints(clean_path, clean).ok());
  FakeContext quiet(dir_ / "quiet", {{"method", "air"}});
  quiet.AddInput("points", "points", clean_path, {{"scene", "grid"}});
  Status status = Run("points.outliers", quiet);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(quiet.counters_["removed"], 0);
  EXPECT_LT(quiet.counters_["noise_m"], 1e-6);  // a flat grid: no noise off its plane
  EXPECT_TRUE(quiet.warnings_.empty());
  EXPECT_EQ(quiet.meta_["points"]["outliers_method"], "air");
  auto same = ReadPlyPoints(quiet.outputs_["points"]);
  ASSERT_TRUE(same.ok()) << same.status().message();
  EXPECT_EQ(same->points.positions, clean.positions);
  EXPECT_EQ(same->points.colors, clean.colors);

  // With 80 returns scattered 2 to 10 cm in front of it (a cloud of them,
  // as sparse as each other).
  PointCloud noisy = GridCloud(0);
  std::mt19937 engine(99);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  auto random = [&] { return unit(engine); };
  for (int i = 0; i < 80; ++i) {
    noisy.positions.insert(noisy.positions.end(), {0.06f * random(), 0.06f * random(), 0.02f + 0.08f * random()});
    noisy.colors.insert(noisy.colors.end(), {255, 0, 0});
  }
  const std::string noisy_path = (dir_ / "noisy.ply").string();
  ASSERT_TRUE(WritePlyPoints(noisy_path, noisy).ok());
  FakeContext ctx(dir_ / "air", {{"method", "air"}});
  ctx.AddInput("points", "points", noisy_path);
  status = Run("points.outliers", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_GE(ctx.counters_["removed"], 70);
  ASSERT_EQ(ctx.warnings_.size(), 1u);
  EXPECT_NE(ctx.warnings_[0].find("points are in the air"), std::string::npos) << ctx.warnings_[0];
  auto out = ReadPlyPoints(ctx.outputs_["points"]);
  ASSERT_TRUE(out.ok()) << out.status().message();
  // The grid's 900 points are all kept, first and in order.
  EXPECT_EQ(std::vector<float>(out->points.positions.begin(), out->points.positions.begin() + 2700), clean.positions);
  EXPECT_EQ(double(out->points.size()), 980 - ctx.counters_["removed"]);

  // Its options: k within 3..64, and its own implementation only.
  for (const nlohmann::json& bad : {nlohmann::json{{"method", "air"}, {"k", 100}},
                                    nlohmann::json{{"method", "air"}, {"implementation", "pcl"}},
                                    nlohmann::json{{"method", "air"}, {"spacing_ratio", 0.5}},
                                    nlohmann::json{{"method", "air"}, {"noise_tolerance", -1}}}) {
    FakeContext wrong(dir_ / "bad", bad);
    wrong.AddInput("points", "points", noisy_path);
    EXPECT_FALSE(Run("points.outliers", wrong).ok()) << bad.dump();
  }
}

TEST_F(PointsStagesTest, OutliersAirRemovesWhatAnotherStationSawThrough) {
  // A wall 1 m in front of two stations, each sampling it every 1 cm, and a
  // clump of 150 points 40 cm in front of it that only the first recorded
  // (a bird): the second saw the wall through it.
  PointCloud cloud;
  cloud.stations = {{-0.5, 0.0, 0.0}, {0.5, 0.0, 0.0}};
  for (uint16_t s = 0; s < 2; ++s)
    for (int i = 0; i < 200; ++i)
      for (int j = 0; j < 100; ++j) {
        cloud.positions.insert(cloud.positions.end(),
                               {-1.0f + 0.01f * float(i) + 0.005f * float(s), 1.0f, -0.5f + 0.01f * float(j)});
        cloud.colors.insert(cloud.colors.end(), {200, 200, 200});
        cloud.station_ids.push_back(s);
      }
  const size_t wall = cloud.size();
  std::mt19937 engine(3);
  std::normal_distribution<float> spread(0.0f, 0.01f);
  for (int i = 0; i < 150; ++i) {
    cloud.positions.insert(cloud.positions.end(), {spread(engine), 0.6f + spread(engine), spread(engine)});
    cloud.colors.insert(cloud.colors.end(), {0, 200, 255});
    cloud.station_ids.push_back(0);
  }
  const std::string path = (dir_ / "bird.ply").string();
  ASSERT_TRUE(WritePlyPoints(path, cloud).ok());
  FakeContext ctx(dir_ / "seen", {{"method", "air"}});
  ctx.AddInput("points", "points", path);
  Status status = Run("points.outliers", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["seen_through_stations"], 2);
  EXPECT_GE(ctx.counters_["seen_through"], 140);
  EXPECT_GE(ctx.counters_["seen_through_decided"], 0.9 * double(wall));
  auto out = ReadPlyPoints(ctx.outputs_["points"]);
  ASSERT_TRUE(out.ok()) << out.status().message();
  // The wall's points are all kept, first and in order.
  ASSERT_GE(out->points.size(), wall);
  EXPECT_EQ(std::vector<float>(out->points.positions.begin(), out->points.positions.begin() + ptrdiff_t(3 * wall)),
            std::vector<float>(cloud.positions.begin(), cloud.positions.begin() + ptrdiff_t(3 * wall)));
  EXPECT_EQ(out->points.stations.size(), 2u);
  bool warned = false;
  for (const std::string& warning : ctx.warnings_)
    warned |= warning.find("another scanner station saw through") != std::string::npos;
  EXPECT_TRUE(warned);

  // seen_through false: the clump is as dense as the wall and stays.
  FakeContext off(dir_ / "off", {{"method", "air"}, {"seen_through", false}});
  off.AddInput("points", "points", path);
  status = Run("points.outliers", off);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(off.counters_["seen_through"], 0);
  EXPECT_EQ(off.counters_["seen_through_stations"], 0);
  EXPECT_LT(off.counters_["removed"], 20);

  for (const nlohmann::json& bad : {nlohmann::json{{"method", "air"}, {"seen_through_spacings", -1}},
                                    nlohmann::json{{"method", "air"}, {"seen_through_range", -0.5}},
                                    nlohmann::json{{"method", "air"}, {"seen_through", "yes"}}}) {
    FakeContext wrong(dir_ / "bad", bad);
    wrong.AddInput("points", "points", path);
    EXPECT_FALSE(Run("points.outliers", wrong).ok()) << bad.dump();
  }
}

// The implementations in pointbake-pcl.so (built when libpcl-dev is
// installed; stages/CMakeLists.txt makes this test depend on it).
bool HavePclModule() { return ModuleSymbol(kPclModule, PB_PCL_SMOOTH_SYMBOL, "test").ok(); }

TEST_F(PointsStagesTest, OutliersWithPclRemovesTheSameFarPoints) {
  if (!HavePclModule()) GTEST_SKIP() << "this build has no pointbake-pcl.so";
  const std::string input = (dir_ / "in.ply").string();
  ASSERT_TRUE(WritePlyPoints(input, GridCloud(2)).ok());
  FakeContext ctx(dir_ / "o", {{"implementation", "pcl"}});
  ctx.AddInput("points", "points", input);
  const Status status = Run("points.outliers", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["removed"], 2);
  EXPECT_EQ(ctx.meta_["points"]["outliers_implementation"], "pcl");
  EXPECT_FALSE(ctx.meta_["points"].contains("outliers_threshold_m"));
}

TEST_F(PointsStagesTest, SmoothFlattensANoisyGridAndKeepsItsPoints) {
  if (!HavePclModule()) GTEST_SKIP() << "this build has no pointbake-pcl.so";
  PointCloud cloud = GridCloud(0);
  // 0.3 mm of Gaussian range noise on a 2 mm grid.
  std::mt19937 rng(4);
  std::normal_distribution<float> noise(0.0f, 0.0003f);
  for (size_t i = 0; i < cloud.size(); ++i) cloud.positions[3 * i + 2] = noise(rng);
  cloud.normals.assign(3 * cloud.size(), 0.0f);
  const std::string input = (dir_ / "in.ply").string();
  ASSERT_TRUE(WritePlyPoints(input, cloud).ok());
  FakeContext ctx(dir_ / "s", nlohmann::json::object(), 2);
  ctx.AddInput("points", "points", input, {{"spacing_m", 0.002}, {"has_normals", true}});
  const Status status = Run("points.smooth", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.phases_, (std::set<std::string>{"io", "compute"}));
  EXPECT_DOUBLE_EQ(ctx.last_progress_, 1.0);
  EXPECT_EQ(ctx.meta_["points"]["has_normals"], false);
  EXPECT_DOUBLE_EQ(ctx.meta_["points"]["smooth"]["radius_m"], 0.008);  // 4 spacings
  EXPECT_EQ(ctx.meta_["points"]["smooth"]["polynomial_order"], 2);
  EXPECT_GT(ctx.counters_["mean_shift_mm"], 0.1);
  auto out = ReadPlyPoints(ctx.outputs_["points"]);
  ASSERT_TRUE(out.ok()) << out.status().message();
  ASSERT_EQ(out->points.size(), cloud.size());
  EXPECT_EQ(out->points.origin, cloud.origin);
  EXPECT_EQ(out->points.colors, cloud.colors);
  EXPECT_FALSE(out->points.has_normals());
  double before = 0, after = 0;
  // Interior points (the fit is one-sided at the border).
  for (int y = 5; y < 25; ++y) {
    for (int x = 5; x < 25; ++x) {
      const size_t i = static_cast<size_t>(30 * y + x);
      before += std::abs(cloud.positions[3 * i + 2]);
      after += std::abs(out->points.positions[3 * i + 2]);
    }
  }
  EXPECT_LT(after, before / 2) << before << " -> " << after;

  FakeContext bad(dir_ / "b", {{"polynomial_order", 5}});
  bad.AddInput("points", "points", input);
  EXPECT_THAT(Run("points.smooth", bad).message(), HasSubstr("polynomial_order"));
}

TEST_F(PointsStagesTest, NormalsRejectsAnUnknownImplementation) {
  const std::string input = (dir_ / "in.ply").string();
  ASSERT_TRUE(WritePlyPoints(input, GridCloud(0)).ok());
  FakeContext ctx(dir_ / "n", {{"implementation", "cgal"}});
  ctx.AddInput("points", "points", input);
  EXPECT_THAT(Run("points.normals", ctx).message(), HasSubstr("implementation"));
}

TEST_F(PointsStagesTest, NormalsOfASphereFaceOutward) {
  PointCloud cloud;
  const int n = 4000;
  const double golden = 3.14159265358979323846 * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1.0 - z * z);
    cloud.positions.insert(cloud.positions.end(), {static_cast<float>(0.2 * r * std::cos(golden * i)),
                                                   static_cast<float>(0.2 * r * std::sin(golden * i)),
                                                   static_cast<float>(0.2 * z)});
  }
  const std::string input = (dir_ / "in.ply").string();
  ASSERT_TRUE(WritePlyPoints(input, cloud).ok());
  FakeContext ctx(dir_ / "n", {{"k", 12}, {"orientation", "auto"}});
  ctx.AddInput("points", "points", input, {{"spacing_m", 0.01}});
  const Status status = Run("points.normals", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["points"], n);
  EXPECT_TRUE(ctx.counters_.count("flipped"));
  EXPECT_EQ(ctx.phases_, (std::set<std::string>{"io", "compute"}));
  EXPECT_DOUBLE_EQ(ctx.last_progress_, 1.0);
  EXPECT_EQ(ctx.meta_["points"]["spacing_m"], 0.01);
  EXPECT_EQ(ctx.meta_["points"]["has_normals"], true);
  EXPECT_EQ(ctx.meta_["points"]["normals_k"], 12);
  EXPECT_EQ(ctx.meta_["points"]["normals_orientation"], "propagate");
  auto out = ReadPlyPoints(ctx.outputs_["points"]);
  ASSERT_TRUE(out.ok()) << out.status().message();
  ASSERT_EQ(out->points.normals.size(), 3u * n);
  for (int i = 0; i < n; ++i) {
    const float* p = &out->points.positions[3 * i];
    const float* normal = &out->points.normals[3 * i];
    ASSERT_GT((p[0] * normal[0] + p[1] * normal[1] + p[2] * normal[2]) / 0.2, 0.98) << "point " << i;
  }
}

// A room merged into one file without stations: the stage finds the space
// it encloses (counters) and faces its walls into it; `interior: no` keeps
// the outward rule and reports nothing.
TEST_F(PointsStagesTest, NormalsOfARoomWithoutStationsFaceIntoIt) {
  const std::string input = (dir_ / "room.ply").string();
  ASSERT_TRUE(WritePlyPoints(input, pb::testing::RoomWithTable(6.0, 4.5, 1.0, 7)).ok());
  // The share of the points on the wall x = 0 whose normal points into the room.
  auto wall_inward = [](const PointCloud& cloud) {
    size_t wall = 0, inward = 0;
    for (size_t i = 0; i < cloud.size(); ++i) {
      if (std::abs(cloud.positions[3 * i]) > 0.01 || cloud.positions[3 * i + 2] < 0.2) continue;
      ++wall, inward += cloud.normals[3 * i] > 0;
    }
    return double(inward) / double(wall);
  };
  for (const std::string interior : {"auto", "no"}) {
    FakeContext ctx(dir_ / interior, {{"interior", interior}});
    ctx.AddInput("points", "points", input);
    const Status status = Run("points.normals", ctx);
    ASSERT_TRUE(status.ok()) << status.message();
    auto out = ReadPlyPoints(ctx.outputs_["points"]);
    ASSERT_TRUE(out.ok()) << out.status().message();
    if (interior == "auto") {
      EXPECT_GT(ctx.counters_["enclosed_volume_m3"], 8.0);
      EXPECT_EQ(ctx.counters_["enclosure_open"], 0.0);
      EXPECT_GT(ctx.counters_["facing_enclosure"], 0.5 * double(out->points.size()));
      EXPECT_GT(wall_inward(out->points), 0.99);
    } else {
      EXPECT_EQ(ctx.counters_.count("enclosed_volume_m3"), 0u);
      EXPECT_LT(wall_inward(out->points), 0.01);
    }
  }
  FakeContext bad(dir_ / "bad", {{"interior", "maybe"}});
  bad.AddInput("points", "points", input);
  EXPECT_THAT(Run("points.normals", bad).message(), HasSubstr("interior"));
}

// The same room with a doorway 2.5 m wide: nearly enclosed (version 7),
// faced in, with a warning and the counter saying so.
TEST_F(PointsStagesTest, NormalsOfARoomOpenOnASideFaceIntoIt) {
  const std::string input = (dir_ / "open-room.ply").string();
  ASSERT_TRUE(WritePlyPoints(input, pb::testing::RoomWithTable(6.0, 4.5, 2.5, 7)).ok());
  FakeContext ctx(dir_ / "open", {});
  ctx.AddInput("points", "points", input);
  const Status status = Run("points.normals", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.counters_["enclosure_open"], 1.0);
  EXPECT_GT(ctx.counters_["enclosed_volume_m3"], 8.0);
  ASSERT_EQ(ctx.warnings_.size(), 1u);
  EXPECT_THAT(ctx.warnings_[0], HasSubstr("nearly enclose"));
  EXPECT_THAT(ctx.warnings_[0], HasSubstr("interior: no"));
  auto out = ReadPlyPoints(ctx.outputs_["points"]);
  ASSERT_TRUE(out.ok()) << out.status().message();
  size_t wall = 0, inward = 0;  // the wall x = 0
  for (size_t i = 0; i < out->points.size(); ++i) {
    if (std::abs(out->points.positions[3 * i]) > 0.01 || out->points.positions[3 * i + 2] < 0.2) continue;
    ++wall, inward += out->points.normals[3 * i] > 0;
  }
  EXPECT_GT(double(inward) / double(wall), 0.99);
}

// A file whose normals were computed without orienting them (random signs
// on a ball): the stage warns and propagates instead.
TEST_F(PointsStagesTest, NormalsWarnOfAFilesUnorientedNormals) {
  PointCloud ball;
  const double center[3] = {0, 0, 0};
  pb::testing::AddSphere(ball, center, 0.4, 8000, 0.0002, 4);
  for (size_t i = 0; i < ball.size(); ++i) {
    const float sign = (i * 2654435761u) % 7 < 3 ? -1.0f : 1.0f;
    for (int a = 0; a < 3; ++a) ball.normals.push_back(sign * ball.positions[3 * i + a]);
  }
  const std::string input = (dir_ / "ball.ply").string();
  ASSERT_TRUE(WritePlyPoints(input, ball).ok());
  FakeContext ctx(dir_ / "out", {});
  ctx.AddInput("points", "points", input);
  const Status status = Run("points.normals", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(ctx.meta_["points"]["normals_orientation"], "propagate");
  EXPECT_GT(ctx.counters_["input_sides_disagree"], 0.3);
  ASSERT_EQ(ctx.warnings_.size(), 1u);
  EXPECT_THAT(ctx.warnings_[0], HasSubstr("the normals the points came with (the scan file's own) "
                                           "face inconsistent sides"));
  EXPECT_THAT(ctx.warnings_[0], HasSubstr("oriented by propagation instead"));
}

// One scan exported without its station (the synthetic facade from one
// station, written without it): the stage finds where the scanner stood,
// says so and turns the normals toward it; find_station: false propagates.
TEST_F(PointsStagesTest, NormalsFindWhereOneScanStood) {
  pb::testing::ScanWithoutStations scan = pb::testing::FacadeWithoutStations(1, 40'000);
  ASSERT_EQ(scan.stations.size(), 1u);
  const std::array<double, 3> station = scan.stations[0];
  const PointCloud& cloud = scan.cloud;
  const std::string input = (dir_ / "one_scan.ply").string();
  ASSERT_TRUE(WritePlyPoints(input, cloud).ok());

  FakeContext found(dir_ / "found", {});
  found.AddInput("points", "points", input);
  Status status = Run("points.normals", found);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(found.meta_["points"]["normals_orientation"], "stations");
  EXPECT_EQ(found.counters_["station_found"], 1.0);
  const nlohmann::json& at = found.meta_["points"]["normals_station_found"];
  ASSERT_TRUE(at.is_array() && at.size() == 3) << found.meta_["points"].dump();
  EXPECT_LT(std::hypot(at[0].get<double>() - station[0], at[1].get<double>() - station[1],
                       at[2].get<double>() - station[2]),
            0.25);
  ASSERT_EQ(found.warnings_.size(), 1u);
  EXPECT_THAT(found.warnings_[0], HasSubstr("the points carry no scanner station, but the points are one scan's"));
  EXPECT_THAT(found.warnings_[0], HasSubstr("find_station: false"));

  FakeContext kept(dir_ / "kept", {{"find_station", false}});
  kept.AddInput("points", "points", input);
  status = Run("points.normals", kept);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(kept.meta_["points"]["normals_orientation"], "propagate");
  EXPECT_EQ(kept.counters_.count("station_found"), 0u);
  EXPECT_TRUE(kept.warnings_.empty());
}

TEST_F(PointsStagesTest, NormalsRejectsBadParameters) {
  const std::string input = (dir_ / "in.ply").string();
  ASSERT_TRUE(WritePlyPoints(input, GridCloud(0)).ok());
  FakeContext small_k(dir_ / "a", {{"k", 2}});
  small_k.AddInput("points", "points", input);
  EXPECT_THAT(Run("points.normals", small_k).message(), HasSubstr("parameter 'k' must be an integer in 3..100"));
  FakeContext stations(dir_ / "b", {{"orientation", "stations"}});
  stations.AddInput("points", "points", input);
  const Status status = Run("points.normals", stations);
  EXPECT_EQ(status.code(), Status::Code::kInvalid);
  EXPECT_THAT(status.message(), HasSubstr("orientation 'stations' needs per-point station ids"));
  EXPECT_TRUE(stations.meta_.empty());
  FakeContext sideways(dir_ / "c", {{"orientation", "sideways"}});
  sideways.AddInput("points", "points", input);
  EXPECT_THAT(Run("points.normals", sideways).message(),
              HasSubstr("parameter 'orientation' must be one of auto, stations, input, propagate, none; "
                        "got 'sideways'"));
}

TEST_F(PointsStagesTest, SpacingOfTwoMillimeterGrid) {
  const PointCloud cloud = GridCloud(0);
  const std::string input = (dir_ / "in.ply").string();
  ASSERT_TRUE(WritePlyPoints(input, cloud).ok());
  FakeContext ctx(dir_ / "s", {{"sample", 0}});
  ctx.AddInput("points", "points", input, {{"scene", "grid"}});
  const Status status = Run("points.spacing", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_NEAR(ctx.meta_["points"]["spacing_m"].get<double>(), 0.002, 1e-6);
  EXPECT_EQ(ctx.meta_["points"]["scene"], "grid");
  EXPECT_NEAR(ctx.counters_["spacing_mm"], 2.0, 1e-3);
  EXPECT_DOUBLE_EQ(ctx.last_progress_, 1.0);
  auto read_bytes = [](const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(file), {});
  };
  EXPECT_EQ(read_bytes(ctx.outputs_["points"]), read_bytes(input));
}

TEST_F(PointsStagesTest, SpacingNeedsTwoPoints) {
  PointCloud cloud;
  cloud.positions = {1, 2, 3};
  const std::string input = (dir_ / "in.ply").string();
  ASSERT_TRUE(WritePlyPoints(input, cloud).ok());
  FakeContext ctx(dir_ / "s", nlohmann::json::object());
  ctx.AddInput("points", "points", input);
  EXPECT_THAT(Run("points.spacing", ctx).message(), HasSubstr("needs at least 2 points, the cloud has 1"));
}

}  // namespace
}  // namespace pb
