#include "stages/geometry/io/xyz.h"

#include "stages/geometry/testing/test_data.h"
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace pb {
namespace {

using ::testing::HasSubstr;

class XyzTest : public pb::testing::TempDirTest {
 protected:
  Expected<ScanReadResult> Read(const std::string& name, const std::string& contents,
                                const std::string& columns = "") const {
    ScanReadOptions options;
    options.columns = columns;
    return ReadXyz(Write(name, contents), options);
  }
  void ExpectError(const std::string& name, const std::string& contents,
                   const std::string& fragment, const std::string& columns = "") const {
    const auto read = Read(name, contents, columns);
    ASSERT_FALSE(read.ok()) << "expected an error containing: " << fragment;
    EXPECT_THAT(read.status().message(), HasSubstr(fragment));
  }

};

// Absolute coordinates of point i.
std::array<double, 3> At(const PointCloud& cloud, size_t i) {
  return {cloud.origin[0] + cloud.positions[3 * i], cloud.origin[1] + cloud.positions[3 * i + 1],
          cloud.origin[2] + cloud.positions[3 * i + 2]};
}

TEST_F(XyzTest, ThreeColumnsWithCommentsAndBlankLines) {
  const auto read = Read("a.xyz",
                         "# exported by hand\n"
                         "// another comment\n"
                         "1.5 -2.25 3\n"
                         "\n"
                         "  \t0.5\t4 +1e1  \r\n"
                         "   # indented comment\n");
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(At(cloud, 0), (std::array<double, 3>{1.5, -2.25, 3}));
  EXPECT_EQ(At(cloud, 1), (std::array<double, 3>{0.5, 4, 10}));
  EXPECT_EQ(cloud.origin, (std::array<double, 3>{1, 1, 7}));  // bbox center rounded to 1 m
  EXPECT_FALSE(cloud.has_colors());
  EXPECT_FALSE(cloud.has_intensities());
  EXPECT_EQ(read->format, "xyz (x y z)");
}

TEST_F(XyzTest, CommaSeparatedGeoreferencedWithByteColors) {
  const auto read = Read("b.txt",
                         "652341.125, 5412345.5, 312.25, 255, 128, 0\n"
                         "652343.0,5412347.0,313.0,1,2,3\n");
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  EXPECT_EQ(cloud.origin, (std::array<double, 3>{652342, 5412346, 313}));
  EXPECT_EQ(cloud.positions, (std::vector<float>{-0.875f, -0.5f, -0.75f, 1, 1, 0}));
  EXPECT_EQ(cloud.colors, (std::vector<uint8_t>{255, 128, 0, 1, 2, 3}));
  EXPECT_EQ(read->format, "txt (x y z r g b)");
}

TEST_F(XyzTest, UnitFloatColorsRescaleEarlierOnes) {
  // "1 0 1" is ambiguous until 0.5 shows the file uses 0..1 floats.
  const auto read = Read("c.xyz", "0 0 0 1 0 1\n1 1 1 0.5 0.2 1.0\n");
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.colors, (std::vector<uint8_t>{255, 0, 255, 128, 51, 255}));
}

TEST_F(XyzTest, SevenAndNineColumns) {
  auto read = Read("d.xyz", "0 0 0 10 1 2 3\n1 1 1 200 4 5 6\n");
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.colors, (std::vector<uint8_t>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(read->points.intensities, (std::vector<float>{10.f / 255, 200.f / 255}));
  ASSERT_EQ(read->warnings.size(), 1u);
  EXPECT_THAT(read->warnings[0], HasSubstr("intensity range [10, 200] divided by 255"));

  read = Read("e.xyz", "0 0 0 9 8 7 0 0 1\n1 1 1 6 5 4 0.6 0.8 0\n");
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.colors, (std::vector<uint8_t>{9, 8, 7, 6, 5, 4}));
  EXPECT_EQ(read->points.normals, (std::vector<float>{0, 0, 1, 0.6f, 0.8f, 0}));
  EXPECT_EQ(read->format, "xyz (x y z r g b nx ny nz)");
}

TEST_F(XyzTest, ExplicitColumnsSkipAndIgnoreTrailingValues) {
  const auto read = Read("f.xyz", "7 1 2 3 0 0 1 10 20 30 extra\n",
                         "_ x y z nx ny nz r g b");
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  EXPECT_EQ(At(cloud, 0), (std::array<double, 3>{1, 2, 3}));
  EXPECT_EQ(cloud.normals, (std::vector<float>{0, 0, 1}));
  EXPECT_EQ(cloud.colors, (std::vector<uint8_t>{10, 20, 30}));
}

TEST_F(XyzTest, LeicaPtsBlocksAndIntensity) {
  const auto read = Read("g.pts",
                         "2\n"
                         "1 2 3 -2048 10 20 30\n"
                         "4 5 6 2047 40 50 60\n"
                         "1\n"
                         "7 8 9 0 70 80 90\n");
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  ASSERT_EQ(cloud.size(), 3u);
  EXPECT_EQ(At(cloud, 2), (std::array<double, 3>{7, 8, 9}));
  EXPECT_EQ(cloud.colors, (std::vector<uint8_t>{10, 20, 30, 40, 50, 60, 70, 80, 90}));
  EXPECT_EQ(cloud.intensities, (std::vector<float>{0.f, 1.f, 2048.f / 4095}));
  EXPECT_TRUE(read->warnings.empty());
  EXPECT_EQ(read->format, "pts (x y z i r g b)");
}

TEST_F(XyzTest, PtsWithFourColumns) {
  const auto read = Read("h.PTS", "1\n1 2 3 -48\n");
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.intensities, (std::vector<float>{2000.f / 4095}));
  EXPECT_FALSE(read->points.has_colors());
}

TEST_F(XyzTest, NonFiniteCoordinateErrorsUnlessDropped) {
  const std::string text = "0 0 0\nnan 1 1\n2 2 2\n";
  ExpectError("n.xyz", text, "n.xyz:2: point 1 has a non-finite coordinate (nan 1 1)");
  ScanReadOptions options;
  options.drop_invalid_points = true;
  const auto read = ReadXyz(Write("n.xyz", text), options);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.size(), 2u);
  EXPECT_EQ(read->dropped_points, 1u);
}

// ---------------------------------------------------------------------------
// Malformed input.

TEST_F(XyzTest, ErrorPtsCountMismatch) {
  ExpectError("a.pts", "3\n0 0 0 0 1 2 3\n1 1 1 0 1 2 3\n",
              "a.pts:1: count mismatch: 3 points declared, the file ends after 2");
  ExpectError("b.pts", "1\n0 0 0 0 1 2 3\n1 1 1 0 1 2 3\n",
              "b.pts:3: count mismatch: more points than the 1 declared at line 1");
  ExpectError("c.pts", "3\n0 0 0 0 1 2 3\n2\n",
              "c.pts:3: count mismatch: 3 points declared at line 1, but a new count");
}

TEST_F(XyzTest, ErrorPtsWithoutCountLine) {
  ExpectError("d.pts", "0 0 0 0 1 2 3\n",
              "d.pts:1: expected the point count (a single integer) at the start of a PTS file");
  ExpectError("e.pts", "# nothing\n", "e.pts: empty PTS file");
}

TEST_F(XyzTest, ErrorNotANumber) {
  ExpectError("a.xyz", "0 0 0\n1 abc 1\n", "a.xyz:2: column 2 ('y'): expected a number, got 'abc'");
  ExpectError("b.xyz", "X Y Z\n", "b.xyz:1: column 1 ('x'): expected a number, got 'X'");
}

TEST_F(XyzTest, ErrorColumnCountChanges) {
  ExpectError("a.xyz", "0 0 0\n1 1 1\n2 2 2 2\n",
              "a.xyz:3: expected 3 values (x y z), got 4; line 1 had 3");
  ExpectError("b.xyz", "0 0 0 1 2\n", "b.xyz:1: cannot tell what 5 columns mean");
  ExpectError("c.xyz", "0 0 0 9 1 2 3\n0 0\n", "c.xyz:2: expected 7 values (x y z _ r g b), got 2",
              "x y z _ r g b");
}

TEST_F(XyzTest, ErrorEmptyCommaField) {
  ExpectError("a.csv", "1,2,3\n4,,6\n", "a.csv:2: column 2 is empty");
  ExpectError("b.csv", "1,2,3,\n", "b.csv:1: column 4 is empty");
}

TEST_F(XyzTest, ErrorBadColumnNames) {
  ExpectError("a.xyz", "0 0 0\n", "columns 'x y q': unknown column name 'q'", "x y q");
  ExpectError("b.xyz", "0 0 0 1\n", "columns 'x y z r': r, g and b go together", "x y z r");
  ExpectError("c.xyz", "0 0 0\n", "columns 'x x y z': column 'x' appears twice", "x x y z");
}

TEST_F(XyzTest, ErrorColorsMixScales) {
  ExpectError("a.xyz", "0 0 0 0.5 0.5 0.5\n1 1 1 128 0 0\n",
              "a.xyz:2: color 'r' is 128 but line 1 had 0..1 colors");
  ExpectError("b.xyz", "0 0 0 300 0 0\n", "b.xyz:1: color 'r' is 300; expected 0..255 or 0..1");
}

}  // namespace
}  // namespace pb
