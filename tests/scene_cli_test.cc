// End-to-end tests of `pointbake scene`: the real binary on scan files.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "stages/geometry/synth/scan_without_stations.h"
#include "tests/cli_test_util.h"

namespace pbtest {
namespace {

class SceneCli : public CliTest {
 protected:
  // An ASCII PLY: a sphere of radius 500 mm around (1000, 2000, 300) mm,
  // 4,000 points without colors, normals or stations.
  std::string WriteSphereMm() {
    const int n = 4000;
    std::string ply = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(n) +
                      "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    for (int i = 0; i < n; ++i) {
      const double z = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1.0 - z * z);
      const double phi = i * M_PI * (3.0 - std::sqrt(5.0));
      ply += std::to_string(1000 + 500 * r * std::cos(phi)) + " " +
             std::to_string(2000 + 500 * r * std::sin(phi)) + " " + std::to_string(300 + 500 * z) +
             "\n";
    }
    const std::string path = P("sphere_mm.ply");
    WriteFile(path, ply);
    return path;
  }
};

TEST_F(SceneCli, WritesASceneTheWorkflowsLoad) {
  const std::string scan = WriteSphereMm();
  const RunResult r = pbtest::Run({"scene", scan, "-o", P("scenes/sphere.yaml"), "--units", "mm"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  const std::string yaml = ReadFile(P("scenes/sphere.yaml"));
  EXPECT_NE(yaml.find("name: sphere_mm\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("units: mm\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("path: \"../sphere_mm.ply\""), std::string::npos)
      << yaml;  // relative to the scene
  EXPECT_NE(yaml.find("name: front"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("name: right"), std::string::npos) << yaml;
  // In mm, like the scan: the robust box's center, within its percentiles' step.
  EXPECT_NE(yaml.find("target: [1000."), std::string::npos) << yaml;
  EXPECT_NE(yaml.find(", 2000."), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("faces_high: 40000"), std::string::npos) << yaml;
  // Each shipped workflow takes it (a dry run resolves every ${scene...}).
  for (const char* workflow : {"hpm", "lpm", "remeshing", "point_transfer"}) {
    const RunResult check =
        pbtest::Run({"run", SourceDir() + "/configs/workflows/" + workflow + ".yaml", "--scene",
                     P("scenes/sphere.yaml"), "-n", "--cache", P("cache")});
    EXPECT_EQ(check.exit_code, 0) << check.Describe();
  }
}

// A scan from one station exported without it: without --station the
// scene says so and how to give it; with it, the views look from the
// station and the scene declares it to io.read_points, which the workflows
// read (a real run of the read, not only a dry run).
TEST_F(SceneCli, AStationTheFileLost) {
  const std::string scan = WriteSphereMm();
  const RunResult lost = pbtest::Run({"scene", scan, "-o", P("lost.yaml"), "--units", "mm"});
  ASSERT_EQ(lost.exit_code, 0) << lost.Describe();
  EXPECT_NE(lost.err.find("note: no scanner station"), std::string::npos) << lost.err;
  EXPECT_NE(ReadFile(P("lost.yaml")).find("# No scanner station: nothing says which side"), std::string::npos);
  const RunResult r =
      pbtest::Run({"scene", scan, "-o", P("station.yaml"), "--units", "mm", "--station", "2500,2000,300.5"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  EXPECT_EQ(r.err.find("note: no scanner station"), std::string::npos) << r.err;
  const std::string yaml = ReadFile(P("station.yaml"));
  EXPECT_NE(yaml.find("1 scanner station"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("station: [2500, 2000, 300.5] }"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("name: station1, eye: [2500, 2000"), std::string::npos) << yaml;
  const RunResult read = pbtest::Run({"run", SourceDir() + "/configs/workflows/point_transfer.yaml", "--scene",
                                      P("station.yaml"), "--until", "scan", "--cache", P("cache"), "--out",
                                      P("out")});
  ASSERT_EQ(read.exit_code, 0) << read.Describe();
  // In meters in the cloud, like its points.
  EXPECT_NE(ReadFile(P("out/scan.points.ply")).find("comment station 0 2.5 2 0.3004999"), std::string::npos);
  const RunResult bad = pbtest::Run({"scene", scan, "--station", "1,2"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--station 1,2: expected three numbers x,y,z"), std::string::npos) << bad.err;
}

// One scan exported without its station (a PLY of x, y, z in millimetres,
// georeferenced): the synthetic facade scanned from one station. The scene
// command finds where it stood (lost_station.h), says so, and declares it;
// --no-find-station leaves it out. Three stations' scans merged get none.
TEST_F(SceneCli, FindsWhereOneScanWasTaken) {
  auto write_facade = [&](int stations, const std::string& name, std::array<double, 3>* station) {
    const pb::testing::ScanWithoutStations scan = pb::testing::FacadeWithoutStations(stations, 40000 * uint64_t(stations));
    EXPECT_EQ(scan.stations.size(), size_t(stations));
    const std::array<double, 3> offset = {512345000, 5401234000, 210000};  // mm
    for (int a = 0; a < 3; ++a) (*station)[a] = scan.stations[0][a] * 1000 + offset[a];
    const size_t n = scan.cloud.size();
    std::string ply = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(n) +
                      "\nproperty double x\nproperty double y\nproperty double z\nend_header\n";
    char line[128];
    for (size_t i = 0; i < n; ++i) {
      const float* p = &scan.cloud.positions[3 * i];
      std::snprintf(line, sizeof line, "%.1f %.1f %.1f\n", p[0] * 1000.0 + offset[0], p[1] * 1000.0 + offset[1],
                    p[2] * 1000.0 + offset[2]);
      ply += line;
    }
    WriteFile(P(name), ply);
    return P(name);
  };
  std::array<double, 3> station{};
  const std::string one = write_facade(1, "one_scan_mm.ply", &station);
  const RunResult r = pbtest::Run({"scene", one, "-o", P("one.yaml"), "--units", "mm"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  EXPECT_NE(r.err.find("note: no scanner station in the file, but the points are one scan's"), std::string::npos)
      << r.err;
  const std::string yaml = ReadFile(P("one.yaml"));
  EXPECT_NE(yaml.find("1 scanner station (not in the file: found in the points)"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("# station: not in the file."), std::string::npos) << yaml;
  const size_t at = yaml.find("station: [");
  ASSERT_NE(at, std::string::npos) << yaml;
  std::array<double, 3> found{};
  ASSERT_EQ(std::sscanf(yaml.c_str() + at, "station: [%lf, %lf, %lf]", &found[0], &found[1], &found[2]), 3);
  EXPECT_LT(std::hypot(found[0] - station[0], found[1] - station[1], found[2] - station[2]), 300.0) << yaml;
  EXPECT_NE(yaml.find("name: station1"), std::string::npos) << yaml;

  const RunResult kept = pbtest::Run({"scene", one, "-o", P("kept.yaml"), "--units", "mm", "--no-find-station"});
  ASSERT_EQ(kept.exit_code, 0) << kept.Describe();
  EXPECT_NE(kept.err.find("note: no scanner station: if this is one scan"), std::string::npos) << kept.err;
  EXPECT_EQ(ReadFile(P("kept.yaml")).find("station: ["), std::string::npos);

  const std::string merged = write_facade(3, "merged_mm.ply", &station);
  const RunResult none = pbtest::Run({"scene", merged, "-o", P("merged.yaml"), "--units", "mm"});
  ASSERT_EQ(none.exit_code, 0) << none.Describe();
  EXPECT_NE(none.err.find("note: no scanner station (the sampling is not one scanner's"), std::string::npos)
      << none.err;
  EXPECT_EQ(ReadFile(P("merged.yaml")).find("station: ["), std::string::npos);
}

TEST_F(SceneCli, KeepsAnExistingFileUnlessForced) {
  const std::string scan = WriteSphereMm();
  WriteFile(P("mine.yaml"), "name: mine\n");
  const RunResult kept = pbtest::Run({"scene", scan, "-o", P("mine.yaml"), "--units", "mm"});
  EXPECT_EQ(kept.exit_code, 2) << kept.Describe();
  EXPECT_NE(kept.err.find("--force"), std::string::npos) << kept.err;
  EXPECT_EQ(ReadFile(P("mine.yaml")), "name: mine\n");
  const RunResult forced =
      pbtest::Run({"scene", scan, "-o", P("mine.yaml"), "--units", "mm", "--force"});
  EXPECT_EQ(forced.exit_code, 0) << forced.Describe();
  EXPECT_NE(ReadFile(P("mine.yaml")).find("viewpoints:"), std::string::npos);
}

TEST_F(SceneCli, AFileNameWithQuotesAndBackslashes) {
  const std::string scan = WriteSphereMm();
  const std::string odd = P("my \"scan\" \\ 2.ply");
  ASSERT_EQ(std::rename(scan.c_str(), odd.c_str()), 0);
  const RunResult r = pbtest::Run({"scene", odd, "-o", P("odd.yaml"), "--units", "mm"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  const RunResult dry = pbtest::Run({"run", SourceDir() + "/configs/workflows/lpm.yaml", "--scene",
                                     P("odd.yaml"), "-n", "--cache", P("cache")});
  EXPECT_EQ(dry.exit_code, 0) << dry.Describe();
}

TEST_F(SceneCli, ToStdoutWithTheAbsolutePathAndAUnitsHint) {
  const std::string scan = WriteSphereMm();
  const RunResult r = pbtest::Run({"scene", scan});  // meters: a 4 mm-spaced sphere read as 4 m
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  EXPECT_NE(r.out.find("path: \"" + scan + "\""), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("--units mm"), std::string::npos) << r.err;
}

TEST_F(SceneCli, BadInputSaysWhat) {
  const RunResult missing = pbtest::Run({"scene", P("nowhere.e57")});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("nowhere.e57: file not found"), std::string::npos) << missing.err;
  const std::string scan = WriteSphereMm();
  const RunResult up = pbtest::Run({"scene", scan, "--up", "0,0"});
  EXPECT_EQ(up.exit_code, 2);
  EXPECT_NE(up.err.find("--up 0,0"), std::string::npos) << up.err;
  WriteFile(P("truncated.ply"), "ply\nformat ascii 1.0\nelement vertex 10\nproperty float x\n");
  const RunResult truncated = pbtest::Run({"scene", P("truncated.ply")});
  EXPECT_EQ(truncated.exit_code, 2);
  EXPECT_NE(truncated.err.find("truncated.ply"), std::string::npos) << truncated.err;
}

// The pump scan of the shared samples: its station gives the view the
// hand-written configs/scenes/pump.yaml has (eye [0, 0, 0.2], target
// [-0.64, -2.57, -1.0]), and the same depths.
TEST_F(SceneCli, ThePumpScanAsItsHandWrittenScene) {
  const std::string scan = SourceDir() + "/../shared/data/pump_e57/pumpAVisualReferenceImage.e57";
  if (!Exists(scan)) GTEST_SKIP() << scan << " is not there";
  const RunResult r = pbtest::Run({"scene", scan, "-o", P("pump.yaml")});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  const std::string yaml = ReadFile(P("pump.yaml"));
  EXPECT_NE(yaml.find("1 scanner station"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("name: station1, eye: [0, 0, 0.15"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("depth_high: 10"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("depth_low: 8"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("name: oblique"), std::string::npos) << yaml;
}

}  // namespace
}  // namespace pbtest
