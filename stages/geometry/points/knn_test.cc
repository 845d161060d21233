// KnnIndex against brute force; statistical outlier removal and median
// spacing, which are thin layers over it.
#include "stages/geometry/points/knn.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "stages/geometry/points/outliers.h"
#include "stages/geometry/points/spacing.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

std::vector<Neighbor> BruteForce(const std::vector<float>& xyz, const float q[3], int k, int64_t exclude) {
  std::vector<Neighbor> all;
  for (size_t i = 0; i < xyz.size() / 3; ++i) {
    if (static_cast<int64_t>(i) == exclude) continue;
    const double dx = static_cast<double>(xyz[3 * i]) - q[0];
    const double dy = static_cast<double>(xyz[3 * i + 1]) - q[1];
    const double dz = static_cast<double>(xyz[3 * i + 2]) - q[2];
    all.push_back({.index = static_cast<uint32_t>(i), 
                   .squared_distance_m2 = dx * dx + dy * dy + dz * dz});
  }
  std::sort(all.begin(), all.end(), [](const Neighbor& a, const Neighbor& b) {
    return a.squared_distance_m2 < b.squared_distance_m2 ||
           (a.squared_distance_m2 == b.squared_distance_m2 && a.index < b.index);
  });
  all.resize(std::min<size_t>(all.size(), k));
  return all;
}

void ExpectSame(const std::vector<Neighbor>& expected, const std::vector<Neighbor>& actual, int count) {
  ASSERT_EQ(static_cast<size_t>(count), expected.size());
  for (int j = 0; j < count; ++j) {
    EXPECT_EQ(actual[j].index, expected[j].index) << "neighbour " << j;
    EXPECT_EQ(actual[j].squared_distance_m2, expected[j].squared_distance_m2) << "neighbour " << j;
  }
}

// Random cloud with clusters of exact duplicates and points on a coarse grid
// (many equal distances), the cases where tie-breaking matters.
std::vector<float> RandomCloud(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  std::vector<float> xyz;
  for (size_t i = 0; i < n; ++i) {
    if (i % 7 == 3 && i >= 3) {
      xyz.insert(xyz.end(), {xyz[3 * (i - 3)], xyz[3 * (i - 3) + 1], xyz[3 * (i - 3) + 2]});
    } else if (i % 5 == 0) {
      xyz.insert(xyz.end(), {std::round(uniform(rng) * 4) / 4, std::round(uniform(rng) * 4) / 4,
                             std::round(uniform(rng) * 4) / 4});
    } else {
      xyz.insert(xyz.end(), {uniform(rng), uniform(rng), 0.1f * uniform(rng)});
    }
  }
  return xyz;
}

TEST(KnnTest, MatchesBruteForce) {
  for (size_t n : {1u, 5u, 17u, 300u, 3000u}) {
    const std::vector<float> xyz = RandomCloud(n, static_cast<uint32_t>(n));
    auto index = KnnIndex::Build(xyz);
    ASSERT_TRUE(index.ok()) << index.status().message();
    ASSERT_EQ(index->size(), n);
    for (int k : {1, 3, 16, 40}) {
      std::vector<Neighbor> out(k);
      for (size_t i = 0; i < n; i += std::max<size_t>(1, n / 97)) {
        SCOPED_TRACE("n=" + std::to_string(n) + " k=" + std::to_string(k) + " i=" + std::to_string(i));
        const float* p = &xyz[3 * i];
        ExpectSame(BruteForce(xyz, p, k, i), out, index->QueryPoint(static_cast<uint32_t>(i), k, out));
        ExpectSame(BruteForce(xyz, p, k, -1), out, index->Query(p, k, out));
        const float off[3] = {p[0] + 0.01f, p[1] - 0.02f, p[2] + 0.3f};
        ExpectSame(BruteForce(xyz, off, k, -1), out, index->Query(off, k, out));
      }
    }
  }
}

// Slots: a permutation of the points; each neighbour's slot holds it.
TEST(KnnTest, SlotsLocateThePoints) {
  const size_t n = 500;
  const std::vector<float> xyz = RandomCloud(n, 4);
  auto index = KnnIndex::Build(xyz);
  ASSERT_TRUE(index.ok());
  std::vector<bool> seen(n, false);
  std::vector<Neighbor> out(16);
  for (size_t slot = 0; slot < n; ++slot) {
    const uint32_t i = index->PointAtSlot(slot);
    ASSERT_LT(i, n);
    EXPECT_FALSE(seen[i]) << "point " << i << " in two slots";
    seen[i] = true;
    EXPECT_EQ(index->SlotOf(i), slot);
    EXPECT_EQ(index->PositionAtSlot(slot),
              (std::array<float, 3>{xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]}));
    const int count = index->QueryPoint(i, 16, out);
    ASSERT_EQ(count, 16);
    for (int j = 0; j < count; ++j) EXPECT_EQ(index->PointAtSlot(out[j].slot), out[j].index);
  }
}

TEST(KnnTest, FewerPointsThanK) {
  const std::vector<float> xyz = {0, 0, 0, 1, 0, 0, 3, 0, 0};
  auto index = KnnIndex::Build(xyz);
  ASSERT_TRUE(index.ok());
  std::vector<Neighbor> out(10);
  ASSERT_EQ(index->QueryPoint(0, 10, out), 2);
  EXPECT_EQ(out[0].index, 1u);
  EXPECT_EQ(out[0].squared_distance_m2, 1.0);
  EXPECT_EQ(out[1].index, 2u);
  EXPECT_EQ(out[1].squared_distance_m2, 9.0);
  const float q[3] = {2.9f, 0, 0};
  ASSERT_EQ(index->Query(q, 10, out), 3);
  EXPECT_EQ(out[0].index, 2u);
  EXPECT_EQ(out[2].index, 0u);
  EXPECT_EQ(index->Query(q, 0, out), 0);

  auto empty = KnnIndex::Build({});
  ASSERT_TRUE(empty.ok());
  EXPECT_EQ(empty->Query(q, 3, out), 0);
}

TEST(KnnTest, AllDuplicates) {
  const std::vector<float> xyz(3 * 50, 0.25f);
  auto index = KnnIndex::Build(xyz);
  ASSERT_TRUE(index.ok());
  std::vector<Neighbor> out(4);
  ASSERT_EQ(index->QueryPoint(0, 4, out), 4);
  for (int j = 0; j < 4; ++j) {
    EXPECT_EQ(out[j].index, static_cast<uint32_t>(j + 1));
    EXPECT_EQ(out[j].squared_distance_m2, 0.0);
  }
}

TEST(KnnTest, RejectsBadInput) {
  const std::vector<float> nan = {0, 0, 0, 1, std::numeric_limits<float>::quiet_NaN(), 0};
  auto index = KnnIndex::Build(nan);
  ASSERT_FALSE(index.ok());
  EXPECT_THAT(index.status().message(), HasSubstr("point 1 has a non-finite coordinate"));
  const std::vector<float> ragged = {0, 0, 0, 1};
  EXPECT_THAT(KnnIndex::Build(ragged).status().message(), HasSubstr("expected 3 floats per point, got 4"));
}

// A plane of `side` x `side` points `step_m` apart, z = 0.
PointCloud Grid(int side, float step_m) {
  PointCloud cloud;
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) cloud.positions.insert(cloud.positions.end(), {x * step_m, y * step_m, 0.0f});
  }
  return cloud;
}

TEST(OutliersTest, RemovesPlantedFarPointsAndKeepsAttributes) {
  PointCloud cloud = Grid(40, 0.002f);
  const size_t plane = cloud.size();
  cloud.positions.insert(cloud.positions.end(), {0.03f, 0.03f, 0.5f, -0.4f, 0.01f, 0.02f, 0.05f, 0.9f, -0.3f});
  const size_t n = cloud.size();
  for (size_t i = 0; i < n; ++i) {
    cloud.colors.insert(cloud.colors.end(), {static_cast<uint8_t>(i % 256), 7, 9});
    cloud.normals.insert(cloud.normals.end(), {0, 0, 1});
    cloud.intensities.push_back(static_cast<float>(i) / n);
    cloud.station_ids.push_back(static_cast<uint16_t>(i % 2));
  }
  cloud.stations = {{1, 2, 3}, {4, 5, 6}};
  cloud.origin = {100, 200, 300};
  OutlierReport report;
  auto out = RemoveStatisticalOutliers(cloud, {}, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(report.points_in, n);
  EXPECT_EQ(report.removed, 3u);
  EXPECT_EQ(report.points_out, plane);
  ASSERT_EQ(out->size(), plane);
  EXPECT_EQ(out->positions, std::vector<float>(cloud.positions.begin(), cloud.positions.begin() + 3 * plane));
  EXPECT_EQ(out->colors, std::vector<uint8_t>(cloud.colors.begin(), cloud.colors.begin() + 3 * plane));
  EXPECT_EQ(out->normals.size(), 3 * plane);
  EXPECT_EQ(out->intensities.size(), plane);
  EXPECT_EQ(out->intensities[plane - 1], cloud.intensities[plane - 1]);
  EXPECT_EQ(out->station_ids.size(), plane);
  EXPECT_EQ(out->stations, cloud.stations);
  EXPECT_EQ(out->origin, cloud.origin);
  EXPECT_GT(report.threshold_m, report.mean_distance_m);
}

TEST(OutliersTest, SameResultWithOneAndTwoThreads) {
  PointCloud cloud;
  cloud.positions = RandomCloud(5000, 11);
  OutlierReport one, two;
  std::vector<float> kept_one, kept_two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    auto out = RemoveStatisticalOutliers(cloud, {.k = 8, .std_ratio = 1.0}, &one);
    ASSERT_TRUE(out.ok());
    kept_one = out->positions;
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    auto out = RemoveStatisticalOutliers(cloud, {.k = 8, .std_ratio = 1.0}, &two);
    ASSERT_TRUE(out.ok());
    kept_two = out->positions;
  }
  EXPECT_GT(one.removed, 0u);
  EXPECT_EQ(one.removed, two.removed);
  EXPECT_EQ(one.threshold_m, two.threshold_m);
  EXPECT_EQ(kept_one, kept_two);
}

TEST(OutliersTest, RejectsBadOptions) {
  const PointCloud cloud = Grid(3, 1.0f);
  EXPECT_THAT(RemoveStatisticalOutliers(cloud, {.k = 0}).status().message(),
              HasSubstr("k must be between 1 and 1000, got 0"));
  EXPECT_THAT(RemoveStatisticalOutliers(cloud, {.std_ratio = -1}).status().message(),
              HasSubstr("std_ratio must be a finite number >= 0"));
}

TEST(SpacingTest, RegularGrid) {
  const PointCloud cloud = Grid(200, 0.002f);
  auto all = MedianSpacing(cloud, {.sample = 0});
  ASSERT_TRUE(all.ok()) << all.status().message();
  EXPECT_NEAR(*all, 0.002, 1e-6);
  auto sampled = MedianSpacing(cloud, {.sample = 1000});
  ASSERT_TRUE(sampled.ok());
  EXPECT_NEAR(*sampled, 0.002, 1e-6);
}

TEST(SpacingTest, EvenCountAveragesMiddleValues) {
  PointCloud cloud;
  // Nearest-neighbour distances 1, 1, 3, 3: the median is 2.
  cloud.positions = {0, 0, 0, 1, 0, 0, 11, 0, 0, 14, 0, 0};
  auto spacing = MedianSpacing(cloud, {.sample = 0});
  ASSERT_TRUE(spacing.ok());
  EXPECT_DOUBLE_EQ(*spacing, 2.0);
  PointCloud single;
  single.positions = {0, 0, 0};
  EXPECT_THAT(MedianSpacing(single).status().message(), HasSubstr("needs at least 2 points, the cloud has 1"));
}

}  // namespace
}  // namespace pb
