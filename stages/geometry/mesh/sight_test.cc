#include "stages/geometry/mesh/sight.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

namespace pb {
namespace {

// A 1 m wall of points 1 cm apart at x = `x`, seen from one station at the
// origin.
PointCloud Wall(double x) {
  PointCloud cloud;
  for (int j = -50; j <= 50; ++j) {
    for (int i = -50; i <= 50; ++i) {
      cloud.positions.insert(cloud.positions.end(), {static_cast<float>(x), 0.01f * i, 0.01f * j});
      cloud.station_ids.push_back(0);
    }
  }
  cloud.stations = {{0, 0, 0}};
  return cloud;
}

TEST(LinesOfSightTest, CountsTheLinesATriangleStandsInFrontOfTheirPoint) {
  const Expected<LinesOfSight> sight = LinesOfSight::Build(Wall(2), {0, 0, 0});
  ASSERT_TRUE(sight.ok()) << sight.status().message();
  EXPECT_EQ(sight->size(), 101u * 101u);
  // Halfway to the wall, a triangle of legs 0.1 m covers the directions of
  // points of a triangle of legs 0.2 m on the wall: 21 x 22 / 2 = 231 with
  // its edges (rounding may drop some of those).
  const std::array<double, 3> a = {1, -0.05, -0.05}, b = {1, 0.05, -0.05}, c = {1, -0.05, 0.05};
  const LinesOfSight::Counts half = sight->Through(a, b, c, 0.01);
  EXPECT_GE(half.behind, 190u);
  EXPECT_LE(half.behind, 231u);
  EXPECT_EQ(half.near, 0u);
  // Behind the wall: the lines end before it.
  const LinesOfSight::Counts past = sight->Through({2.5, -0.05, -0.05}, {2.5, 0.05, -0.05},
                                                   {2.5, -0.05, 0.05}, 0.01);
  EXPECT_EQ(past.behind, 0u);
  EXPECT_EQ(past.near, 0u);
  // A hair in front of the points, within the clearance: the same surface.
  const LinesOfSight::Counts hair = sight->Through({1.995, -0.05, -0.05}, {1.995, 0.05, -0.05},
                                                   {1.995, -0.05, 0.05}, 0.01);
  EXPECT_EQ(hair.behind, 0u);
  EXPECT_GT(hair.near, 40u);  // legs of 0.1 m on the wall: 11 x 12 / 2 = 66
  EXPECT_GT(sight->Through({1.98, -0.05, -0.05}, {1.98, 0.05, -0.05}, {1.98, -0.05, 0.05}, 0.01)
                .behind,
            0u);
  // Along the lines (its plane holds the station): grazing, not counted.
  const LinesOfSight::Counts grazing = sight->Through({0.5, 0, 0}, {1.5, 0, 0}, {1, 0, 0.1}, 0.01);
  EXPECT_EQ(grazing.behind + grazing.near, 0u);
}

TEST(LinesOfSightTest, FindsTheLinesAcrossTheAzimuthSeam) {
  // The wall behind the station, at x = -2: its directions straddle the
  // azimuth +-pi, and so does a triangle in front of it centred on y = 0.
  const Expected<LinesOfSight> sight = LinesOfSight::Build(Wall(-2), {0, 0, 0});
  ASSERT_TRUE(sight.ok());
  const size_t seam =
      sight->Through({-1, -0.05, -0.05}, {-1, 0.05, -0.05}, {-1, -0.05, 0.05}, 0.01).behind;
  EXPECT_GE(seam, 190u);
  EXPECT_LE(seam, 231u);
}

TEST(LinesOfSightTest, FindsTheLinesThroughATriangleAroundTheZenith) {
  // A ceiling 2 m above the station and a triangle 1 m up around the
  // vertical (an oculus): its corners lie at 80 degrees of elevation, the
  // lines through it up to 90.
  PointCloud ceiling;
  for (int j = -50; j <= 50; ++j) {
    for (int i = -50; i <= 50; ++i) {
      ceiling.positions.insert(ceiling.positions.end(), {0.01f * i, 0.01f * j, 2.0f});
      ceiling.station_ids.push_back(0);
    }
  }
  ceiling.stations = {{0, 0, 0}};
  const Expected<LinesOfSight> sight = LinesOfSight::Build(ceiling, {0, 0, 0});
  ASSERT_TRUE(sight.ok());
  const double r = std::tan(10 * M_PI / 180);  // 0.176 m at 1 m: 80 degrees up
  const LinesOfSight::Counts up = sight->Through(
      {r, 0, 1}, {-r / 2, r * std::sqrt(3.0) / 2, 1}, {-r / 2, -r * std::sqrt(3.0) / 2, 1}, 0.01);
  // The triangle's shadow on the ceiling: area 3 sqrt(3) / 4 (2r)^2, 1 cm grid.
  const double expected = 3 * std::sqrt(3.0) / 4 * (2 * r) * (2 * r) / 1e-4;
  EXPECT_GT(static_cast<double>(up.behind), 0.9 * expected);
  EXPECT_LT(static_cast<double>(up.behind), 1.1 * expected);
}

TEST(LinesOfSightTest, UsesTheQueryFrameAndRefusesCloudsWithoutStations) {
  PointCloud wall = Wall(2);
  // The same wall stored relative to an origin 100 m away, queried in a
  // frame whose origin is 10 m away: the same count.
  wall.origin = {100, 0, 0};
  for (size_t i = 0; i < wall.size(); ++i) wall.positions[3 * i] -= 100;
  const Expected<LinesOfSight> shifted = LinesOfSight::Build(wall, {10, 0, 0});
  ASSERT_TRUE(shifted.ok());
  const Expected<LinesOfSight> plain = LinesOfSight::Build(Wall(2), {0, 0, 0});
  EXPECT_EQ(shifted->Through({-9, -0.05, -0.05}, {-9, 0.05, -0.05}, {-9, -0.05, 0.05}, 0.01).behind,
            plain->Through({1, -0.05, -0.05}, {1, 0.05, -0.05}, {1, -0.05, 0.05}, 0.01).behind);

  PointCloud no_stations = Wall(2);
  no_stations.station_ids.clear();
  no_stations.stations.clear();
  const Expected<LinesOfSight> refused = LinesOfSight::Build(no_stations, {0, 0, 0});
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("no scanner stations"), std::string::npos);
  PointCloud bad_id = Wall(2);
  bad_id.station_ids[7] = 3;
  EXPECT_FALSE(LinesOfSight::Build(bad_id, {0, 0, 0}).ok());
}

}  // namespace
}  // namespace pb
