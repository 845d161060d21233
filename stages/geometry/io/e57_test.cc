#include "stages/geometry/io/e57.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <numbers>
#include <sstream>

#include "stages/geometry/io/e57_binary.h"
#include "stages/geometry/io/e57_xml.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/io/e57_test_writer.h"
#include "stages/geometry/io/grid_sweep_test_util.h"
#include "stages/geometry/testing/test_data.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

std::string SharedData() { return pb::testing::SharedDataDir(); }

using pb::testing::AppendLe;
using pb::testing::BuildE57;
using pb::testing::Float32;
using pb::testing::Float64;
using pb::testing::Integer;
using pb::testing::PutLe;
using pb::testing::Scaled;
using pb::testing::TestField;
using pb::testing::TestScan;
using pb::testing::WriterOptions;

class E57Test : public pb::testing::TempDirTest {
 protected:
  std::string Write(const std::string& name, const std::vector<uint8_t>& bytes) const {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
    return path;
  }
  std::string WriteScans(const std::vector<TestScan>& scans, const WriterOptions& options = {}) {
    return Write("t.e57", BuildE57(scans, options));
  }
  // Reads a file expected to fail; returns its message.
  std::string Error(const std::string& path, const ScanReadOptions& options = {}) {
    auto read = ReadE57(path, options);
    EXPECT_FALSE(read.ok());
    return read.ok() ? "" : read.status().message();
  }

};

std::vector<uint8_t> ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

TestScan XyzScan(std::vector<double> x, std::vector<double> y, std::vector<double> z) {
  TestScan scan;
  scan.fields = {Float64("cartesianX", std::move(x)), Float64("cartesianY", std::move(y)),
                 Float64("cartesianZ", std::move(z))};
  return scan;
}

// ---------------------------------------------------------------------------
// Shared sample files.

TEST_F(E57Test, PumpMatchesDecodedPly) {
  const std::string data = SharedData();
  if (data.empty()) GTEST_SKIP() << "shared data not found";
  int progress_calls = 0;
  ScanReadOptions options;
  options.progress = [&](double) { ++progress_calls; };
  auto read = ReadE57(data + "/pump_e57/pumpAVisualReferenceImage.e57", options);
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  EXPECT_EQ(read->format, "e57");
  EXPECT_EQ(cloud.size(), 155201u);
  EXPECT_EQ(read->dropped_points, 0u);
  ASSERT_TRUE(cloud.has_colors());
  ASSERT_TRUE(cloud.has_intensities());
  // No pose in this file, but its 1074 x 345 grid was swept from its
  // frame's origin: the scanner stood there (grid_station.h).
  ASSERT_TRUE(cloud.has_stations());
  EXPECT_EQ(cloud.stations, (std::vector<std::array<double, 3>>{{0, 0, 0}}));
  EXPECT_EQ(cloud.station_ids, std::vector<uint16_t>(cloud.size(), 0));
  ASSERT_EQ(read->warnings.size(), 1u);
  EXPECT_THAT(read->warnings[0],
              HasSubstr("data3D scan 0 has no pose: its scanner taken at its frame's origin "
                        "(seen from there, 99.9 % of the 303204 steps"));
  EXPECT_GE(progress_calls, 1);
  EXPECT_TRUE(Validate(cloud).ok());
  for (float intensity : cloud.intensities) {
    ASSERT_GE(intensity, 0.f);
    ASSERT_LE(intensity, 1.f);
  }

  auto ply = ReadPlyPoints(data + "/pump_e57/pumpA.ply");
  ASSERT_TRUE(ply.ok()) << ply.status().message();
  ASSERT_EQ(ply->points.size(), cloud.size());
  for (size_t i :
       {size_t{0}, size_t{1}, size_t{2}, size_t{3}, size_t{4}, size_t{77777}, cloud.size() - 1}) {
    for (int a = 0; a < 3; ++a) {
      const double e57 = cloud.origin[a] + cloud.positions[3 * i + a];
      const double reference = ply->points.origin[a] + ply->points.positions[3 * i + a];
      EXPECT_NEAR(e57, reference, 1e-4) << "point " << i << " axis " << a;
      EXPECT_EQ(cloud.colors[3 * i + a], ply->points.colors[3 * i + a]) << "point " << i;
    }
  }
  // Bounding box agrees with the file's own cartesianBounds.
  const Bounds bounds = AbsoluteBounds(cloud);
  EXPECT_NEAR(bounds.min_m[0], -2.903764, 1e-5);
  EXPECT_NEAR(bounds.max_m[1], -0.792647, 1e-5);
  EXPECT_NEAR(bounds.max_m[2], 1.843003, 1e-5);
}

TEST_F(E57Test, BunnyDoubles) {
  const std::string data = SharedData();
  if (data.empty()) GTEST_SKIP() << "shared data not found";
  auto read = ReadE57(data + "/bunny/bunnyDouble.e57", {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.size(), 30571u);
  EXPECT_FALSE(read->points.has_colors());
  EXPECT_FALSE(read->points.has_intensities());
  EXPECT_EQ(read->dropped_points, 0u);
  const Bounds bounds = AbsoluteBounds(read->points);
  EXPECT_NEAR(bounds.min_m[0], -0.094689, 1e-6);
  EXPECT_NEAR(bounds.max_m[0], 0.061009, 1e-6);
  EXPECT_NEAR(bounds.min_m[1], 0.040011, 1e-6);
  EXPECT_NEAR(bounds.max_m[1], 0.187321, 1e-6);
  EXPECT_NEAR(bounds.min_m[2], -0.061873, 1e-6);
  EXPECT_NEAR(bounds.max_m[2], 0.058799, 1e-6);
  EXPECT_EQ(read->points.origin, (std::array<double, 3>{0, 0, 0}));
  // Merged range images without pose or grid: no scanner known, nothing to say.
  EXPECT_FALSE(read->points.has_stations());
  EXPECT_TRUE(read->warnings.empty());
}

TEST_F(E57Test, FlippedByteIsCrcErrorNamingThePage) {
  const std::string data = SharedData();
  if (data.empty()) GTEST_SKIP() << "shared data not found";
  std::vector<uint8_t> bytes = ReadBytes(data + "/bunny/bunnyDouble.e57");
  ASSERT_GT(bytes.size(), 400000u);
  bytes[300 * 1024 + 517] ^= 0x10;  // inside the point data
  EXPECT_THAT(Error(Write("flipped.e57", bytes)),
              HasSubstr("flipped.e57: CRC-32C mismatch in page 300 (byte 307200)"));
}

TEST_F(E57Test, TruncatedCopy) {
  const std::string data = SharedData();
  if (data.empty()) GTEST_SKIP() << "shared data not found";
  std::vector<uint8_t> bytes = ReadBytes(data + "/bunny/bunnyDouble.e57");
  bytes.resize(500000);
  EXPECT_THAT(Error(Write("short.e57", bytes)),
              HasSubstr("short.e57: truncated: the header says 743424 bytes, the file has 500000"));
}

// ---------------------------------------------------------------------------
// Hand-made files.

TEST_F(E57Test, Crc32cKnownValue) {
  const char* check = "123456789";
  EXPECT_EQ(e57::Crc32c(reinterpret_cast<const uint8_t*>(check), 9), 0xE3069283u);
}

TEST_F(E57Test, CartesianFloatSingle) {
  TestScan scan;
  scan.fields = {Float32("cartesianX", {1.5, -2.25, 100.125}),
                 Float32("cartesianY", {0.0, 3.0, 200.0}),
                 Float32("cartesianZ", {-1.0, 0.5, 300.75})};
  auto read = ReadE57(WriteScans({scan}), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  ASSERT_EQ(cloud.size(), 3u);
  // bbox center (48.9375, 100, 149.875) rounded to 1 m.
  EXPECT_EQ(cloud.origin, (std::array<double, 3>{49, 100, 150}));
  EXPECT_EQ(cloud.positions,
            (std::vector<float>{1.5f - 49, 0 - 100, -1 - 150, -2.25f - 49, 3 - 100, 0.5f - 150,
                                100.125f - 49, 200 - 100, 300.75f - 150}));
  EXPECT_FALSE(cloud.has_colors());
  EXPECT_FALSE(cloud.has_stations());
  EXPECT_TRUE(read->warnings.empty());
}

TEST_F(E57Test, ScaledIntegersStraddlePackets) {
  // 24-bit values in 7-byte packet slices: most values cross a packet boundary.
  std::vector<double> x, y, z;
  for (int i = 0; i < 1000; ++i) {
    x.push_back(i * 37 % 100000 - 50000);
    y.push_back(8388607 - i);
    z.push_back(-8388608 + i * 3);
  }
  TestScan scan;
  scan.fields = {Scaled("cartesianX", -8388608, 8388607, 0.001, 0.0, x),
                 Scaled("cartesianY", -8388608, 8388607, 0.001, 0.0, y),
                 Scaled("cartesianZ", -8388608, 8388607, 0.001, 5000.0, z)};
  auto read = ReadE57(WriteScans({scan}), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  ASSERT_EQ(cloud.size(), 1000u);
  for (size_t i : {size_t{0}, size_t{1}, size_t{2}, size_t{500}, size_t{999}}) {
    // 1e-5: float32 resolution; one raw step is 1e-3.
    EXPECT_NEAR(cloud.origin[0] + cloud.positions[3 * i], x[i] * 0.001, 1e-5) << i;
    EXPECT_NEAR(cloud.origin[1] + cloud.positions[3 * i + 1], y[i] * 0.001, 1e-5) << i;
    EXPECT_NEAR(cloud.origin[2] + cloud.positions[3 * i + 2], z[i] * 0.001 + 5000.0, 1e-4) << i;
  }
}

TEST_F(E57Test, SphericalConvertedToCartesian) {
  const double pi = std::numbers::pi;
  TestScan scan;
  scan.fields = {Float64("sphericalRange", {2.0, 3.0, 4.0}),
                 Float64("sphericalAzimuth", {0.0, pi / 2, pi / 4}),
                 Float64("sphericalElevation", {0.0, 0.0, pi / 6})};
  auto read = ReadE57(WriteScans({scan}), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  ASSERT_EQ(cloud.size(), 3u);
  const double expected[3][3] = {{2, 0, 0},
                                 {0, 3, 0},
                                 {4 * std::cos(pi / 6) * std::cos(pi / 4),
                                  4 * std::cos(pi / 6) * std::sin(pi / 4), 4 * std::sin(pi / 6)}};
  for (int i = 0; i < 3; ++i) {
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(cloud.origin[a] + cloud.positions[3 * i + a], expected[i][a], 1e-6);
    }
  }
}

TEST_F(E57Test, InvalidStatesAreDroppedAndCounted) {
  TestScan scan = XyzScan({1, 2, 3, 4}, {1, 2, 3, 4}, {1, 2, 3, 4});
  scan.fields.push_back(Integer("cartesianInvalidState", 0, 2, {0, 1, 0, 2}));
  scan.fields.push_back(Integer("rowIndex", 0, 2047, {5, 6, 7, 8}));  // alone: no grid
  auto read = ReadE57(WriteScans({scan}), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->no_return_points, 2u);
  EXPECT_EQ(read->dropped_points, 0u);
  ASSERT_EQ(read->points.size(), 2u);
  EXPECT_EQ(read->points.origin, (std::array<double, 3>{2, 2, 2}));
  EXPECT_EQ(read->points.positions, (std::vector<float>{-1, -1, -1, 1, 1, 1}));
}

TEST_F(E57Test, TwoScansWithPosesMerge) {
  // Scan 0: rotated 90 degrees about z, then moved by (1000, 2000, 10).
  TestScan a = XyzScan({1, 2}, {0, 0}, {0, 1});
  const double half = std::sqrt(0.5);
  std::ostringstream pose;
  pose.precision(17);
  pose << "<pose type=\"Structure\"><rotation type=\"Structure\"><w type=\"Float\">" << half
       << "</w><x type=\"Float\"/><y type=\"Float\"/><z type=\"Float\">" << half
       << "</z></rotation><translation type=\"Structure\"><x type=\"Float\">1000</x>"
          "<y type=\"Float\">2000</y><z type=\"Float\">10</z></translation></pose>";
  a.extra_xml = pose.str();
  // Scan 1: identity rotation (element omitted), moved by (1002, 2000, 10).
  TestScan b = XyzScan({0}, {0}, {0});
  b.extra_xml =
      "<pose type=\"Structure\"><translation type=\"Structure\"><x type=\"Float\">1002</x>"
      "<y type=\"Float\">2000</y><z type=\"Float\">10</z></translation></pose>";
  auto read = ReadE57(WriteScans({a, b}), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  ASSERT_EQ(cloud.size(), 3u);
  // Absolute: (1000, 2001, 10), (1000, 2002, 11), (1002, 2000, 10).
  const double expected[3][3] = {{1000, 2001, 10}, {1000, 2002, 11}, {1002, 2000, 10}};
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(cloud.origin[k] + cloud.positions[3 * i + k], expected[i][k], 1e-6);
    }
  }
  EXPECT_EQ(cloud.origin, (std::array<double, 3>{1001, 2001, 11}));  // 10.5 rounds away from 0
  ASSERT_EQ(cloud.stations.size(), 2u);
  EXPECT_EQ(cloud.stations[0], (std::array<double, 3>{1000, 2000, 10}));
  EXPECT_EQ(cloud.stations[1], (std::array<double, 3>{1002, 2000, 10}));
  EXPECT_EQ(cloud.station_ids, (std::vector<uint16_t>{0, 0, 1}));
  EXPECT_THAT(read->warnings, ::testing::Contains("2 scans merged"));
}

// A structured scan without a pose: a grid of `rows` x `columns` records,
// column after column, grid_sweep_test_util.h's sweep from `station`.
TestScan GridScan(int rows, int columns, const std::array<double, 3>& station) {
  std::vector<double> x, y, z, row_index, column_index;
  for (int column = 0; column < columns; ++column) {
    for (int row = 0; row < rows; ++row) {
      const std::array<double, 3> p = pb::testing::SweptPoint(station.data(), row, column);
      x.push_back(p[0]);
      y.push_back(p[1]);
      z.push_back(p[2]);
      row_index.push_back(row);
      column_index.push_back(column);
    }
  }
  TestScan scan = XyzScan(std::move(x), std::move(y), std::move(z));
  scan.fields.push_back(Integer("rowIndex", 0, rows - 1, std::move(row_index)));
  scan.fields.push_back(Integer("columnIndex", 0, columns - 1, std::move(column_index)));
  return scan;
}

TEST_F(E57Test, APoselessGridScanHasItsScannerAtItsOrigin) {
  auto read = ReadE57(WriteScans({GridScan(30, 25, {0, 0, 0})}), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  EXPECT_EQ(cloud.stations, (std::vector<std::array<double, 3>>{{0, 0, 0}}));
  EXPECT_EQ(cloud.station_ids, std::vector<uint16_t>(750, 0));
  EXPECT_THAT(read->warnings,
              ::testing::Contains(HasSubstr("data3D scan 0 has no pose: its scanner taken at "
                                            "its frame's origin (seen from there, 100.0 %")));
  // Every 7th record invalid (no return): left out, its neighbours two cells
  // apart, the same verdict.
  TestScan holed = GridScan(30, 25, {0, 0, 0});
  std::vector<double> state(750, 0);
  for (size_t i = 3; i < state.size(); i += 7) state[i] = 2;
  holed.fields.push_back(Integer("cartesianInvalidState", 0, 2, state));
  auto with_holes = ReadE57(WriteScans({holed}), {});
  ASSERT_TRUE(with_holes.ok()) << with_holes.status().message();
  EXPECT_EQ(with_holes->no_return_points, 107u);
  EXPECT_EQ(with_holes->dropped_points, 0u);
  EXPECT_EQ(with_holes->points.stations, (std::vector<std::array<double, 3>>{{0, 0, 0}}));
  EXPECT_EQ(with_holes->points.station_ids.size(), 750u - 107u);
}

TEST_F(E57Test, APoselessGridScanSweptFromElsewhereHasNoStation) {
  // The registration baked into the coordinates: the scanner 30 cm off.
  auto read = ReadE57(WriteScans({GridScan(30, 25, {0.3, 0, 0})}), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_FALSE(read->points.has_stations());
  EXPECT_TRUE(read->points.stations.empty());
  EXPECT_THAT(read->warnings,
              ::testing::Contains(HasSubstr("no scanner stations: data3D scan 0 has no pose, and "
                                            "its grid does not show its frame's origin as its "
                                            "scanner's (seen from there")));
  // Too small a grid to tell: no station either.
  auto small = ReadE57(WriteScans({GridScan(10, 10, {0, 0, 0})}), {});
  ASSERT_TRUE(small.ok()) << small.status().message();
  EXPECT_FALSE(small->points.has_stations());
  EXPECT_THAT(small->warnings,
              ::testing::Contains(HasSubstr("data3D scan 0 has no pose, and its grid cannot tell "
                                            "whether its frame's origin is its scanner's (")));
  // The caller sets the stations itself: no test, no station, no word of them.
  ScanReadOptions declared;
  declared.infer_stations = false;
  for (const std::array<double, 3> station : {std::array<double, 3>{0.3, 0, 0}, {0, 0, 0}}) {
    auto caller = ReadE57(WriteScans({GridScan(30, 25, station)}), declared);
    ASSERT_TRUE(caller.ok()) << caller.status().message();
    EXPECT_FALSE(caller->points.has_stations());
    EXPECT_TRUE(caller->warnings.empty());
    EXPECT_EQ(caller->points.size(), 750u);
  }
}

TEST_F(E57Test, APoselessSphericalScanHasItsScannerAtItsOrigin) {
  TestScan scan;
  scan.fields = {Float64("sphericalRange", {2.0, 3.0}), Float64("sphericalAzimuth", {0.0, 1.0}),
                 Float64("sphericalElevation", {0.0, 0.5})};
  auto read = ReadE57(WriteScans({scan}), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.stations, (std::vector<std::array<double, 3>>{{0, 0, 0}}));
  EXPECT_EQ(read->points.station_ids, (std::vector<uint16_t>{0, 0}));
  EXPECT_THAT(read->warnings,
              ::testing::ElementsAre("data3D scan 0 has no pose: its scanner taken at its "
                                     "frame's origin, from which its spherical coordinates are "
                                     "measured"));
  // Five such scans: all at the origin; three lines say so, the third for the rest.
  auto five = ReadE57(WriteScans({scan, scan, scan, scan, scan}), {});
  ASSERT_TRUE(five.ok()) << five.status().message();
  EXPECT_EQ(five->points.stations.size(), 5u);
  EXPECT_EQ(five->points.station_ids, (std::vector<uint16_t>{0, 0, 1, 1, 2, 2, 3, 3, 4, 4}));
  EXPECT_THAT(five->warnings,
              ::testing::ElementsAre("5 scans merged", HasSubstr("data3D scan 0 has no pose"),
                                     HasSubstr("data3D scan 1 has no pose"),
                                     HasSubstr("measured (and 2 more scans alike)")));
}

TEST_F(E57Test, StationsNeedEveryScansScanner) {
  // Scan 0 posed, scan 1 neither posed nor gridded: no stations at all (a
  // normal without its scanner cannot be oriented by one), and why.
  TestScan a = XyzScan({1, 2}, {0, 0}, {0, 1});
  a.extra_xml =
      "<pose type=\"Structure\"><translation type=\"Structure\"><x type=\"Float\">3</x>"
      "</translation></pose>";
  auto read = ReadE57(WriteScans({a, XyzScan({0}, {0}, {0})}), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_TRUE(read->points.stations.empty());
  EXPECT_TRUE(read->points.station_ids.empty());
  EXPECT_THAT(read->warnings,
              ::testing::Contains("no scanner stations: data3D scan 1 has no pose and no "
                                  "row/column grid; io.read_points `station` can declare where "
                                  "one scanner stood"));
  // A poseless scan swept from its origin beside one without pose or grid:
  // no stations, and no line saying the first one's scanner was found.
  auto mixed = ReadE57(WriteScans({GridScan(30, 25, {0, 0, 0}), XyzScan({0}, {0}, {1})}), {});
  ASSERT_TRUE(mixed.ok()) << mixed.status().message();
  EXPECT_TRUE(mixed->points.stations.empty());
  EXPECT_THAT(mixed->warnings, ::testing::ElementsAre(
                                   "2 scans merged", HasSubstr("no scanner stations: data3D scan "
                                                               "1 has no pose and no row/column")));
  // A posed scan and a poseless one swept from its origin: both stations.
  auto both = ReadE57(WriteScans({a, GridScan(30, 25, {0, 0, 0})}), {});
  ASSERT_TRUE(both.ok()) << both.status().message();
  EXPECT_EQ(both->points.stations, (std::vector<std::array<double, 3>>{{3, 0, 0}, {0, 0, 0}}));
  ASSERT_EQ(both->points.station_ids.size(), 752u);
  EXPECT_EQ(both->points.station_ids[1], 0);
  EXPECT_EQ(both->points.station_ids[2], 1);
}

TEST_F(E57Test, ColorAndIntensityNormalizedByLimits) {
  TestScan scan = XyzScan({0, 1, 2}, {0, 0, 0}, {0, 0, 0});
  scan.fields.push_back(Integer("colorRed", 0, 1023, {0, 1023, 512}));
  scan.fields.push_back(Integer("colorGreen", 0, 1023, {100, 200, 300}));
  scan.fields.push_back(Integer("colorBlue", 0, 1023, {0, 0, 1023}));
  scan.fields.push_back(Scaled("intensity", 0, 4095, 0.01, 0.0, {0, 2000, 4000}));
  // Green uses its own limits 100..300; red and blue fall back to 0..1023.
  scan.extra_xml =
      "<colorLimits type=\"Structure\"><colorGreenMinimum type=\"Integer\">100</colorGreenMinimum>"
      "<colorGreenMaximum type=\"Integer\">300</colorGreenMaximum></colorLimits>"
      "<intensityLimits type=\"Structure\"><intensityMinimum type=\"Float\"/>"
      "<intensityMaximum type=\"ScaledInteger\" scale=\"0.01\">4000</intensityMaximum>"
      "</intensityLimits>";
  auto read = ReadE57(WriteScans({scan}), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.colors, (std::vector<uint8_t>{0, 0, 0, 255, 128, 0, 128, 255, 255}));
  ASSERT_EQ(read->points.intensities.size(), 3u);
  EXPECT_FLOAT_EQ(read->points.intensities[0], 0.f);
  EXPECT_FLOAT_EQ(read->points.intensities[1], 0.5f);
  EXPECT_FLOAT_EQ(read->points.intensities[2], 1.f);
}

TEST_F(E57Test, ColorsAndIntensitiesMarkedInvalidAreListed) {
  TestScan scan = XyzScan({0, 1, 2, 3}, {0, 0, 0, 0}, {0, 0, 0, 0});
  scan.fields.push_back(Integer("colorRed", 0, 255, {10, 0, 30, 0}));
  scan.fields.push_back(Integer("colorGreen", 0, 255, {10, 0, 30, 0}));
  scan.fields.push_back(Integer("colorBlue", 0, 255, {10, 0, 30, 0}));
  scan.fields.push_back(Integer("isColorInvalid", 0, 1, {0, 1, 0, 1}));
  scan.fields.push_back(Float64("intensity", {0.1, 0.2, 0.3, 0.4}));
  scan.fields.push_back(Integer("isIntensityInvalid", 0, 1, {0, 0, 1, 0}));
  scan.fields.push_back(Integer("cartesianInvalidState", 0, 2, {2, 0, 0, 0}));  // 0 dropped
  auto read = ReadE57(WriteScans({scan}), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  ASSERT_EQ(read->points.size(), 3u);
  // Indices into the points read (the first record was dropped).
  EXPECT_EQ(read->colorless_points, (std::vector<size_t>{0, 2}));
  EXPECT_EQ(read->intensityless_points, (std::vector<size_t>{1}));
  // Without the flags: nothing listed.
  auto plain = ReadE57(WriteScans({XyzScan({0, 1}, {0, 0}, {0, 0})}), {});
  ASSERT_TRUE(plain.ok());
  EXPECT_TRUE(plain->colorless_points.empty());
  EXPECT_TRUE(plain->intensityless_points.empty());
}

TEST_F(E57Test, NonFiniteCoordinateFailsOrIsDropped) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::string path = WriteScans({XyzScan({0, 1, nan}, {0, 1, 2}, {0, 1, 2})});
  EXPECT_THAT(Error(path), HasSubstr("t.e57: data3D scan 0 point 2 has a NaN or infinite"));
  ScanReadOptions options;
  options.drop_invalid_points = true;
  auto read = ReadE57(path, options);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.size(), 2u);
  EXPECT_EQ(read->dropped_points, 1u);
  EXPECT_EQ(read->no_return_points, 0u);
}

TEST(E57XmlTest, ParsesEntitiesCdataAndPrefixes) {
  auto root = e57::ParseXml(
      "<?xml version=\"1.0\"?>\n<!-- c -->\n<a k='&lt;&amp;&#65;&#x42;'>x &gt; y<![CDATA[<raw>]]>"
      "<nor:n type=\"Float\"/></a>\n");
  ASSERT_TRUE(root.ok()) << root.status().message();
  EXPECT_EQ(*root->Attribute("k"), "<&AB");
  EXPECT_EQ(root->text, "x > y<raw>");
  ASSERT_EQ(root->children.size(), 1u);
  EXPECT_EQ(root->children[0].Prefix(), "nor");
  EXPECT_EQ(root->children[0].line, 3);
}

TEST(E57XmlTest, RejectsMalformedXml) {
  EXPECT_THAT(e57::ParseXml("<a><b></a>").status().message(),
              HasSubstr("line 1: end tag </a> does not match <b>"));
  EXPECT_THAT(e57::ParseXml("<a>\n&bogus;</a>").status().message(),
              HasSubstr("line 2: unknown entity '&bogus;'"));
  EXPECT_THAT(e57::ParseXml("<a x='1' x='2'/>").status().message(),
              HasSubstr("duplicate attribute 'x'"));
  EXPECT_THAT(e57::ParseXml("<a/><b/>").status().message(),
              HasSubstr("unexpected content after the root element"));
  EXPECT_THAT(e57::ParseXml("<!DOCTYPE a [<!ENTITY e 'x'>]><a/>").status().message(),
              HasSubstr("DOCTYPE with an internal subset is not supported"));
  std::string deep;
  for (int i = 0; i < 200; ++i) deep += "<a>";
  EXPECT_THAT(e57::ParseXml(deep).status().message(), HasSubstr("nested deeper than 128"));
}

// ---------------------------------------------------------------------------
// Malformed inputs.

TEST_F(E57Test, XmlSyntaxErrorNamesLine) {
  WriterOptions options;
  options.edit_xml = [](std::string* xml) {
    const size_t at = xml->find("</prototype>");
    xml->replace(at, 12, "</prototyp>");
  };
  const std::string message = Error(WriteScans({XyzScan({1}, {2}, {3})}, options));
  EXPECT_THAT(message,
              HasSubstr("t.e57: XML line 13: end tag </prototyp> does not match <prototype>"));
}

TEST_F(E57Test, UnsupportedCodec) {
  TestScan scan = XyzScan({1}, {2}, {3});
  scan.codecs_xml =
      "<vectorChild type=\"Structure\"><inputs type=\"Vector\"/>"
      "<zipCodec type=\"Structure\"/></vectorChild>";
  EXPECT_THAT(Error(WriteScans({scan})),
              HasSubstr("codec 'zipCodec' is not supported (only bitPackCodec)"));
}

TEST_F(E57Test, NotAnE57File) {
  std::vector<uint8_t> bytes(2048, 'x');
  EXPECT_THAT(Error(Write("x.e57", bytes)), HasSubstr("x.e57: not an E57 file (no 'ASTM-E57'"));
  EXPECT_THAT(Error(Write("tiny.e57", {'A', 'S'})), HasSubstr("shorter than the 48-byte header"));
  EXPECT_THAT(Error((dir_ / "missing.e57").string()), HasSubstr("missing.e57: open"));
}

TEST_F(E57Test, UnsupportedVersion) {
  WriterOptions options;
  options.version_major = 2;
  EXPECT_THAT(Error(WriteScans({XyzScan({1}, {2}, {3})}, options)),
              HasSubstr("E57 version 2.0 is not supported"));
}

TEST_F(E57Test, UnsupportedFieldType) {
  TestScan scan = XyzScan({1}, {2}, {3});
  scan.extra_xml = "";
  WriterOptions options;
  options.edit_xml = [](std::string* xml) {
    const size_t at = xml->find("</prototype>");
    xml->insert(at, "<label type=\"String\"/>");
  };
  EXPECT_THAT(Error(WriteScans({scan}, options)),
              HasSubstr("prototype field 'label' has type 'String', which this reader does not"));
}

TEST_F(E57Test, PrototypeWithoutCoordinates) {
  TestScan scan;
  scan.fields = {Float64("cartesianX", {1}), Float64("cartesianY", {2})};
  EXPECT_THAT(Error(WriteScans({scan})),
              HasSubstr("data3D scan 0: prototype has neither cartesianX/Y/Z nor"));
}

TEST_F(E57Test, RecordCountTooLargeForSection) {
  TestScan scan = XyzScan({1}, {2}, {3});
  scan.record_count = 1000000;
  EXPECT_THAT(Error(WriteScans({scan})), HasSubstr("recordCount 1000000 cannot fit in a"));
}

TEST_F(E57Test, SectionEndsEarly) {
  TestScan scan = XyzScan({1, 2, 3, 4, 5, 6, 7, 8, 9, 10}, std::vector<double>(10, 0.0),
                          std::vector<double>(10, 0.0));
  scan.record_count = 11;
  WriterOptions options;
  options.stream_bytes_per_packet = 1000;
  options.empty_and_index_packets = false;
  EXPECT_THAT(Error(WriteScans({scan}, options)),
              HasSubstr("data3D scan 0 points: section ends after 10 of 11 records"));
}

TEST_F(E57Test, BytestreamCountMismatch) {
  WriterOptions options;
  options.edit_xml = [](std::string* xml) {
    const size_t at = xml->find("</prototype>");
    xml->insert(at, "<intensity type=\"Float\"/>");
  };
  EXPECT_THAT(Error(WriteScans({XyzScan({1}, {2}, {3})}, options)),
              HasSubstr("data packet has 3 bytestreams, the prototype has 4 fields"));
}

TEST_F(E57Test, FileOffsetOutsideFile) {
  TestScan scan = XyzScan({1}, {2}, {3});
  scan.file_offset = 1 << 30;
  EXPECT_THAT(Error(WriteScans({scan})),
              HasSubstr("fileOffset 1073741824 is not a valid offset in the"));
}

TEST_F(E57Test, IntegerOutsideDeclaredRange) {
  TestScan scan = XyzScan({1, 2}, {2, 3}, {3, 4});
  scan.fields.push_back(Integer("cartesianInvalidState", 0, 2, {0, 3}));  // 3 fits in 2 bits
  EXPECT_THAT(Error(WriteScans({scan})),
              HasSubstr("field 3 of record 1 is outside its [minimum, maximum]"));
}

TEST_F(E57Test, UnknownPacketType) {
  WriterOptions options;
  options.packet_type = 7;
  options.empty_and_index_packets = false;
  EXPECT_THAT(Error(WriteScans({XyzScan({1}, {2}, {3})}, options)),
              HasSubstr("unknown packet type 7 (packet at byte 80, record 0 of 1)"));
}

TEST_F(E57Test, NoScans) {
  EXPECT_THAT(Error(WriteScans({})), HasSubstr("no 3D data: data3D has no scans"));
}

TEST_F(E57Test, BadNumberInPose) {
  TestScan scan = XyzScan({1}, {2}, {3});
  scan.extra_xml =
      "<pose type=\"Structure\"><translation type=\"Structure\">"
      "<x type=\"Float\">1.5m</x></translation></pose>";
  EXPECT_THAT(Error(WriteScans({scan})),
              HasSubstr("data3D scan 0: pose x: expected a number, found '1.5m'"));
}

}  // namespace
}  // namespace pb
