#include "stages/geometry/io/grid_station.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "stages/geometry/io/grid_sweep_test_util.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

using pb::testing::SweepRange;
using pb::testing::SweptPoint;

// The sweep of grid_sweep_test_util.h from `station`, column-major records
// (a vertical line per azimuth step), as a verdict. `skip` > 0 leaves every
// skip-th record out (not recorded, or invalid and not added: its
// neighbours are then two cells apart).
GridStationTest::Verdict Sweep(const double station[3], int64_t rows, int64_t columns,
                               int skip = 0, double azimuth_step = 0.02) {
  GridStationTest test;
  int64_t record = 0;
  for (int64_t column = 0; column < columns; ++column) {
    for (int64_t row = 0; row < rows; ++row, ++record) {
      if (skip > 0 && record % skip == 0) continue;
      test.Add(double(row), double(column), SweptPoint(station, row, column, azimuth_step).data());
    }
  }
  return test.Decide();
}

TEST(GridStationTest, AGridSweptFromTheOriginPasses) {
  const double origin[3] = {0, 0, 0};
  const GridStationTest::Verdict verdict = Sweep(origin, 80, 120);
  EXPECT_TRUE(verdict.decided);
  EXPECT_TRUE(verdict.at_origin);
  EXPECT_GT(verdict.regular, 0.999);
  // Each step down a column and along a row against the one before it.
  EXPECT_EQ(verdict.steps, 78u * 120u + 80u * 118u);
  EXPECT_THAT(verdict.Describe(), HasSubstr("100.0 % of the 18800 steps"));
}

TEST(GridStationTest, AGridSweptFromElsewhereFails) {
  // The same sweep with its registration baked into the coordinates: the
  // scanner 40 cm from the frame's origin. Seen from the origin the steps
  // vary with range and jump at the depth edges.
  const double station[3] = {0.4, -0.2, 0.1};
  const GridStationTest::Verdict verdict = Sweep(station, 80, 120);
  EXPECT_TRUE(verdict.decided);
  EXPECT_FALSE(verdict.at_origin);
  EXPECT_LT(verdict.regular, 0.95);
  // Far away, as a site frame's origin usually is.
  const double far[3] = {250, 1200, 30};
  EXPECT_FALSE(Sweep(far, 80, 120).at_origin);
}

// The angle between directions: from the chord's series below a chord of
// 0.1, from the arctangent above, both the angle to float precision.
TEST(GridStationTest, AngleIsTheAngleOnBothSidesOfTheSeries) {
  for (double angle : {1e-4, 0.003, 0.05, 0.0999, 0.1, 0.10005, 0.2, 1.0, 2.5, 3.1}) {
    SCOPED_TRACE(angle);
    // Two directions `angle` apart, tilted out of any axis plane.
    const float a[3] = {float(std::cos(0.3) * std::cos(0.2)), float(std::sin(0.3) * std::cos(0.2)),
                        float(std::sin(0.2))};
    const double azimuth = 0.3 + angle / std::cos(0.2);  // not exactly `angle`: measure it in double
    const float b[3] = {float(std::cos(azimuth) * std::cos(0.2)),
                        float(std::sin(azimuth) * std::cos(0.2)), float(std::sin(0.2))};
    const double dot = double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2];
    const double cross = std::sqrt(std::pow(double(a[1]) * b[2] - double(a[2]) * b[1], 2) +
                                   std::pow(double(a[2]) * b[0] - double(a[0]) * b[2], 2) +
                                   std::pow(double(a[0]) * b[1] - double(a[1]) * b[0], 2));
    const double exact = std::atan2(cross, dot);
    EXPECT_NEAR(GridStationTest::Angle(a, b), exact, 1e-6 * exact + 1e-7);
    EXPECT_DOUBLE_EQ(GridStationTest::Angle(a, b), GridStationTest::Angle(b, a));
  }
  const float same[3] = {0, 0, 1};
  EXPECT_EQ(GridStationTest::Angle(same, same), 0);
}

// Steps of 0.15 rad along the rows (a coarse sweep: their angle from the
// arctangent) and 0.01 rad down the columns (from the chord's series): both
// regular seen from the origin, and neither from 40 cm off.
TEST(GridStationTest, CoarseAndFineStepsAreMeasuredAlike) {
  const double origin[3] = {0, 0, 0};
  const GridStationTest::Verdict coarse = Sweep(origin, 80, 40, 0, /*azimuth_step=*/0.15);
  EXPECT_TRUE(coarse.at_origin);
  EXPECT_GT(coarse.regular, 0.999);
  // With every 3rd record left out, steps of one and two cells (0.15 and
  // 0.30 rad, 0.01 and 0.02 rad) are divided by their cells alike.
  const GridStationTest::Verdict skipped = Sweep(origin, 80, 40, 3, /*azimuth_step=*/0.15);
  EXPECT_TRUE(skipped.at_origin);
  EXPECT_GT(skipped.regular, 0.999);
  const double station[3] = {0.4, -0.2, 0.1};
  EXPECT_FALSE(Sweep(station, 80, 40, 0, /*azimuth_step=*/0.15).at_origin);
}

TEST(GridStationTest, MissingRecordsMakeLongerSteps) {
  const double origin[3] = {0, 0, 0};
  // Every 5th record not there: its neighbours are 2 cells apart, a double
  // step, as regular as the others once divided.
  const GridStationTest::Verdict skipped = Sweep(origin, 80, 120, /*skip=*/5);
  EXPECT_TRUE(skipped.at_origin);
  EXPECT_GT(skipped.regular, 0.999);
  // Steps of one and six cells' angle in turn, each called one cell: not a grid
  // seen from the origin.
  GridStationTest test;
  for (int64_t row = 0; row < 1000; ++row) {
    const double elevation = 0.01 * double(row / 2 * 7 + row % 2);
    const double p[3] = {std::cos(elevation), 0, std::sin(elevation)};
    test.Add(double(row), 0, p);
  }
  EXPECT_TRUE(test.Decide().decided);
  EXPECT_FALSE(test.Decide().at_origin);
}

TEST(GridStationTest, BadCellIndicesAreIgnored) {
  // NaN, infinite or beyond 2^53: no step (and no undefined conversion).
  GridStationTest test;
  const double p[3] = {1, 0, 0};
  for (double bad : {std::nan(""), double(INFINITY), 1e300, -1e19}) {
    test.Add(bad, 0, p);
    test.Add(0, bad, p);
  }
  EXPECT_EQ(test.Decide().steps, 0u);
}

TEST(GridStationTest, ACamerasPixelGridPasses) {
  // An organized RGB-D frame: 160 x 120 pixels, 60 degrees across, looking
  // down -z; a pinhole's angle per pixel shrinks toward the corners.
  GridStationTest test;
  const double focal = 80.0 / std::tan(M_PI / 6);
  for (int64_t row = 0; row < 120; ++row) {
    for (int64_t column = 0; column < 160; ++column) {
      const double x = (double(column) - 79.5) / focal, y = (double(row) - 59.5) / focal;
      const double depth = SweepRange(row, column);
      const double p[3] = {x * depth, y * depth, -depth};
      test.Add(double(row), double(column), p);
    }
  }
  const GridStationTest::Verdict verdict = test.Decide();
  EXPECT_TRUE(verdict.at_origin) << verdict.Describe();
}

TEST(GridStationTest, TooFewStepsDecideNothing) {
  const double origin[3] = {0, 0, 0};
  const GridStationTest::Verdict verdict = Sweep(origin, 20, 20);
  EXPECT_FALSE(verdict.decided);
  EXPECT_FALSE(verdict.at_origin);
  EXPECT_THAT(verdict.Describe(), HasSubstr("720 successive steps between neighbours"));
  EXPECT_THAT(verdict.Describe(), HasSubstr("too few to tell"));
  // A point at the origin itself has no direction: it is ignored.
  GridStationTest test;
  const double zero[3] = {0, 0, 0};
  for (int64_t row = 0; row < 2000; ++row) test.Add(double(row), 0, zero);
  EXPECT_EQ(test.Decide().steps, 0u);
}

// The three verdicts as every reader's warning words them.
TEST(GridStationTest, AFindingSaysTheVerdictForTheDevice) {
  const double origin[3] = {0, 0, 0}, station[3] = {0.4, -0.2, 0.1};
  const GridStationTest::Verdict there = Sweep(origin, 80, 120);
  EXPECT_EQ(there.Finding("scanner"), "its scanner taken at its frame's origin (" +
                                          there.Describe() + ")");
  const GridStationTest::Verdict elsewhere = Sweep(station, 80, 120);
  EXPECT_EQ(elsewhere.Finding("sensor"),
            "its grid does not show its frame's origin as its sensor's (" +
                elsewhere.Describe() + ")");
  const GridStationTest::Verdict small = Sweep(origin, 20, 20);
  EXPECT_EQ(small.Finding("scanner"),
            "its grid cannot tell whether its frame's origin is its scanner's (" +
                small.Describe() + ")");
  // A one-grid file's warning around it.
  EXPECT_EQ(there.Warning("a scan", "scanner"), "a scan: " + there.Finding("scanner"));
  EXPECT_EQ(elsewhere.Warning("a frame", "sensor"),
            "no sensor station: a frame, and " + elsewhere.Finding("sensor") +
                "; io.read_points `station` can declare where it stood");
}

TEST(GridStationTest, AScanOfMillionsIsCountedWhole) {
  // Only counts and one record per row and column are kept. Its rows wrap
  // past the zenith: along a row the step shrinks with the cosine of the
  // elevation, the same for every step of that row.
  const double origin[3] = {0, 0, 0};
  const GridStationTest::Verdict at = Sweep(origin, 1100, 1000);
  EXPECT_EQ(at.steps, 1098u * 1000u + 1100u * 998u);
  EXPECT_TRUE(at.at_origin);
  const double station[3] = {0.4, -0.2, 0.1};
  EXPECT_FALSE(Sweep(station, 1100, 1000).at_origin);
}

}  // namespace
}  // namespace pb
