// Surfels (surfels.h) on a tilted regular grid, where the plane and the
// border are known.
#include "stages/geometry/points/surfels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "stages/geometry/testing/clouds.h"

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

// A sphere of radius 0.1 m, 4000 points on a Fibonacci spiral (about 5.6 mm
// apart), each moved `noise` times a pseudo-random number in [-1, 1]
// radially (range noise).
PointCloud Sphere(double noise) {
  PointCloud cloud;
  const int n = 4000;
  uint64_t state = 99;
  for (int i = 0; i < n; ++i) {
    const double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - z * z);
    const double phi = i * M_PI * (3 - std::sqrt(5.0));
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const double u = double(state >> 11) * 0x1.0p-53 * 2 - 1;
    const double radius = 0.1 + noise * u;
    cloud.positions.insert(cloud.positions.end(), {float(radius * r * std::cos(phi)),
                                                   float(radius * r * std::sin(phi)), float(radius * z)});
  }
  return cloud;
}

double MeanRadialError(const std::vector<float>& xyz) {
  double sum = 0;
  for (size_t i = 0; i < xyz.size(); i += 3) sum += std::abs(std::hypot(xyz[i], xyz[i + 1], xyz[i + 2]) - 0.1);
  return sum / double(xyz.size() / 3);
}

// The projection onto the local quadric: on an exact sphere it moves the
// points by far less than a plane's r_k^2 / 4R (r_k about 12 mm for 16
// neighbours: 0.36 mm), and on a noisy one it takes most of the noise out.
TEST(SurfelsTest, ProjectionOntoTheLocalSurface) {
  const PointCloud exact = Sphere(0);
  Expected<Surfels> plain = EstimateSurfels(exact);
  ASSERT_TRUE(plain.ok());
  EXPECT_TRUE(plain->on_surface.empty());  // not asked for
  Expected<Surfels> on_exact = EstimateSurfels(exact, {.project = true});
  ASSERT_TRUE(on_exact.ok());
  ASSERT_EQ(on_exact->on_surface.size(), exact.positions.size());
  EXPECT_LT(MeanRadialError(exact.positions), 1e-6);
  EXPECT_LT(MeanRadialError(on_exact->on_surface), 2e-5);

  const PointCloud noisy = Sphere(0.002);  // mean |error| 1 mm
  Expected<Surfels> on_noisy = EstimateSurfels(noisy, {.project = true});
  ASSERT_TRUE(on_noisy.ok());
  const double before = MeanRadialError(noisy.positions), after = MeanRadialError(on_noisy->on_surface);
  EXPECT_NEAR(before, 0.001, 1e-4);
  EXPECT_LT(after, 0.6 * before);  // sqrt(6 / 17) = 0.59 of the noise is left at most
  // Moved along the normal only: a point's direction from the center barely changes.
  for (size_t i = 0; i < noisy.size(); i += 97) {
    const float* p = &noisy.positions[i * 3];
    const float* q = &on_noisy->on_surface[i * 3];
    const double cosine = (double(p[0]) * q[0] + double(p[1]) * q[1] + double(p[2]) * q[2]) /
                          (std::hypot(p[0], p[1], p[2]) * std::hypot(q[0], q[1], q[2]));
    EXPECT_GT(cosine, 0.9999) << i;
  }
}

// An index the caller already built from the same positions gives the same
// surfels as the one built inside; one of another cloud is refused.
TEST(SurfelsTest, AGivenIndexOfTheSamePointsGivesTheSameSurfels) {
  const PointCloud noisy = Sphere(0.002);
  Expected<KnnIndex> index = KnnIndex::Build(noisy.positions);
  ASSERT_TRUE(index.ok());
  Expected<Surfels> own = EstimateSurfels(noisy, {.project = true});
  Expected<Surfels> given = EstimateSurfels(noisy, {.project = true}, &*index);
  ASSERT_TRUE(own.ok() && given.ok());
  EXPECT_EQ(own->normal, given->normal);
  EXPECT_EQ(own->outward, given->outward);
  EXPECT_EQ(own->variation, given->variation);
  EXPECT_EQ(own->on_surface, given->on_surface);
  EXPECT_EQ(own->border_points, given->border_points);

  const PointCloud grid = TiltedGrid();
  Expected<Surfels> wrong = EstimateSurfels(grid, {}, &*index);
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.status().message().find("index holds"), std::string::npos) << wrong.status().message();
}

// The ceiling above a scanner (testing::AddZenithCeiling): within 0.2 m of
// the zenith, the plane of a point's 16 nearest stands on edge; widened to
// a typical neighbourhood it lies in the ceiling, few points there are
// taken for a border, and the projection puts them onto the ceiling.
TEST(SurfelsTest, WhereScanLinesConvergeTheNeighbourhoodIsWidened) {
  PointCloud cloud;
  testing::AddZenithCeiling(cloud, 1.7, 0.006, 0.4, 0.002, 11);
  struct Near {
    size_t points = 0, tilted = 0, border = 0;
  };
  auto near_zenith = [&](const Surfels& s) {
    Near n;
    for (size_t i = 0; i < cloud.size(); ++i) {
      if (std::hypot(cloud.positions[3 * i], cloud.positions[3 * i + 1]) >= 0.2) continue;
      ++n.points;
      n.tilted += std::fabs(s.normal[3 * i + 2]) < 0.9f;
      n.border += s.outward[3 * i] != 0 || s.outward[3 * i + 1] != 0 || s.outward[3 * i + 2] != 0;
    }
    return n;
  };
  Expected<Surfels> nearest = EstimateSurfels(cloud, {.project = true});
  ASSERT_TRUE(nearest.ok()) << nearest.status().message();
  EXPECT_EQ(nearest->widened, 0u);
  const Near before = near_zenith(*nearest);
  EXPECT_GT(before.tilted, before.points * 3 / 4);
  Expected<Surfels> widened = EstimateSurfels(cloud, {.project = true, .widen_dense = true});
  ASSERT_TRUE(widened.ok()) << widened.status().message();
  EXPECT_GT(widened->widened, cloud.size() / 4);
  const Near after = near_zenith(*widened);
  // 19,684 of the 19,912 points tilted before, 215 after; 7,356 taken for
  // a border before (their arcs' centroids lie off them), 197 after.
  EXPECT_LT(after.tilted, after.points / 50);
  EXPECT_GT(before.border, after.points / 4);
  EXPECT_LT(after.border, before.border / 10);
  // Moved onto the ceiling: within 3 mm of 1.7 m, as the noise allows.
  size_t off = 0;
  for (size_t i = 0; i < cloud.size(); ++i) off += std::fabs(widened->on_surface[3 * i + 2] - 1.7f) > 0.003f;
  EXPECT_LT(off, cloud.size() / 100);
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
