#include "stages/geometry/io/ptx.h"

#include "stages/geometry/testing/test_data.h"
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>

namespace pb {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

class PtxTest : public pb::testing::TempDirTest {
 protected:
  // Reads `contents` as a PTX file and returns the error message (empty if it
  // was accepted).
  std::string ErrorOf(const std::string& contents) const {
    auto read = ReadPtx(Write("bad.ptx", contents), {});
    return read.ok() ? "" : read.status().message();
  }

};

std::string SharedPtx(const std::string& name) {
  const std::string data = pb::testing::SharedDataDir();
  if (data.empty()) return "";
  const auto path = std::filesystem::path(data) / "ptx" / name;
  return std::filesystem::exists(path) ? path.string() : "";
}

// Absolute coordinate `axis` of point `i`.
double Absolute(const PointCloud& cloud, size_t i, int axis) {
  return cloud.origin[axis] + cloud.positions[3 * i + axis];
}

// A scan header with identity axes, the given position, and a matrix whose
// 3x3 part is `rotation` (row-major) and whose 4th row is `translation`.
std::string Header(int columns, int rows, const std::string& position = "0 0 0",
                   const std::string& rotation = "1 0 0\n0 1 0\n0 0 1",
                   const std::string& translation = "0 0 0") {
  std::string text = std::to_string(columns) + "\n" + std::to_string(rows) + "\n" + position +
                     "\n1 0 0\n0 1 0\n0 0 1\n";
  size_t start = 0;
  for (int row = 0; row < 3; ++row) {
    const size_t end = rotation.find('\n', start);
    text += rotation.substr(start, end - start) + " 0\n";
    start = end + 1;
  }
  return text + translation + " 1\n";
}

// --- Shared sample files (PDAL test data) ----------------------------------

TEST_F(PtxTest, ColoredGridFromPdal) {
  const std::string path = SharedPtx("1.2-with-color.ptx");
  if (path.empty()) GTEST_SKIP() << "shared data absent";
  auto read = ReadPtx(path, {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  EXPECT_EQ(read->format, "ptx");
  EXPECT_EQ(cloud.size(), 1065u);  // 15 x 71, no 0 0 0 cell
  EXPECT_EQ(read->dropped_points, 0u);
  EXPECT_TRUE(read->warnings.empty());
  ASSERT_TRUE(cloud.has_colors());
  ASSERT_TRUE(cloud.has_intensities());
  ASSERT_EQ(cloud.station_ids.size(), 1065u);
  ASSERT_EQ(cloud.stations.size(), 1u);
  EXPECT_EQ(cloud.stations[0], (std::array<double, 3>{0, 0, 0}));
  EXPECT_EQ(cloud.origin, (std::array<double, 3>{637012, 849028, 432}));
  // First line: 637012.240000 849028.310000 431.660000 0.034912 68 77 88
  EXPECT_NEAR(Absolute(cloud, 0, 0), 637012.24, 1e-6);
  EXPECT_NEAR(Absolute(cloud, 0, 1), 849028.31, 1e-6);
  EXPECT_NEAR(Absolute(cloud, 0, 2), 431.66, 1e-6);
  EXPECT_FLOAT_EQ(cloud.intensities[0], 0.034912f);
  EXPECT_THAT(std::vector<uint8_t>(cloud.colors.begin(), cloud.colors.begin() + 3),
              ElementsAre(68, 77, 88));
  // Last line: 637342.850000 853240.320000 423.920000 0.028320 138 107 136,
  // 4.2 km from the origin, where float32 steps are 0.49 mm.
  EXPECT_NEAR(Absolute(cloud, 1064, 0), 637342.85, 2.5e-4);
  EXPECT_NEAR(Absolute(cloud, 1064, 1), 853240.32, 2.5e-4);
  EXPECT_NEAR(Absolute(cloud, 1064, 2), 423.92, 2.5e-4);
  EXPECT_THAT(std::vector<uint8_t>(cloud.colors.end() - 3, cloud.colors.end()),
              ElementsAre(138, 107, 136));
}

TEST_F(PtxTest, NoColorFromPdal) {
  const std::string path = SharedPtx("no-color.ptx");
  if (path.empty()) GTEST_SKIP() << "shared data absent";
  auto read = ReadPtx(path, {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  EXPECT_EQ(cloud.size(), 15u);
  EXPECT_FALSE(cloud.has_colors());
  EXPECT_TRUE(cloud.has_intensities());
  // Last line: 635795.240000 849310.430000 426.610000 0.035645
  EXPECT_NEAR(Absolute(cloud, 14, 0), 635795.24, 1e-4);
  EXPECT_NEAR(Absolute(cloud, 14, 1), 849310.43, 1e-4);
  EXPECT_NEAR(Absolute(cloud, 14, 2), 426.61, 1e-4);
  EXPECT_FLOAT_EQ(cloud.intensities[14], 0.035645f);
}

TEST_F(PtxTest, MultipleScansWithScaleAndTranslationFromPdal) {
  const std::string path = SharedPtx("multiple-and-transform.ptx");
  if (path.empty()) GTEST_SKIP() << "shared data absent";
  auto read = ReadPtx(path, {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  ASSERT_EQ(cloud.size(), 8u);
  EXPECT_THAT(cloud.station_ids, ElementsAre(0, 0, 0, 0, 1, 1, 1, 1));
  ASSERT_EQ(cloud.stations.size(), 2u);
  EXPECT_EQ(cloud.stations[0], (std::array<double, 3>{600000, 800000, 400}));
  EXPECT_EQ(cloud.stations[1], (std::array<double, 3>{0, 0, 0}));
  EXPECT_THAT(read->warnings, ElementsAre("2 scans merged"));
  // Scan 1, point 1: (37012.24, 49028.31, 15.83) * diag(1, 1, 2) + (600000, 800000, 400).
  EXPECT_NEAR(Absolute(cloud, 0, 0), 637012.24, 1e-6);
  EXPECT_NEAR(Absolute(cloud, 0, 1), 849028.31, 1e-6);
  EXPECT_NEAR(Absolute(cloud, 0, 2), 431.66, 1e-6);
  // Scan 2 holds the same points already registered, identity matrix.
  for (size_t i = 0; i < 4; ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      EXPECT_NEAR(Absolute(cloud, i, axis), Absolute(cloud, i + 4, axis), 1e-4);
    }
  }
}

TEST_F(PtxTest, RotatedScanWithNoReturnsFromPdal) {
  const std::string path = SharedPtx("complex-transform.ptx");
  if (path.empty()) GTEST_SKIP() << "shared data absent";
  auto read = ReadPtx(path, {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  ASSERT_EQ(cloud.size(), 4u);  // 2 x 6 grid, 8 cells are 0 0 0
  EXPECT_EQ(read->no_return_points, 8u);
  EXPECT_EQ(read->dropped_points, 0u);
  ASSERT_TRUE(cloud.has_colors());
  EXPECT_THAT(cloud.colors, ElementsAre(33, 38, 24, 31, 37, 24, 30, 37, 23, 31, 37, 23));
  EXPECT_EQ(cloud.stations[0], (std::array<double, 3>{-3.028748, -3.819741, -1.384333}));
  // p = (-0.005630, 0.645218, -0.440506); x' = p . column 0 of M + M[3][0]:
  // -0.005630*0.999979 + 0.645218*0.003613 - 0.440506*0.005359 - 3.028748
  EXPECT_NEAR(Absolute(cloud, 0, 0), -3.034407381, 1e-6);
  EXPECT_NEAR(Absolute(cloud, 0, 1), -3.173781036, 1e-6);
  EXPECT_NEAR(Absolute(cloud, 0, 2), -1.823750042, 1e-6);
  // Fourth point (-0.005600, 0.647598, -0.438828).
  EXPECT_NEAR(Absolute(cloud, 3, 0), -3.034359790, 1e-6);
  EXPECT_NEAR(Absolute(cloud, 3, 1), -3.171403932, 1e-6);
  EXPECT_NEAR(Absolute(cloud, 3, 2), -1.822068350, 1e-6);
  EXPECT_FLOAT_EQ(cloud.intensities[0], 0.494911f);
}

// --- Hand-made files --------------------------------------------------------

TEST_F(PtxTest, RotationAndTranslationAreAppliedAsRowVectors) {
  // M's 3x3 part maps x -> y, y -> -x (a 90 degree turn about z) when points
  // are row vectors; translation (10, 20, 30) in the 4th row.
  const std::string text =
      Header(1, 2, "10 20 30", "0 1 0\n-1 0 0\n0 0 1", "10 20 30") + "1 2 3 0.5\n0 0 0 0.5\n";
  auto read = ReadPtx(Write("r.ptx", text), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  ASSERT_EQ(cloud.size(), 1u);
  EXPECT_EQ(read->no_return_points, 1u);
  EXPECT_EQ(cloud.origin, (std::array<double, 3>{8, 21, 33}));
  EXPECT_DOUBLE_EQ(Absolute(cloud, 0, 0), 10 - 2);
  EXPECT_DOUBLE_EQ(Absolute(cloud, 0, 1), 20 + 1);
  EXPECT_DOUBLE_EQ(Absolute(cloud, 0, 2), 30 + 3);
  EXPECT_EQ(cloud.stations[0], (std::array<double, 3>{10, 20, 30}));
  EXPECT_FLOAT_EQ(cloud.intensities[0], 0.5f);
}

TEST_F(PtxTest, CrLfBlankLinesAndNoFinalNewline) {
  const std::string text =
      "1\r\n2\r\n\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n0 0 1\r\n1 0 0 0\r\n"
      "0 1 0 0\r\n0 0 1 0\r\n0 0 0 1\r\n1 2 3 0.25 1 2 3\r\n\r\n"
      "4 5 6 0.75 250 251 252";
  auto read = ReadPtx(Write("crlf.ptx", text), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  ASSERT_EQ(read->points.size(), 2u);
  EXPECT_THAT(read->points.colors, ElementsAre(1, 2, 3, 250, 251, 252));
  EXPECT_DOUBLE_EQ(Absolute(read->points, 1, 2), 6);
}

TEST_F(PtxTest, IntensitiesAreClampedWithAWarning) {
  auto read = ReadPtx(Write("i.ptx", Header(3, 1) + "1 1 1 -0.5\n2 2 2 1.5\n3 3 3 0.5\n"), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_THAT(read->points.intensities, ElementsAre(0.0f, 1.0f, 0.5f));
  EXPECT_THAT(read->warnings, ElementsAre("2 intensities outside [0, 1] clamped"));
}

TEST_F(PtxTest, MixedColorAndNoColorScansDropColors) {
  const std::string text = Header(1, 1) + "1 1 1 0.5 1 2 3\n" + Header(1, 1) + "2 2 2 0.5\n";
  auto read = ReadPtx(Write("m.ptx", text), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.size(), 2u);
  EXPECT_FALSE(read->points.has_colors());
  EXPECT_THAT(read->warnings, ElementsAre("some scans have colors and some do not; colors dropped",
                                          "2 scans merged"));
  EXPECT_TRUE(Validate(read->points).ok());
}

TEST_F(PtxTest, NanPointsAreDroppedOnRequest) {
  const std::string text = Header(3, 1) + "1 1 1 0.5\nnan 1 1 0.5\n0 0 0 0.5\n";
  ScanReadOptions options;
  options.drop_invalid_points = true;
  auto read = ReadPtx(Write("nan.ptx", text), options);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.size(), 1u);
  EXPECT_EQ(read->dropped_points, 1u);  // the NaN
  EXPECT_EQ(read->no_return_points, 1u);  // the 0 0 0
}

TEST_F(PtxTest, ProgressEndsAtOne) {
  double last = -1;
  ScanReadOptions options;
  options.progress = [&](double fraction) { last = fraction; };
  ASSERT_TRUE(ReadPtx(Write("p.ptx", Header(1, 1) + "1 1 1 0.5\n"), options).ok());
  EXPECT_EQ(last, 1.0);
}

// --- Malformed input --------------------------------------------------------

TEST_F(PtxTest, MissingFileIsNotFound) {
  auto read = ReadPtx((dir_ / "absent.ptx").string(), {});
  ASSERT_FALSE(read.ok());
  EXPECT_EQ(read.status().code(), Status::Code::kNotFound);
}

TEST_F(PtxTest, EmptyFile) {
  EXPECT_THAT(ErrorOf("\n\n"), HasSubstr("bad.ptx: empty file, expected a PTX header"));
}

TEST_F(PtxTest, BadColumnCount) {
  EXPECT_THAT(ErrorOf("abc\n2\n"),
              HasSubstr("bad.ptx:1: expected the column count (a positive integer), found 'abc'"));
  EXPECT_THAT(ErrorOf("-3\n2\n"), HasSubstr("bad.ptx:1: expected the column count"));
  EXPECT_THAT(ErrorOf("2.5\n2\n"), HasSubstr("bad.ptx:1: expected the column count"));
}

TEST_F(PtxTest, ZeroRows) {
  EXPECT_THAT(ErrorOf("2\n0\n"),
              HasSubstr("bad.ptx:2: expected the row count (a positive integer), found '0'"));
}

TEST_F(PtxTest, ShortPositionLine) {
  EXPECT_THAT(ErrorOf("1\n1\n0 0\n"),
              HasSubstr("bad.ptx:3: expected the scanner position x y z (3 numbers), found '0 0'"));
}

TEST_F(PtxTest, NonNumericAxis) {
  EXPECT_THAT(ErrorOf("1\n1\n0 0 0\n1 0 0\n0 one 0\n"),
              HasSubstr("bad.ptx:5: expected a scanner axis x y z, found 'one'"));
}

TEST_F(PtxTest, TruncatedHeader) {
  EXPECT_THAT(ErrorOf("1\n1\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0 0\n"),
              HasSubstr("bad.ptx:7: truncated header: expected a transformation matrix row"));
}

TEST_F(PtxTest, ColumnMajorMatrixIsRejected) {
  const std::string text =
      "1\n1\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0 5\n0 1 0 6\n0 0 1 7\n"
      "0 0 0 1\n1 1 1 0.5\n";
  EXPECT_THAT(ErrorOf(text), HasSubstr("bad.ptx:7: transformation matrix row 1 must end in 0"));
}

TEST_F(PtxTest, TruncatedPoints) {
  EXPECT_THAT(ErrorOf(Header(2, 2) + "1 1 1 0.5\n2 2 2 0.5\n3 3 3 0.5\n"),
              HasSubstr("bad.ptx:13: truncated: scan 1 ends after 3 of 4 points "
                        "(2 columns x 2 rows)"));
}

TEST_F(PtxTest, TruncatedSecondScan) {
  EXPECT_THAT(ErrorOf(Header(1, 1) + "1 1 1 0.5\n" + Header(1, 2) + "2 2 2 0.5\n"),
              HasSubstr("bad.ptx:22: truncated: scan 2 ends after 1 of 2 points"));
}

TEST_F(PtxTest, WrongValueCount) {
  EXPECT_THAT(ErrorOf(Header(2, 1) + "1 1 1 0.5 9\n2 2 2 0.5\n"),
              HasSubstr("bad.ptx:11: expected 4 values (x y z intensity) or 7 (x y z intensity "
                        "r g b), found 5"));
}

TEST_F(PtxTest, ValueCountChangesInsideAScan) {
  EXPECT_THAT(ErrorOf(Header(2, 1) + "1 1 1 0.5\n2 2 2 0.5 1 2 3\n"),
              HasSubstr("bad.ptx:12: expected 4 values like line 11, found 7"));
}

TEST_F(PtxTest, NonNumericValue) {
  EXPECT_THAT(ErrorOf(Header(1, 1) + "1 x 1 0.5\n"),
              HasSubstr("bad.ptx:11: value 2 is not a number: 'x'"));
}

TEST_F(PtxTest, NanIsAnErrorByDefault) {
  EXPECT_THAT(ErrorOf(Header(2, 1) + "1 1 1 0.5\n1 inf 1 0.5\n"),
              HasSubstr("bad.ptx:12: point 2 of scan 1 has a NaN or infinite value"));
}

TEST_F(PtxTest, ExtraLinesAfterTheLastScanAreABadHeader) {
  EXPECT_THAT(ErrorOf(Header(1, 1) + "1 1 1 0.5\n4 4 4 0.5\n"),
              HasSubstr("bad.ptx:12: expected the column count (a positive integer), "
                        "found '4 4 4 0.5'"));
}

TEST_F(PtxTest, AbsurdGridDoesNotAllocate) {
  EXPECT_THAT(ErrorOf(Header(2000000000, 2000000000) + "1 1 1 0.5\n"),
              HasSubstr("bad.ptx:11: truncated: scan 1 ends after 1 of"));
}

}  // namespace
}  // namespace pb
