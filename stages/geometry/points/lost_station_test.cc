#include "stages/geometry/points/lost_station.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "stages/geometry/testing/clouds.h"
#include "stages/geometry/synth/scan_without_stations.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

using Facade = testing::ScanWithoutStations;
Facade ScanFacade(int stations) {
  Facade facade = testing::FacadeWithoutStations(stations, 60'000 * uint64_t(stations));
  EXPECT_EQ(facade.stations.size(), size_t(stations));
  return facade;
}

double Distance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

// One scan exported without its station, far from the origin in another
// frame (georeferenced): found within a quarter metre (measured 0.13 m
// with 130,000 points), in absolute coordinates.
TEST(LostStationTest, OneScanWithoutItsStationTellsWhereItStood) {
  Facade facade = ScanFacade(1);
  ASSERT_EQ(facade.stations.size(), 1u);
  const std::array<double, 3> shift = {512345.0, 5401234.0, 210.0};
  for (int a = 0; a < 3; ++a) facade.cloud.origin[a] += shift[a];
  Expected<LostStation> lost = FindLostStation(facade.cloud);
  ASSERT_TRUE(lost.ok()) << lost.status().message();
  EXPECT_TRUE(lost->found) << lost->verdict << ": " << lost->figures;
  const std::array<double, 3> station = {facade.stations[0][0] + shift[0], facade.stations[0][1] + shift[1],
                                         facade.stations[0][2] + shift[2]};
  EXPECT_LT(Distance(lost->position, station), 0.25) << lost->figures;
  EXPECT_LT(lost->misfit, 0.05);
  EXPECT_GT(lost->explained, 0.8);
  EXPECT_THAT(lost->verdict, HasSubstr("one scan's"));
}

// The scanner's axis matters: its azimuth steps close up toward the zenith.
// The same scan with the up direction wrong fits worse.
TEST(LostStationTest, TheScannersAxisIsPartOfTheFit) {
  const Facade facade = ScanFacade(1);
  LostStationOptions sideways;
  sideways.up = {1, 0, 0};
  Expected<LostStation> right = FindLostStation(facade.cloud), wrong = FindLostStation(facade.cloud, sideways);
  ASSERT_TRUE(right.ok() && wrong.ok());
  EXPECT_LT(right->misfit, 0.8 * wrong->misfit) << right->figures << " / " << wrong->figures;
}

// Without the axis, the search tries the cloud's three and keeps the one
// that fits: z for the facade, y once the scan is written y-up.
TEST(LostStationTest, WithoutTheAxisTheBestOfThreeIsTaken) {
  Facade facade = ScanFacade(1);
  LostStationOptions unknown;
  unknown.up = {0, 0, 0};
  Expected<LostStation> z_up = FindLostStation(facade.cloud, unknown);
  ASSERT_TRUE(z_up.ok()) << z_up.status().message();
  EXPECT_TRUE(z_up->found) << z_up->figures;
  EXPECT_EQ(z_up->up, (std::array<double, 3>{0, 0, 1}));
  for (size_t i = 0; i < facade.cloud.size(); ++i) {  // (x, y, z) -> (x, z, -y)
    float* p = &facade.cloud.positions[3 * i];
    const float y = p[1];
    p[1] = p[2], p[2] = -y;
  }
  Expected<LostStation> y_up = FindLostStation(facade.cloud, unknown);
  ASSERT_TRUE(y_up.ok()) << y_up.status().message();
  EXPECT_TRUE(y_up->found) << y_up->figures;
  EXPECT_EQ(y_up->up, (std::array<double, 3>{0, 1, 0}));
  const std::array<double, 3> station = {facade.stations[0][0], facade.stations[0][2], -facade.stations[0][1]};
  EXPECT_LT(Distance(y_up->position, station), 0.25) << y_up->figures;
}

// Three stations' scans merged: no one place explains the sampling (the
// misfit about 0.12, 62 % explained at 400,000 points).
TEST(LostStationTest, ScansMergedFromSeveralStationsHaveNone) {
  const Facade facade = ScanFacade(3);
  Expected<LostStation> lost = FindLostStation(facade.cloud);
  ASSERT_TRUE(lost.ok()) << lost.status().message();
  EXPECT_FALSE(lost->found) << lost->figures;
  EXPECT_GT(lost->misfit, 0.065) << lost->figures;
}

// An object sampled all round (evenly, as a mesh's vertices or a fused
// capture): every place outside it sees its far side through its near side,
// and from inside the sampling does not grow with the distance.
TEST(LostStationTest, AClosedObjectHasNone) {
  PointCloud sphere;
  const double center[3] = {0, 0, 1};
  testing::AddSphere(sphere, center, 0.5, 40000, 0.0005, 3);
  Expected<LostStation> lost = FindLostStation(sphere);
  ASSERT_TRUE(lost.ok()) << lost.status().message();
  EXPECT_FALSE(lost->found) << lost->verdict << ": " << lost->figures;
}

// A lone wall scanned from one station: its mirror image behind the wall
// sees it the same, so the side cannot be told, and nothing is declared.
TEST(LostStationTest, ALoneWallCannotTellItsSide) {
  PointCloud wall;
  const double step = 0.004;  // rad
  for (double azimuth = -0.9; azimuth <= 0.9; azimuth += step)
    for (double elevation = -0.4; elevation <= 0.6; elevation += step) {
      // The wall x = 3 m, seen from a station at (0, 0, 1.5).
      const double dx = std::cos(elevation) * std::cos(azimuth), dy = std::cos(elevation) * std::sin(azimuth),
                   dz = std::sin(elevation);
      const double t = 3.0 / dx;
      wall.positions.insert(wall.positions.end(), {float(t * dx), float(t * dy), float(1.5 + t * dz)});
    }
  Expected<LostStation> lost = FindLostStation(wall);
  ASSERT_TRUE(lost.ok()) << lost.status().message();
  EXPECT_FALSE(lost->found) << lost->verdict << ": " << lost->figures;
}

TEST(LostStationTest, BadInputSaysWhat) {
  PointCloud few;
  const double center[3] = {0, 0, 0};
  testing::AddSphere(few, center, 1, 50, 0, 1);
  EXPECT_THAT(FindLostStation(few).status().message(), HasSubstr("fewer than 100 points"));
  PointCloud nan;
  testing::AddSphere(nan, center, 1, 500, 0, 1);
  nan.positions[3 * 7 + 1] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(FindLostStation(nan).ok());
  LostStationOptions bad_up;
  bad_up.up = {0, std::numeric_limits<double>::infinity(), 0};
  PointCloud enough;
  testing::AddSphere(enough, center, 1, 500, 0, 1);
  EXPECT_THAT(FindLostStation(enough, bad_up).status().message(), HasSubstr("out of range"));
}

}  // namespace
}  // namespace pb
