// BakeRaster, frames, maps, dilation (bake_raster.h) and BakeVertexColors
// (bake.h).
#include "stages/geometry/bake/bake.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "stages/geometry/bake/raster.h"
#include "stages/geometry/core/tangents.h"

namespace pb {
namespace {

// A unit square in the z = 0 plane, uv = xy, two faces: (0,1,2), (0,2,3).
Mesh UnitQuad() {
  Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  mesh.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  mesh.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  mesh.colors = {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  return mesh;
}

// One triangle with the given uv corners (positions = uv, z = 0).
Mesh Triangle(float u0, float v0, float u1, float v1, float u2, float v2) {
  Mesh mesh;
  mesh.positions = {u0, v0, 0, u1, v1, 0, u2, v2, 0};
  mesh.uvs = {u0, v0, u1, v1, u2, v2};
  mesh.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  mesh.colors = {200, 10, 10, 10, 200, 10, 10, 10, 200};
  mesh.indices = {0, 1, 2};
  return mesh;
}

// A grid of n x n quads in the unit square with jittered interior vertices
// and both diagonals' orientations, uv = xy: many faces sharing edges.
Mesh JitteredGrid(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.3f, 0.3f);
  std::uniform_int_distribution<int> byte(0, 255);
  Mesh mesh;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      float x = float(i) / n, y = float(j) / n;
      if (i > 0 && i < n && j > 0 && j < n) {
        x += jitter(rng) / n;
        y += jitter(rng) / n;
      }
      mesh.positions.insert(mesh.positions.end(), {x, y, 0.1f * x * y});
      mesh.uvs.insert(mesh.uvs.end(), {x, y});
      for (int c = 0; c < 3; ++c) mesh.colors.push_back(uint8_t(byte(rng)));
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      if ((i + j) % 2) {
        mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
      } else {
        mesh.indices.insert(mesh.indices.end(), {a, b, d, b, c, d});
      }
    }
  }
  return mesh;
}

TEST(BakeRasterTest, QuadCoversEveryTexelOnceAtItsCentre) {
  const Mesh quad = UnitQuad();
  auto raster = BakeRaster::Build(quad, 16);
  ASSERT_TRUE(raster.ok()) << raster.status().message();
  EXPECT_EQ(raster->covered_texels(), 256u);
  EXPECT_EQ(raster->edge_texels(), 0u);
  std::vector<BakeTexel> texels;
  size_t total = 0;
  for (uint32_t face = 0; face < 2; ++face) {
    raster->TexelsOf(quad, face, texels);
    total += texels.size();
    for (const BakeTexel& texel : texels) {
      EXPECT_FLOAT_EQ(texel.s, texel.x + 0.5f);
      EXPECT_FLOAT_EQ(texel.t, texel.y + 0.5f);
      EXPECT_EQ(raster->owner(texel.x, texel.y), face);
    }
  }
  EXPECT_EQ(total, 256u);
  // Texel (3, 3) has its centre on the diagonal u = v... in texel space the
  // diagonal from uv (0,0) to (1,1) runs from (0,16) to (16,0): s + t = 16.
  // Texel (7, 8) has centre (7.5, 8.5) on it: both faces contain it, the
  // lower index wins.
  EXPECT_EQ(raster->owner(7, 8), 0u);
  // Face 0 = (0,0),(1,0),(1,1): below the diagonal in uv = right/bottom in
  // texel space (s + t > 16).
  EXPECT_EQ(raster->owner(15, 15), 0u);
  EXPECT_EQ(raster->owner(0, 0), 1u);
}

TEST(BakeRasterTest, EdgeTexelsSampleTheNearestPointOfTheFace) {
  // A small triangle, about 5 texels wide at 32.
  const Mesh tri = Triangle(0.30f, 0.30f, 0.47f, 0.31f, 0.35f, 0.46f);
  auto raster = BakeRaster::Build(tri, 32);
  ASSERT_TRUE(raster.ok());
  ASSERT_GT(raster->edge_texels(), 0u);
  std::vector<BakeTexel> texels;
  raster->TexelsOf(tri, 0, texels);
  ASSERT_EQ(texels.size(), raster->covered_texels());
  size_t edge = 0;
  for (const BakeTexel& texel : texels) {
    const bool inside = raster->centre_inside(texel.x, texel.y);
    if (!inside) ++edge;
    // The sample point is the barycentric combination of the corners.
    float s = 0, t = 0;
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(texel.bary[k], 0.0f);
      s += texel.bary[k] * tri.uvs[2 * k] * 32;
      t += texel.bary[k] * (1 - tri.uvs[2 * k + 1]) * 32;
    }
    EXPECT_NEAR(s, texel.s, 1e-4);
    EXPECT_NEAR(t, texel.t, 1e-4);
    // The face touches the texel's square, so its nearest point is no
    // farther than the square's half diagonal from the centre.
    EXPECT_LE(std::hypot(texel.s - (texel.x + 0.5f), texel.t - (texel.y + 0.5f)),
              std::sqrt(0.5f) + 1e-5f);
  }
  EXPECT_EQ(edge, raster->edge_texels());
  // Every texel whose centre the triangle contains is owned with its centre.
  EXPECT_TRUE(raster->centre_inside(11, 18));  // centre (11.5, 18.5) = uv (0.36, 0.42)
}

TEST(BakeRasterTest, OwnershipDoesNotDependOnThreads) {
  const Mesh grid = JitteredGrid(23, 7);
  auto one = BakeRaster::Build(grid, 200, 1);
  auto two = BakeRaster::Build(grid, 200, 2);
  ASSERT_TRUE(one.ok() && two.ok());
  EXPECT_EQ(one->covered_texels(), 200u * 200u);
  for (int y = 0; y < 200; ++y) {
    for (int x = 0; x < 200; ++x) ASSERT_EQ(one->owner(x, y), two->owner(x, y)) << x << "," << y;
  }
}

TEST(BakeRasterTest, RejectsMeshWithoutUvsAndBadSizes) {
  Mesh quad = UnitQuad();
  EXPECT_FALSE(BakeRaster::Build(quad, 0).ok());
  EXPECT_FALSE(BakeRaster::Build(quad, 40000).ok());
  quad.uvs.clear();
  auto raster = BakeRaster::Build(quad, 16);
  ASSERT_FALSE(raster.ok());
  EXPECT_NE(raster.status().message().find("no uvs"), std::string::npos);
}

TEST(BakeRasterTest, DegenerateUvFacesOwnNothing) {
  Mesh tri = Triangle(0.1f, 0.1f, 0.5f, 0.5f, 0.9f, 0.9f);  // collinear in uv
  auto raster = BakeRaster::Build(tri, 32);
  ASSERT_TRUE(raster.ok());
  EXPECT_EQ(raster->covered_texels(), 0u);
}

TEST(BakeFrameTest, TangentSpaceOfAFlatQuad) {
  auto mesh = PrepareBakeMesh(UnitQuad());
  ASSERT_TRUE(mesh.ok());
  const TexelFrame frame = FrameAt(*mesh, 0, {0.2f, 0.3f, 0.5f});
  EXPECT_NEAR(frame.position[0], 0.8f, 1e-6);  // 0.3 * 1 + 0.5 * 1
  EXPECT_NEAR(frame.position[1], 0.5f, 1e-6);
  const auto n = ToTangentSpace(frame, {0, 0, 1});
  EXPECT_NEAR(n[2], 1.0f, 1e-6);
  const auto t = ToTangentSpace(frame, {1, 0, 0});  // +u
  EXPECT_NEAR(t[0], 1.0f, 1e-6);
  const auto b = ToTangentSpace(frame, {0, 1, 0});  // +v
  EXPECT_NEAR(b[1], 1.0f, 1e-6);
  const auto tilted = ToTangentSpace(frame, {0.6f, 0, 0.8f});
  EXPECT_NEAR(tilted[0], 0.6f, 1e-6);
  EXPECT_NEAR(tilted[2], 0.8f, 1e-6);
  const auto zero = ToTangentSpace(frame, {0, 0, 0});
  EXPECT_EQ(zero, (std::array<float, 3>{0, 0, 1}));
}

TEST(BakeFrameTest, MirroredUvsFlipTheBitangent) {
  Mesh quad = UnitQuad();
  for (size_t i = 0; i < quad.uvs.size(); i += 2) quad.uvs[i] = 1 - quad.uvs[i];  // mirror u
  quad.indices = {0, 2, 1, 0, 3, 2};  // keep uv winding non-degenerate; 3-D winding flips
  auto mesh = PrepareBakeMesh(quad);
  ASSERT_TRUE(mesh.ok());
  const TexelFrame frame = FrameAt(*mesh, 0, {1.0f / 3, 1.0f / 3, 1.0f / 3});
  // +u is now -x; +v is still +y.
  EXPECT_NEAR(ToTangentSpace(frame, {-1, 0, 0})[0], 1.0f, 1e-5);
  EXPECT_NEAR(ToTangentSpace(frame, {0, 1, 0})[1], 1.0f, 1e-5);
}

TEST(BakeVertexColorsTest, InterpolatesVertexColorsAndKeepsTheNormalMapFlat) {
  BakeOptions options;
  options.size = 16;
  options.gutter = 0;
  auto result = BakeVertexColors(UnitQuad(), options);
  ASSERT_TRUE(result.ok()) << result.status().message();
  EXPECT_EQ(result->covered_texels, 256u);
  ASSERT_TRUE(result->mesh.has_tangents());
  // Texel (12, 14): centre (12.5, 14.5) -> uv (0.78125, 0.09375), face 0
  // (corners (0,0) red, (1,0) green, (1,1) blue): barycentrics
  // (1 - u, u - v, v) = (0.21875, 0.6875, 0.09375).
  const Image& color = result->maps.color;
  EXPECT_EQ(color.at_u8(12, 14, 0), std::lround(0.21875 * 255));
  EXPECT_EQ(color.at_u8(12, 14, 1), std::lround(0.6875 * 255));
  EXPECT_EQ(color.at_u8(12, 14, 2), std::lround(0.09375 * 255));
  const Image& normal = result->maps.normal;
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) {
      ASSERT_EQ(normal.at_u8(x, y, 0), 128);
      ASSERT_EQ(normal.at_u8(x, y, 1), 128);
      ASSERT_EQ(normal.at_u8(x, y, 2), 255);
    }
  }
}

TEST(BakeVertexColorsTest, FloatNormalsAreExactlyFlat) {
  BakeOptions options;
  options.size = 8;
  options.float_normals = true;
  auto result = BakeVertexColors(UnitQuad(), options);
  ASSERT_TRUE(result.ok());
  EXPECT_EQ(result->maps.normal.type, Image::PixelType::kF32);
  EXPECT_EQ(result->maps.normal.at_f32(3, 3, 2), 1.0f);
  EXPECT_EQ(result->maps.normal.at_f32(3, 3, 0), 0.0f);
}

TEST(BakeVertexColorsTest, GutterDilatesRingsWithTheNeighbourMean) {
  // A one-color triangle in the middle of a 64 map.
  Mesh tri = Triangle(0.4f, 0.4f, 0.6f, 0.4f, 0.5f, 0.6f);
  tri.colors = {100, 150, 200, 100, 150, 200, 100, 150, 200};
  BakeOptions options;
  options.size = 64;
  options.gutter = 3;
  auto result = BakeVertexColors(tri, options);
  ASSERT_TRUE(result.ok());
  auto raster = BakeRaster::Build(result->mesh, 64);
  ASSERT_TRUE(raster.ok());
  // Chebyshev distance of each texel to the covered set.
  size_t filled = 0;
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      int distance = 99;
      for (int yy = std::max(0, y - 4); yy <= std::min(63, y + 4); ++yy) {
        for (int xx = std::max(0, x - 4); xx <= std::min(63, x + 4); ++xx) {
          if (raster->owner(xx, yy) != BakeRaster::kNoFace) {
            distance = std::min(distance, std::max(std::abs(xx - x), std::abs(yy - y)));
          }
        }
      }
      const uint8_t red = result->maps.color.at_u8(x, y, 0);
      if (distance >= 1 && distance <= 3) {
        ++filled;
        ASSERT_EQ(red, 100) << x << "," << y;  // mean of equal colors
        ASSERT_EQ(result->maps.color.at_u8(x, y, 2), 200);
      } else if (distance > 3) {
        ASSERT_EQ(red, 0) << x << "," << y;
      }
    }
  }
  EXPECT_EQ(filled, result->gutter_texels);
  EXPECT_GT(filled, 0u);
}

TEST(BakeVertexColorsTest, ThreadCountDoesNotChangeBytes) {
  const Mesh grid = JitteredGrid(31, 3);
  BakeOptions options;
  options.size = 256;
  options.gutter = 4;
  options.threads = 1;
  auto one = BakeVertexColors(grid, options);
  options.threads = 2;
  auto two = BakeVertexColors(grid, options);
  ASSERT_TRUE(one.ok() && two.ok());
  EXPECT_EQ(one->maps.color.data, two->maps.color.data);
  EXPECT_EQ(one->maps.normal.data, two->maps.normal.data);
  EXPECT_EQ(one->mesh.tangents, two->mesh.tangents);
}

TEST(BakeVertexColorsTest, NeedsColorsAndUvs) {
  Mesh quad = UnitQuad();
  quad.colors.clear();
  auto result = BakeVertexColors(quad, BakeOptions{});
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.status().message().find("no vertex colors"), std::string::npos);
  quad = UnitQuad();
  quad.uvs.clear();
  EXPECT_FALSE(BakeVertexColors(quad, BakeOptions{}).ok());
}

}  // namespace
}  // namespace pb
