// BakeFromPoints (bake_from_points.h) on planes with known point patterns.
#include "stages/geometry/bake/from_points.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pb {
namespace {

// A unit square in z = 0, uv = xy, two faces, vertex colors all gray 50.
Mesh Plane() {
  Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  mesh.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  mesh.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  mesh.colors.assign(12, 50);
  mesh.indices = {0, 1, 2, 0, 2, 3};
  return mesh;
}

// The color the pattern gives texel (x, y).
std::array<uint8_t, 3> PatternColor(int x, int y) {
  return {uint8_t(10 + 15 * x), uint8_t(10 + 15 * y), uint8_t((x * 7 + y * 3) % 256)};
}

// One point above the centre of every texel of a size x size map (uv = xy,
// so texel (x, y) centre is at ((x + .5) / size, 1 - (y + .5) / size)), 1 mm
// off the plane, with the pattern color and a normal tilted by `tilt` about y.
PointCloud TexelCentrePoints(int size, double tilt_rad) {
  PointCloud cloud;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      cloud.positions.insert(cloud.positions.end(),
                             {float((x + 0.5) / size), float(1 - (y + 0.5) / size), 0.001f});
      const auto color = PatternColor(x, y);
      cloud.colors.insert(cloud.colors.end(), color.begin(), color.end());
      cloud.normals.insert(cloud.normals.end(),
                           {float(std::sin(tilt_rad)), 0.0f, float(std::cos(tilt_rad))});
    }
  }
  return cloud;
}

FromPointsOptions Options(TexelInterpolation mode) {
  FromPointsOptions options;
  options.max_distance_m = 0.01;
  options.max_angle_deg = 90;
  options.interpolation.mode = mode;
  options.splat_sigma_m = 0.25 / 16;
  return options;
}

TEST(BakeFromPointsTest, PointsAtTexelCentresBakeToExactlyTheirTexels) {
  BakeOptions bake;
  bake.size = 16;
  bake.gutter = 0;
  for (TexelInterpolation mode : {TexelInterpolation::kDelaunay, TexelInterpolation::kNearest,
                                  TexelInterpolation::kIdw}) {
    FromPointsReport report;
    auto result = BakeFromPoints(Plane(), TexelCentrePoints(16, 0.3), bake, Options(mode), &report);
    ASSERT_TRUE(result.ok()) << result.status().message();
    EXPECT_EQ(report.assign.assigned, 256u);
    EXPECT_EQ(report.faces_from_corners, 0u);
    for (int y = 0; y < 16; ++y) {
      for (int x = 0; x < 16; ++x) {
        const auto expected = PatternColor(x, y);
        for (int c = 0; c < 3; ++c) {
          ASSERT_EQ(result->maps.color.at_u8(x, y, c), expected[c])
              << "mode " << int(mode) << " texel " << x << "," << y << " channel " << c;
        }
        // Normal tilted by 0.3 rad about y: tangent space (sin, 0, cos).
        ASSERT_NEAR(result->maps.normal.at_u8(x, y, 0), std::lround((std::sin(0.3) + 1) * 127.5), 1)
            << x << "," << y;
        ASSERT_NEAR(result->maps.normal.at_u8(x, y, 1), 128, 1);
        ASSERT_NEAR(result->maps.normal.at_u8(x, y, 2), std::lround((std::cos(0.3) + 1) * 127.5), 1);
      }
    }
  }
}

TEST(BakeFromPointsTest, FacesWithoutPointsTakeTheirCornerColors) {
  BakeOptions bake;
  bake.size = 16;
  bake.gutter = 0;
  PointCloud far = TexelCentrePoints(4, 0);
  for (size_t i = 2; i < far.positions.size(); i += 3) far.positions[i] = 0.5f;  // 0.5 m away
  FromPointsReport report;
  auto result = BakeFromPoints(Plane(), std::move(far), bake, Options(TexelInterpolation::kDelaunay), &report);
  ASSERT_TRUE(result.ok());
  EXPECT_EQ(report.assign.assigned, 0u);
  EXPECT_EQ(report.assign.too_far, 16u);
  EXPECT_EQ(report.faces_from_corners, 2u);
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) ASSERT_EQ(result->maps.color.at_u8(x, y, 0), 50);
  }
}

TEST(BakeFromPointsTest, PointsOnTheWrongSideAreRejectedByAngle) {
  BakeOptions bake;
  bake.size = 16;
  bake.gutter = 0;
  FromPointsReport report;
  // Normals pointing away from the face normal (160 degrees off).
  auto result = BakeFromPoints(Plane(), TexelCentrePoints(16, 160 * M_PI / 180), bake,
                               Options(TexelInterpolation::kDelaunay), &report);
  ASSERT_TRUE(result.ok());
  EXPECT_EQ(report.assign.assigned, 0u);
  EXPECT_EQ(report.assign.wrong_angle, 256u);
}

TEST(BakeFromPointsTest, ThreadCountDoesNotChangeBytes) {
  // An irregular cloud on a plane with many faces: jittered points.
  Mesh plane;
  const int n = 12;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      plane.positions.insert(plane.positions.end(), {float(i) / n, float(j) / n, 0});
      plane.uvs.insert(plane.uvs.end(), {float(i) / n, float(j) / n});
      plane.normals.insert(plane.normals.end(), {0, 0, 1});
      plane.colors.insert(plane.colors.end(), {uint8_t(i * 20), uint8_t(j * 20), 90});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i;
      plane.indices.insert(plane.indices.end(), {a, a + 1, a + n + 2, a, a + n + 2, a + n + 1});
    }
  }
  PointCloud cloud;
  uint32_t state = 12345;
  auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return float(state >> 8) / float(1 << 24);
  };
  for (int i = 0; i < 20000; ++i) {
    const float x = next(), y = next();
    cloud.positions.insert(cloud.positions.end(), {x, y, 0.002f * (next() - 0.5f)});
    cloud.colors.insert(cloud.colors.end(), {uint8_t(255 * x), uint8_t(255 * next()), uint8_t(255 * y)});
    const float tilt = 0.4f * (next() - 0.5f);
    cloud.normals.insert(cloud.normals.end(), {std::sin(tilt), 0, std::cos(tilt)});
  }
  BakeOptions bake;
  bake.size = 128;
  bake.gutter = 3;
  for (TexelInterpolation mode : {TexelInterpolation::kDelaunay, TexelInterpolation::kNearest,
                                  TexelInterpolation::kIdw, TexelInterpolation::kSplat}) {
    bake.threads = 1;
    PointCloud copy = cloud;
    auto one = BakeFromPoints(plane, std::move(copy), bake, Options(mode));
    bake.threads = 2;
    copy = cloud;
    auto two = BakeFromPoints(plane, std::move(copy), bake, Options(mode));
    ASSERT_TRUE(one.ok() && two.ok());
    EXPECT_EQ(one->maps.color.data, two->maps.color.data) << int(mode);
    EXPECT_EQ(one->maps.normal.data, two->maps.normal.data) << int(mode);
  }
}

TEST(BakeFromPointsTest, NeedsColoredPoints) {
  PointCloud cloud = TexelCentrePoints(4, 0);
  cloud.colors.clear();
  auto result = BakeFromPoints(Plane(), std::move(cloud), BakeOptions{}, Options(TexelInterpolation::kDelaunay));
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.status().message().find("no colors"), std::string::npos);
}

}  // namespace
}  // namespace pb
