// Surfels (surfels.h) on a tilted regular grid, where the plane and the
// border are known.
#include "stages/geometry/points/surfels.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pb {
namespace {

// A 20 x 20 grid of step 0.01 m in the plane z = 0.5 x (tilted about y), far
// from the origin; point index = j * 20 + i.
PointCloud TiltedGrid() {
  PointCloud cloud;
  cloud.origin = {1000, 2000, 30};
  for (int j = 0; j < 20; ++j)
    for (int i = 0; i < 20; ++i) {
      const float x = 0.01f * i, y = 0.01f * j;
      cloud.positions.insert(cloud.positions.end(), {100 + x, 200 + y, 50 + 0.5f * x});
    }
  return cloud;
}

TEST(SurfelsTest, NormalsOfAPlaneAndTheBorderPointsOutward) {
  const PointCloud cloud = TiltedGrid();
  Expected<Surfels> surfels = EstimateSurfels(cloud);
  ASSERT_TRUE(surfels.ok()) << surfels.status().message();
  ASSERT_EQ(surfels->normal.size(), 1200u);
  const double expected[3] = {-0.5 / std::sqrt(1.25), 0, 1 / std::sqrt(1.25)};
  for (size_t p = 0; p < cloud.size(); ++p) {
    const float* n = &surfels->normal[p * 3];
    EXPECT_NEAR(std::abs(n[0] * expected[0] + n[1] * expected[1] + n[2] * expected[2]), 1.0, 1e-4) << p;
    EXPECT_LT(surfels->variation[p], 1e-6) << p;
  }
  const auto outward = [&](int i, int j) {
    const float* o = &surfels->outward[size_t(j * 20 + i) * 3];
    return std::array<float, 3>{o[0], o[1], o[2]};
  };
  // Interior: no border.
  for (int j = 4; j < 16; ++j)
    for (int i = 4; i < 16; ++i) EXPECT_EQ(outward(i, j), (std::array<float, 3>{0, 0, 0})) << i << " " << j;
  // The middle of each side points out of the grid, in the plane.
  EXPECT_LT(outward(10, 0)[1], -0.99f);
  EXPECT_GT(outward(10, 19)[1], 0.99f);
  EXPECT_LT(outward(0, 10)[0], -0.85f);  // (-1, 0, -0.5) / |.| = (-0.894, 0, -0.447)
  EXPECT_LT(outward(0, 10)[2], -0.4f);
  EXPECT_GT(outward(19, 10)[0], 0.85f);
  EXPECT_GE(surfels->border_points, 4u * 18u);
  EXPECT_LE(surfels->border_points, 4u * 19u * 2u);
}

TEST(SurfelsTest, AThinPartIsNoPlane) {
  // A cable: a cylinder of radius 4 mm sampled every 2 mm around and along,
  // beside a plane sampled every 1 cm. The cable's neighbourhoods (16 points
  // reach 6 mm along it) are no plane; the plane's are.
  PointCloud cloud;
  for (int j = 0; j < 20; ++j)
    for (int i = 0; i < 20; ++i) cloud.positions.insert(cloud.positions.end(), {0.01f * i, 0.01f * j, 0.0f});
  const size_t cable = cloud.size();
  for (int j = 0; j < 50; ++j)
    for (int a = 0; a < 12; ++a) {
      const double angle = 2 * M_PI * a / 12;  // 12 around: 2.1 mm apart
      cloud.positions.insert(cloud.positions.end(),
                             {float(0.004 * std::cos(angle)), 0.5f + 0.002f * j, float(0.5 + 0.004 * std::sin(angle))});
    }
  Expected<Surfels> surfels = EstimateSurfels(cloud);
  ASSERT_TRUE(surfels.ok());
  EXPECT_GT(surfels->variation[cable + 25 * 12 + 3], 0.05f);
  EXPECT_LT(surfels->variation[10 * 20 + 10], 1e-6f);
}

TEST(SurfelsTest, RejectsBadInput) {
  const PointCloud cloud = TiltedGrid();
  EXPECT_FALSE(EstimateSurfels(cloud, {.k = 2}).ok());
  EXPECT_FALSE(EstimateSurfels(cloud, {.k = 16, .border_shift = 0}).ok());
  PointCloud few;
  few.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  EXPECT_FALSE(EstimateSurfels(few, {.k = 3}).ok());
}

}  // namespace
}  // namespace pb
