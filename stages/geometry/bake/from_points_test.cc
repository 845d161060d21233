// BakeFromPoints (bake_from_points.h) on planes with known point patterns.
#include "stages/geometry/bake/from_points.h"

#include <gtest/gtest.h>

#include <algorithm>
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
    for (bool neighbors : {false, true}) {
      FromPointsOptions options = Options(mode);
      options.neighbors = neighbors;
      bake.threads = 1;
      PointCloud copy = cloud;
      auto one = BakeFromPoints(plane, std::move(copy), bake, options);
      bake.threads = 2;
      copy = cloud;
      auto two = BakeFromPoints(plane, std::move(copy), bake, options);
      ASSERT_TRUE(one.ok() && two.ok());
      EXPECT_EQ(one->maps.color.data, two->maps.color.data) << int(mode) << " " << neighbors;
      EXPECT_EQ(one->maps.normal.data, two->maps.normal.data) << int(mode) << " " << neighbors;
    }
  }
}

// Two faces folded 90 degrees about their shared edge BC (x = 1, z = 0):
// face 0 = A B C in z = 0, face 1 = B C D in x = 1, each with its own UV
// island (a seam along BC), face 1's turned a quarter relative to face 0's.
// Vertex colors black on purpose: the corners' values are wrong.
Mesh Fold() {
  Mesh mesh;
  auto vertex = [&](float x, float y, float z, float u, float v, std::array<float, 3> n) {
    mesh.positions.insert(mesh.positions.end(), {x, y, z});
    mesh.uvs.insert(mesh.uvs.end(), {u, v});
    mesh.normals.insert(mesh.normals.end(), n.begin(), n.end());
    mesh.colors.insert(mesh.colors.end(), {0, 0, 0});
  };
  // Face 0: uv = (0.05 + 0.4 x, 0.05 + 0.4 y).
  vertex(0, 0, 0, 0.05f, 0.05f, {0, 0, 1});
  vertex(1, 0, 0, 0.45f, 0.05f, {0, 0, 1});
  vertex(1, 1, 0, 0.45f, 0.45f, {0, 0, 1});
  // Face 1: uv = (0.55 + 0.4 y, 0.55 + 0.4 z).
  vertex(1, 0, 0, 0.55f, 0.55f, {1, 0, 0});
  vertex(1, 1, 0, 0.95f, 0.55f, {1, 0, 0});
  vertex(1, 0, 1, 0.55f, 0.95f, {1, 0, 0});
  mesh.indices = {0, 1, 2, 3, 4, 5};
  return mesh;
}

// The ramp both faces carry, linear in the fold's unfolded coordinates:
// u = x on face 0, 1 + z on face 1 (the distance across the fold), and y.
std::array<double, 3> Ramp(double u, double y) { return {40 + 100 * u, 128, 60 + 100 * y}; }

// Points on a jittered 0.1 m grid over both faces (sparse: 5 texels apart at
// 128^2), colored by the ramp, with their face's normal.
PointCloud FoldPoints() {
  PointCloud cloud;
  uint32_t state = 7;
  auto jitter = [&state] {
    state = state * 1664525u + 1013904223u;
    return 0.04f * (float(state >> 8) / float(1 << 24) - 0.5f);
  };
  auto add = [&](float x, float y, float z, double u, std::array<float, 3> n) {
    cloud.positions.insert(cloud.positions.end(), {x, y, z});
    const auto color = Ramp(u, y);
    for (double c : color) cloud.colors.push_back(uint8_t(std::lround(c)));
    cloud.normals.insert(cloud.normals.end(), n.begin(), n.end());
  };
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) {
      const float a = (i + 0.5f) / 10 + jitter(), b = (j + 0.5f) / 10 + jitter();
      if (b < a - 0.01f) add(a, b, 0, a, {0, 0, 1});       // face 0: x = a, y = b
      if (a + b < 0.99f) add(1, a, b, 1 + b, {1, 0, 0});   // face 1: y = a, z = b
    }
  }
  return cloud;
}

// Largest deviation from the ramp over the texels of both faces at least
// `margin` meters inside their outer edges (the fold edge BC included).
double WorstRampError(const BakeResult& result, int size, double margin) {
  double worst = 0;
  for (int ty = 0; ty < size; ++ty) {
    for (int tx = 0; tx < size; ++tx) {
      const double u = (tx + 0.5) / size, v = 1 - (ty + 0.5) / size;
      std::array<double, 3> expected;
      if (u < 0.5) {  // face 0: x, y in [0, 1], y <= x
        const double x = (u - 0.05) / 0.4, y = (v - 0.05) / 0.4;
        if (!(y >= margin && (x - y) / std::sqrt(2.0) >= margin && x <= 1)) continue;
        expected = Ramp(x, y);
      } else {  // face 1: y, z >= 0, y + z <= 1
        const double y = (u - 0.55) / 0.4, z = (v - 0.55) / 0.4;
        if (!(y >= margin && (1 - y - z) / std::sqrt(2.0) >= margin && z >= 0)) continue;
        expected = Ramp(1 + z, y);
      }
      for (int c = 0; c < 3; ++c) {
        worst = std::max(worst, std::abs(result.maps.color.at_u8(tx, ty, c) - expected[c]));
      }
    }
  }
  return worst;
}

constexpr int kFoldSize = 128;

// The fold baked at kFoldSize^2 without gutter, by Delaunay.
Expected<BakeResult> BakeFold(PointCloud points, bool neighbors, FromPointsReport* report) {
  BakeOptions bake;
  bake.size = kFoldSize;
  bake.gutter = 0;
  FromPointsOptions options = Options(TexelInterpolation::kDelaunay);
  options.neighbors = neighbors;
  return BakeFromPoints(Fold(), std::move(points), bake, options, report);
}

TEST(BakeFromPointsTest, NeighborsCarryTheColorAcrossEdgesSeamsAndFolds) {
  FromPointsReport report;
  auto with = BakeFold(FoldPoints(), /*neighbors=*/true, &report);
  ASSERT_TRUE(with.ok()) << with.status().message();
  EXPECT_EQ(report.faces_from_corners, 0u);
  EXPECT_GT(report.points_borrowed, 0u);
  // Linear interpolation reproduces the ramp wherever the points surround
  // the texel: right up to the fold, across the seam and the quarter turn,
  // with none of the corners' black.
  EXPECT_LE(WorstRampError(*with, kFoldSize, 0.12), 2.0);
  // The paper's per-face triangulation: between the last points and the
  // fold edge the texels blend towards the black corners.
  auto without = BakeFold(FoldPoints(), /*neighbors=*/false, &report);
  ASSERT_TRUE(without.ok());
  EXPECT_EQ(report.points_borrowed, 0u);
  EXPECT_GT(WorstRampError(*without, kFoldSize, 0.12), 40.0);
}

// A face with no point of its own borrows none: it keeps its corners'
// blend (here black), as in the paper, while its neighbour borrows nothing
// from it either.
TEST(BakeFromPointsTest, NeighborsLeaveAFaceWithoutPointsToItsCorners) {
  PointCloud all = FoldPoints(), face0;
  for (size_t i = 0; i < all.size(); ++i) {
    if (all.positions[3 * i + 2] != 0) continue;  // keep the points in z = 0
    for (int c = 0; c < 3; ++c) {
      face0.positions.push_back(all.positions[3 * i + c]);
      face0.colors.push_back(all.colors[3 * i + c]);
      face0.normals.push_back(all.normals[3 * i + c]);
    }
  }
  FromPointsReport report;
  auto result = BakeFold(std::move(face0), /*neighbors=*/true, &report);
  ASSERT_TRUE(result.ok()) << result.status().message();
  EXPECT_EQ(report.faces_from_corners, 1u);
  EXPECT_EQ(report.points_borrowed, 0u);
  size_t checked = 0;
  for (int ty = 0; ty < kFoldSize; ++ty) {
    for (int tx = kFoldSize / 2; tx < kFoldSize; ++tx) {  // face 1's island
      for (int c = 0; c < 3; ++c) ASSERT_EQ(result->maps.color.at_u8(tx, ty, c), 0) << tx << "," << ty;
      ++checked;
    }
  }
  EXPECT_GT(checked, 0u);
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
