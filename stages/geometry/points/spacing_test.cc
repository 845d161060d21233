// Local spacing (spacing.h) on a regular grid, where every answer is known.
#include "stages/geometry/points/spacing.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pb {
namespace {

// A 10 x 10 grid of step 0.1 m in the plane z = 0; point index = j * 10 + i.
PointCloud Grid() {
  PointCloud cloud;
  for (int j = 0; j < 10; ++j)
    for (int i = 0; i < 10; ++i) cloud.positions.insert(cloud.positions.end(), {0.1f * i, 0.1f * j, 0.0f});
  return cloud;
}

// LocalSpacing is r_k sqrt(pi / k).
double Step(double r_k, int k) { return r_k * std::sqrt(M_PI / k); }

TEST(LocalSpacingTest, KthNeighbourDistanceOnAGrid) {
  const PointCloud cloud = Grid();
  Expected<std::vector<float>> four = LocalSpacing(cloud, 4);
  Expected<std::vector<float>> eight = LocalSpacing(cloud, 8);
  Expected<std::vector<float>> three = LocalSpacing(cloud, 3);
  ASSERT_TRUE(four.ok() && eight.ok() && three.ok());
  ASSERT_EQ(four->size(), 100u);
  const size_t interior = 5 * 10 + 5, corner = 0, edge = 5;  // (5, 5), (0, 0), (5, 0)
  EXPECT_NEAR((*four)[interior], Step(0.1, 4), 1e-6);                   // the 4 axis neighbours
  EXPECT_NEAR((*eight)[interior], Step(0.1 * std::sqrt(2.0), 8), 1e-6);  // and the 4 diagonals
  EXPECT_NEAR((*eight)[interior], 0.0886, 1e-4);                          // 0.886 grid steps
  EXPECT_NEAR((*three)[corner], Step(0.1 * std::sqrt(2.0), 3), 1e-6);    // 2 axis neighbours, then the diagonal
  EXPECT_NEAR((*four)[edge], Step(0.1 * std::sqrt(2.0), 4), 1e-6);       // 3 axis neighbours, then a diagonal
}

TEST(LocalSpacingTest, DuplicatesCountAndBadInputIsNamed) {
  PointCloud cloud = Grid();
  cloud.positions.insert(cloud.positions.end(), {0.5f, 0.5f, 0.0f});  // a duplicate of (5, 5)
  Expected<std::vector<float>> one = LocalSpacing(cloud, 1);
  ASSERT_TRUE(one.ok());
  EXPECT_EQ((*one)[55], 0.0f);
  EXPECT_EQ((*one)[100], 0.0f);
  EXPECT_FALSE(LocalSpacing(cloud, 0).ok());
  PointCloud few;
  few.positions = {0, 0, 0, 1, 0, 0};
  Expected<std::vector<float>> too_few = LocalSpacing(few, 2);
  ASSERT_FALSE(too_few.ok());
  EXPECT_NE(too_few.status().message().find("k = 2"), std::string::npos) << too_few.status().message();
}

TEST(SpacingTest, MedianLocalSpacingIsTheUpperMiddleValue) {
  EXPECT_EQ(MedianLocalSpacing(std::vector<float>{}), 0.0);
  EXPECT_EQ(MedianLocalSpacing(std::vector<float>{3.0f, 1.0f, 2.0f}), 2.0);
  EXPECT_EQ(MedianLocalSpacing(std::vector<float>{4.0f, 1.0f, 3.0f, 2.0f}), 3.0);
}

}  // namespace
}  // namespace pb
