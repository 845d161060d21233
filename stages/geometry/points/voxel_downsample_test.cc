#include "stages/geometry/points/voxel_downsample.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pb {
namespace {

TEST(VoxelDownsampleTest, ExactAveragesPerVoxel) {
  PointCloud cloud;
  cloud.origin = {100.0, 0.0, 0.0};
  // Voxel 1 m. Points in absolute cells (101,0,0) x3 and (100,0,0) x1 and
  // (100,1,0) x2, listed out of order.
  cloud.positions = {1.25f, 0.5f, 0.5f,  0.25f, 0.25f, 0.25f, 1.75f, 0.25f, 0.75f,
                     0.5f,  1.5f, 0.0f,  1.0f,  0.0f,  0.5f,  0.5f,  1.5f,  0.5f};
  cloud.colors = {10, 20, 30, 200, 200, 200, 11, 21, 31, 0, 0, 0, 12, 22, 33, 255, 255, 255};
  cloud.normals = {0, 0, 1, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, -1};
  cloud.intensities = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f};
  cloud.stations = {{0, 0, 0}, {5, 5, 5}};
  cloud.station_ids = {1, 0, 0, 1, 0, 1};
  auto result = VoxelDownsample(cloud, {.voxel_m = 1.0});
  ASSERT_TRUE(result.ok()) << result.status().message();
  const PointCloud& out = *result;
  EXPECT_EQ(out.origin, cloud.origin);
  ASSERT_EQ(out.size(), 3u);
  // Sorted by cell: (100,0,0), (100,1,0), (101,0,0).
  EXPECT_EQ(out.positions, (std::vector<float>{0.25f, 0.25f, 0.25f, 0.5f, 1.5f, 0.25f,
                                               static_cast<float>(4.0 / 3.0), 0.25f,
                                               static_cast<float>(1.75 / 3.0)}));
  // Colors: rounded means (128 from 127.5, 11 from 11, 31.33 -> 31).
  EXPECT_EQ(out.colors, (std::vector<uint8_t>{200, 200, 200, 128, 128, 128, 11, 21, 31}));
  // Normals: renormalized means; the opposite pair falls back to the first.
  EXPECT_FLOAT_EQ(out.normals[0], 1.0f);
  EXPECT_EQ((std::vector<float>{out.normals[3], out.normals[4], out.normals[5]}),
            (std::vector<float>{0, 0, 1}));
  const float inv = static_cast<float>(1.0 / std::sqrt(5.0));
  EXPECT_FLOAT_EQ(out.normals[6], 0.0f);
  EXPECT_FLOAT_EQ(out.normals[7], inv);
  EXPECT_FLOAT_EQ(out.normals[8], 2 * inv);
  // Intensities average; each voxel keeps the station of its first point.
  ASSERT_EQ(out.intensities.size(), 3u);
  EXPECT_FLOAT_EQ(out.intensities[0], 0.2f);
  EXPECT_FLOAT_EQ(out.intensities[1], 0.5f);
  EXPECT_FLOAT_EQ(out.intensities[2], 0.3f);
  EXPECT_EQ(out.stations, cloud.stations);
  EXPECT_EQ(out.station_ids, (std::vector<uint16_t>{0, 1, 1}));
}

TEST(VoxelDownsampleTest, GridIsAlignedToAbsoluteCoordinates) {
  PointCloud a;
  a.positions = {0.4f, 0, 0, 0.6f, 0, 0};
  PointCloud b = a;
  b.origin = {0.5, 0, 0};  // same offsets, shifted half a voxel: now in two cells
  EXPECT_EQ(VoxelDownsample(a, {.voxel_m = 1.0})->size(), 1u);
  EXPECT_EQ(VoxelDownsample(b, {.voxel_m = 1.0})->size(), 2u);
}

TEST(VoxelDownsampleTest, RejectsBadVoxelAndHugeGrids) {
  PointCloud cloud;
  cloud.positions = {0, 0, 0, 1000, 0, 0};
  EXPECT_EQ(VoxelDownsample(cloud, {.voxel_m = 0}).status().code(), Status::Code::kInvalid);
  EXPECT_EQ(VoxelDownsample(cloud, {.voxel_m = -1}).status().code(), Status::Code::kInvalid);
  EXPECT_EQ(VoxelDownsample(cloud, {.voxel_m = 1e-6}).status().code(), Status::Code::kInvalid);
  EXPECT_EQ(VoxelDownsample(PointCloud{}, {.voxel_m = 0.1})->size(), 0u);
}

}  // namespace
}  // namespace pb
