// Stray points (strays.h): a lone return and a floating cluster beside a
// scanned surface are strays; the surface, its border, a far field sparser
// with range and a thin line of samples are not.
#include "stages/geometry/points/strays.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
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

}  // namespace
}  // namespace pb
