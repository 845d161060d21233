// Stray points (strays.h): a lone return and a floating cluster beside a
// scanned surface are strays; the surface, its border, a far field sparser
// with range and a thin line of samples are not.
#include "stages/geometry/points/strays.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "stages/geometry/points/spacing.h"

namespace pb {
namespace {

struct Flags {
  std::vector<uint8_t> stray;
  size_t count = 0;
};

Flags Strays(const std::vector<float>& xyz, const StrayOptions& options = {}) {
  Expected<KnnIndex> index = KnnIndex::Build(xyz);
  EXPECT_TRUE(index.ok());
  Expected<std::vector<float>> spacing = LocalSpacing(*index, options.k);
  EXPECT_TRUE(spacing.ok());
  Expected<SpacingAndStrays> stray = LocalSpacingAndStrays(*index, options);
  EXPECT_TRUE(stray.ok()) << stray.status().message();
  // The spacing of the same queries is LocalSpacing's, value for value.
  EXPECT_EQ(stray->spacing, *spacing);
  Flags flags;
  flags.stray = stray->stray;
  for (uint8_t s : flags.stray) flags.count += s;
  return flags;
}

// A 60 x 60 plane at z = 0 whose row spacing grows with y (5 mm to about
// 16 mm, like a one-station scan's range), then the extras.
std::vector<float> FallingDensityPlane() {
  std::vector<float> xyz;
  double y = 0, step = 0.005;
  for (int j = 0; j < 60; ++j, y += step, step *= 1.02)
    for (int i = 0; i < 60; ++i) xyz.insert(xyz.end(), {float(i * step), float(y), 0.0f});
  return xyz;
}

TEST(StrayPointsTest, ALoneReturnAndAFloatingClusterAreStraysTheSurfaceIsNot) {
  std::vector<float> xyz = FallingDensityPlane();
  const size_t surface = xyz.size() / 3;
  xyz.insert(xyz.end(), {0.1f, 0.1f, 0.08f});  // a lone return 8 cm in front
  for (int c = 0; c < 20; ++c)                  // 20 returns within 3 mm, 5 cm in front
    xyz.insert(xyz.end(), {0.2f + 0.001f * float(c % 4), 0.15f + 0.001f * float(c / 4), 0.05f});
  // A thin line of 100 samples 1 mm apart, 10 cm in front: a wire, kept.
  for (int c = 0; c < 100; ++c) xyz.insert(xyz.end(), {0.3f, 0.05f + 0.001f * float(c), 0.1f});
  const Flags flags = Strays(xyz);
  for (size_t i = 0; i < surface; ++i) ASSERT_EQ(flags.stray[i], 0) << "surface point " << i;
  EXPECT_EQ(flags.stray[surface], 1);
  for (size_t i = surface + 1; i < surface + 21; ++i) EXPECT_EQ(flags.stray[i], 1) << i;
  for (size_t i = surface + 21; i < surface + 121; ++i) EXPECT_EQ(flags.stray[i], 0) << i;
  EXPECT_EQ(flags.count, 21u);

  // A smaller threshold keeps the cluster; 0 keeps everything.
  EXPECT_EQ(Strays(xyz, {.min_cluster_points = 20}).count, 1u);
  EXPECT_EQ(Strays(xyz, {.min_cluster_points = 0}).count, 0u);
}

// A sparse strip beside denser sampling (the top of a wall seen at grazing
// angle beside its face, the ceiling where a tripod scanner's lines
// converge): 45 points 7 mm apart, 16 mm from a patch sampled every 4 mm.
// 16 mm is over twice the spacing of the patch (5.1 mm along its border,
// more at its corners) but within twice the strip's (8.4 mm), and
// the spacings differ by less than 3: the strip links. By the smaller
// spacing alone (max_spacing_ratio 1) it was cut off as strays.
TEST(StrayPointsTest, ASparseStripBesideDenserSamplingIsNoStray) {
  std::vector<float> xyz;
  for (int j = 0; j < 40; ++j)
    for (int i = 0; i < 40; ++i) xyz.insert(xyz.end(), {0.004f * float(i), 0.004f * float(j), 0.0f});
  const size_t patch = xyz.size() / 3;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 15; ++i)
      xyz.insert(xyz.end(), {0.007f * float(i), 0.156f + 0.016f + 0.007f * float(j), 0.0f});
  EXPECT_EQ(Strays(xyz).count, 0u);
  const Flags cut = Strays(xyz, {.max_spacing_ratio = 1.0});
  EXPECT_EQ(cut.count, 45u);
  for (size_t i = patch; i < patch + 45; ++i) EXPECT_EQ(cut.stray[i], 1) << i;
}

TEST(StrayPointsTest, SameFlagsForAnyThreadCountAndBadOptions) {
  std::vector<float> xyz = FallingDensityPlane();
  xyz.insert(xyz.end(), {0.1f, 0.1f, 0.08f});
  Expected<KnnIndex> index = KnnIndex::Build(xyz);
  ASSERT_TRUE(index.ok());
  EXPECT_FALSE(LocalSpacingAndStrays(*index, {.k = 0}).ok());
  EXPECT_FALSE(LocalSpacingAndStrays(*index, {.link_spacings = 0}).ok());
  EXPECT_FALSE(LocalSpacingAndStrays(*index, {.max_spacing_ratio = 0.5}).ok());
  // At most k points: no k-th neighbour, as LocalSpacing says.
  Expected<KnnIndex> few = KnnIndex::Build(std::span<const float>(xyz).first(3 * 8));
  ASSERT_TRUE(few.ok());
  EXPECT_FALSE(LocalSpacingAndStrays(*few, {}).ok());
  std::vector<uint8_t> flags[2];
  for (int threads : {1, 2}) {
    tbb::task_arena arena(threads);
    arena.execute([&] { flags[threads - 1] = Strays(xyz).stray; });
  }
  EXPECT_EQ(flags[0], flags[1]);
  EXPECT_EQ(std::count(flags[0].begin(), flags[0].end(), 1), 1);
}

// Points in the air (strays.h, AirPoints).

// Pseudo-random numbers in [0, 1), the same on every run.
struct Uniform {
  std::mt19937 engine{12345};
  std::uniform_real_distribution<double> unit{0.0, 1.0};
  double operator()() { return unit(engine); }
};

std::vector<uint8_t> Air(const std::vector<float>& xyz, const AirOptions& options = {}, AirReport* report = nullptr) {
  Expected<KnnIndex> index = KnnIndex::Build(xyz);
  EXPECT_TRUE(index.ok());
  Expected<std::vector<uint8_t>> air = AirPoints(*index, options, report);
  EXPECT_TRUE(air.ok()) << air.status().message();
  return air.ok() ? *air : std::vector<uint8_t>(xyz.size() / 3, 0);
}

size_t Count(const std::vector<uint8_t>& flags, size_t begin, size_t end) {
  return size_t(std::count(flags.begin() + ptrdiff_t(begin), flags.begin() + ptrdiff_t(end), uint8_t{1}));
}

TEST(AirPointsTest, ReturnsScatteredInFrontAreInTheAirSurfacesAreNot) {
  std::vector<float> xyz;
  Uniform random;
  // A rough surface: 100 x 100 samples 1 cm apart, each up to 1 cm off the
  // plane (its k nearest have no plane, but it is as dense as the scan).
  for (int j = 0; j < 100; ++j)
    for (int i = 0; i < 100; ++i)
      xyz.insert(xyz.end(), {0.01f * float(i), 0.01f * float(j), float(0.02 * (random() - 0.5))});
  const size_t rough = xyz.size() / 3;
  // A far field: 20 x 20 samples 8 cm apart, 3 m away (sparse, planar).
  for (int j = 0; j < 20; ++j)
    for (int i = 0; i < 20; ++i) xyz.insert(xyz.end(), {3.0f + 0.08f * float(i), 0.08f * float(j), 0.5f});
  const size_t far = xyz.size() / 3;
  // A wire of 60 samples 5 cm apart (sparse, a line).
  for (int c = 0; c < 60; ++c) xyz.insert(xyz.end(), {-1.0f, 0.05f * float(c), 0.3f});
  const size_t wire = xyz.size() / 3;
  // 300 returns scattered through the half metre in front of the surface.
  for (int c = 0; c < 300; ++c)
    xyz.insert(xyz.end(), {float(0.2 + 0.6 * random()), float(0.2 + 0.6 * random()), float(0.1 + 0.5 * random())});
  const size_t all = xyz.size() / 3;
  AirReport report;
  const std::vector<uint8_t> air = Air(xyz, {}, &report);
  EXPECT_EQ(Count(air, 0, rough), 0u);
  EXPECT_EQ(Count(air, rough, far), 0u);
  EXPECT_EQ(Count(air, far, wire), 0u);
  EXPECT_GE(Count(air, wire, all), 270u);  // nearly all; a few lie next to others by chance
  EXPECT_EQ(report.air, Count(air, 0, all));
  EXPECT_NEAR(report.median_spacing_m, 0.01, 0.002);
  // They are strays too, and are not with the air test off.
  EXPECT_GE(Strays(xyz).count, report.air);
  Flags without = Strays(xyz, {.air = {.spacing_ratio = 0}});
  EXPECT_LT(without.count, 30u);  // the cloud links to itself: the clusters keep it
  // The plane test alone, without the scan's noise allowed, takes surface:
  // with every point above the median spacing tested, a part of the rough
  // surface goes.
  const std::vector<uint8_t> unplanar = Air(xyz, {.spacing_ratio = 1.0001, .noise_tolerance = 0});
  EXPECT_GT(Count(unplanar, 0, rough), rough / 20);
  // Later passes only add: every point of the first pass is in the last.
  const std::vector<uint8_t> first = Air(xyz, {.passes = 1});
  for (size_t i = 0; i < all; ++i) EXPECT_TRUE(!first[i] || air[i]) << i;
}

TEST(AirPointsTest, ASparseCornerOfThreeWallsLosesAtMostItsApex) {
  // Three walls meeting at a corner, sampled 8 cm apart, beside a dense patch
  // that sets the median spacing at 1 cm: the corner is sparse, and the
  // neighbours of the points nearest its apex span the three walls.
  std::vector<float> xyz;
  for (int j = 0; j < 60; ++j)
    for (int i = 0; i < 60; ++i) xyz.insert(xyz.end(), {0.01f * float(i), 0.01f * float(j), 0.0f});
  const size_t patch = xyz.size() / 3;
  for (int wall = 0; wall < 3; ++wall)
    for (int j = 0; j < 12; ++j)
      for (int i = 0; i < 12; ++i) {
        if (wall > 0 && i == 0) continue;  // the shared edges once
        if (wall == 2 && j == 0) continue;
        float p[3] = {0, 0, 0};
        p[wall] = 0.0f;
        p[(wall + 1) % 3] = 0.08f * float(i);
        p[(wall + 2) % 3] = 0.08f * float(j);
        xyz.insert(xyz.end(), {5.0f + p[0], p[1], p[2]});
      }
  const size_t all = xyz.size() / 3;
  const std::vector<uint8_t> air = Air(xyz);
  EXPECT_EQ(Count(air, 0, patch), 0u);
  size_t near_apex = 0, flagged = 0;
  for (size_t i = patch; i < all; ++i) {
    if (!air[i]) continue;
    ++flagged;
    const double dx = xyz[3 * i] - 5.0, dy = xyz[3 * i + 1], dz = xyz[3 * i + 2];
    near_apex += std::sqrt(dx * dx + dy * dy + dz * dz) < 0.25;
  }
  EXPECT_EQ(flagged, near_apex) << "only points within 3 samples of the apex";
  EXPECT_LE(flagged, 10u);
}

TEST(AirPointsTest, ASparseNoisyCurvedSurfaceIsNotInTheAir) {
  // A dense wall (5 mm apart) and the side of a ball of 1 m radius that only
  // one far station saw (3 cm apart: sparse), both with 3 mm of noise off
  // their surface. At 3 cm spacing the noise and the ball's curve put half
  // of a sample's 16 nearest off every plane through it by more than 0.1
  // spacing; the scan's noise, measured on the wall, allows them. 300
  // returns in front of the wall.
  std::vector<float> xyz;
  std::mt19937 engine(7);
  std::normal_distribution<double> noise(0.0, 0.003);
  for (int j = 0; j < 200; ++j)
    for (int i = 0; i < 200; ++i) xyz.insert(xyz.end(), {0.005f * float(i), 0.005f * float(j), float(noise(engine))});
  const size_t wall = xyz.size() / 3;
  // A cap of 30 degrees of a Fibonacci sphere (evenly spread samples).
  const double radius = 1.0, golden = std::numbers::pi * (3.0 - std::sqrt(5.0)), top = std::cos(std::numbers::pi / 6);
  const int samples = int(4 * std::numbers::pi * radius * radius / (0.03 * 0.03));
  for (int c = 0; c < samples; ++c) {
    const double z = 1 - 2 * (c + 0.5) / samples, r = std::sqrt(1 - z * z), a = golden * c;
    if (z < top) break;
    const double length = radius + noise(engine);
    xyz.insert(xyz.end(), {float(3.0 + length * r * std::cos(a)), float(length * r * std::sin(a)), float(length * z)});
  }
  const size_t ball = xyz.size() / 3;
  Uniform random;
  for (int c = 0; c < 300; ++c)
    xyz.insert(xyz.end(), {float(0.2 + 0.6 * random()), float(0.2 + 0.6 * random()), float(0.1 + 0.5 * random())});
  const size_t all = xyz.size() / 3;
  AirReport report;
  const std::vector<uint8_t> air = Air(xyz, {}, &report);
  // The RMS off a plane fitted to 17 noisy samples: the fit takes up part of
  // the noise (2.3 mm here).
  EXPECT_GT(report.noise_m, 0.7 * 0.003);
  EXPECT_LT(report.noise_m, 0.003);
  EXPECT_EQ(Count(air, 0, wall), 0u);
  EXPECT_LE(Count(air, wall, ball), (ball - wall) / 100) << "of " << ball - wall;
  EXPECT_GE(Count(air, ball, all), 270u);
  // Without the noise allowance the plane test takes a part of the ball.
  const std::vector<uint8_t> strict = Air(xyz, {.noise_tolerance = 0});
  EXPECT_GT(Count(strict, wall, ball), (ball - wall) / 10) << "of " << ball - wall;
  EXPECT_GE(Count(strict, ball, all), 270u);
}

TEST(AirPointsTest, BadOptionsAndThreads) {
  std::vector<float> xyz = FallingDensityPlane();
  Uniform random;
  for (int c = 0; c < 100; ++c)
    xyz.insert(xyz.end(), {float(0.3 * random()), float(0.3 * random()), float(0.05 + 0.3 * random())});
  Expected<KnnIndex> index = KnnIndex::Build(xyz);
  ASSERT_TRUE(index.ok());
  EXPECT_FALSE(AirPoints(*index, {.k = 2}).ok());
  EXPECT_FALSE(AirPoints(*index, {.k = 65}).ok());
  EXPECT_FALSE(AirPoints(*index, {.spacing_ratio = 0.5}).ok());
  EXPECT_FALSE(AirPoints(*index, {.plane_tolerance = 0}).ok());
  EXPECT_FALSE(AirPoints(*index, {.passes = 0}).ok());
  EXPECT_FALSE(AirPoints(*index, {.noise_tolerance = -1}).ok());
  Expected<std::vector<uint8_t>> off = AirPoints(*index, {.spacing_ratio = 0});
  ASSERT_TRUE(off.ok());
  EXPECT_EQ(std::count(off->begin(), off->end(), uint8_t{1}), 0);
  std::vector<uint8_t> flags[2];
  for (int threads : {1, 2}) {
    tbb::task_arena arena(threads);
    arena.execute([&] { flags[threads - 1] = Air(xyz); });
  }
  EXPECT_EQ(flags[0], flags[1]);
  EXPECT_GT(std::count(flags[0].begin(), flags[0].end(), uint8_t{1}), 50);
}

}  // namespace
}  // namespace pb
