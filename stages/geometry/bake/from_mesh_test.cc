#include "stages/geometry/bake/from_mesh.h"
#include "stages/geometry/testing/meshes.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>

namespace pb {
namespace {

using testing::LowGrid;
using testing::Sheet;

using ::testing::HasSubstr;


void Append(Mesh& to, const Mesh& from) {
  const uint32_t base = uint32_t(to.vertex_count());
  to.positions.insert(to.positions.end(), from.positions.begin(), from.positions.end());
  to.colors.insert(to.colors.end(), from.colors.begin(), from.colors.end());
  to.normals.insert(to.normals.end(), from.normals.begin(), from.normals.end());
  for (uint32_t index : from.indices) to.indices.push_back(base + index);
}

constexpr std::array<uint8_t, 3> kRed = {255, 0, 0};
constexpr std::array<uint8_t, 3> kBlue = {0, 0, 255};
// Dyadic heights and extents, exact in float even when shifted by an origin.
constexpr double kAbove = 1.0 / 64;

std::function<double(double, double)> Flat(double z) {
  return [z](double, double) { return z; };
}
std::function<std::array<uint8_t, 3>(double, double)> Uniform(std::array<uint8_t, 3> c) {
  return [c](double, double) { return c; };
}

// Left half red, right half blue, as two sheets that meet at x = 0.5 (so no
// triangle blends the two), reaching past the low square so that its border
// texels hit too.
Mesh RedBlue(double z) {
  Mesh high = Sheet(-0.125, 0.5, -0.125, 1.125, 20, Flat(z), Uniform(kRed));
  Append(high, Sheet(0.5, 1.125, -0.125, 1.125, 20, Flat(z), Uniform(kBlue)));
  return high;
}

BakeOptions Options(int size) {
  BakeOptions options;
  options.size = size;
  options.gutter = 2;
  options.threads = 1;
  return options;
}

std::array<uint8_t, 3> ColorAt(const BakeResult& result, int x, int y) {
  const Image& c = result.maps.color;
  return {c.at_u8(x, y, 0), c.at_u8(x, y, 1), c.at_u8(x, y, 2)};
}

// The 8-bit normal map's value at (x, y) decoded to [-1, 1].
std::array<double, 3> NormalAt(const BakeResult& result, int x, int y) {
  std::array<double, 3> n{};
  for (int k = 0; k < 3; ++k) n[k] = result.maps.normal.at_u8(x, y, k) / 255.0 * 2.0 - 1.0;
  return n;
}

TEST(BakeFromMeshTest, RedBlueSheetAboveIsBakedWhereItLies) {
  const int size = 64;
  FromMeshReport report;
  auto result = BakeFromMesh(LowGrid(1), RedBlue(kAbove), Options(size), {}, &report);
  ASSERT_TRUE(result.ok()) << result.status().message();
  EXPECT_EQ(result->covered_texels, size_t(size * size));
  EXPECT_EQ(report.texels_hit, size_t(size * size));
  EXPECT_EQ(report.texels_fallback, 0u);
  EXPECT_EQ(report.rays_cast, 2u * size * size);
  EXPECT_NEAR(report.mean_hit_distance_m, kAbove, 1e-6);
  EXPECT_TRUE(result->mesh.has_tangents());
  EXPECT_TRUE(result->mesh.has_normals());
  int far_mismatches = 0, near_mismatches = 0;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double u = (x + 0.5) / size;
      const auto expected = u < 0.5 ? kRed : kBlue;
      if (ColorAt(*result, x, y) != expected) {
        (std::abs(u - 0.5) <= 1.0 / size ? near_mismatches : far_mismatches)++;
      }
      // A parallel sheet: the flat tangent-space normal (0, 0, 1).
      EXPECT_EQ(result->maps.normal.at_u8(x, y, 0), 128);
      EXPECT_EQ(result->maps.normal.at_u8(x, y, 1), 128);
      EXPECT_EQ(result->maps.normal.at_u8(x, y, 2), 255);
    }
  }
  EXPECT_EQ(far_mismatches, 0);
  EXPECT_LE(near_mismatches, size);
}

TEST(BakeFromMeshTest, SheetBelowIsFoundByTheBackwardRay) {
  const int size = 32;
  FromMeshReport report;
  auto result = BakeFromMesh(LowGrid(2), RedBlue(-kAbove), Options(size), {}, &report);
  ASSERT_TRUE(result.ok()) << result.status().message();
  EXPECT_EQ(report.texels_hit, size_t(size * size));
  EXPECT_EQ(ColorAt(*result, 3, 10), kRed);
  EXPECT_EQ(ColorAt(*result, size - 3, 10), kBlue);
}

TEST(BakeFromMeshTest, NearerSheetWinsAndTiesGoForward) {
  const int size = 16;
  auto bake = [&](double red_z, double blue_z) {
    Mesh high = Sheet(-0.125, 1.125, -0.125, 1.125, 4, Flat(red_z), Uniform(kRed));
    Append(high, Sheet(-0.125, 1.125, -0.125, 1.125, 4, Flat(blue_z), Uniform(kBlue)));
    auto result = BakeFromMesh(LowGrid(1), high, Options(size), {});
    EXPECT_TRUE(result.ok()) << result.status().message();
    int red = 0, blue = 0;
    for (int y = 0; y < size; ++y) {
      for (int x = 0; x < size; ++x) {
        const auto c = ColorAt(*result, x, y);
        red += c == kRed;
        blue += c == kBlue;
      }
    }
    return std::array<int, 2>{red, blue};
  };
  EXPECT_EQ(bake(2 * kAbove, -kAbove), (std::array<int, 2>{0, size * size}));
  EXPECT_EQ(bake(kAbove, -2 * kAbove), (std::array<int, 2>{size * size, 0}));
  EXPECT_EQ(bake(-2 * kAbove, kAbove), (std::array<int, 2>{0, size * size}));
  // Red above and blue below at the same distance: forward wins.
  EXPECT_EQ(bake(kAbove, -kAbove), (std::array<int, 2>{size * size, 0}));
}

TEST(BakeFromMeshTest, TiltedSheetGivesItsNormalInTangentSpace) {
  const double angle = 20.0 * M_PI / 180.0;
  // z = tan(angle) (x - 0.5) + 5 mm: normal (-sin, 0, cos), computed from
  // the geometry (the sheet has no normals).
  Mesh high = Sheet(-0.25, 1.25, -0.25, 1.25, 30,
                    [&](double x, double) { return std::tan(angle) * (x - 0.5) + 0.005; },
                    Uniform({50, 60, 70}));
  FromMeshOptions from_mesh;
  from_mesh.cage_m = 0.5;
  const int size = 32;
  FromMeshReport report;
  auto result = BakeFromMesh(LowGrid(3), high, Options(size), from_mesh, &report);
  ASSERT_TRUE(result.ok()) << result.status().message();
  EXPECT_EQ(report.texels_hit, size_t(size * size));
  const std::array<double, 3> expected = {-std::sin(angle), 0.0, std::cos(angle)};
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const auto n = NormalAt(*result, x, y);
      for (int k = 0; k < 3; ++k) ASSERT_NEAR(n[k], expected[k], 1.0 / 127) << x << "," << y;
      ASSERT_EQ(ColorAt(*result, x, y), (std::array<uint8_t, 3>{50, 60, 70}));
    }
  }
  // The red channel is not the flat 128: the tilt is really there.
  EXPECT_LT(result->maps.normal.at_u8(5, 5, 0), 100);

  BakeOptions float_options = Options(size);
  float_options.float_normals = true;
  auto exact = BakeFromMesh(LowGrid(3), high, float_options, from_mesh);
  ASSERT_TRUE(exact.ok()) << exact.status().message();
  ASSERT_EQ(exact->maps.normal.type, Image::PixelType::kF32);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(exact->maps.normal.at_f32(7, 20, k), expected[k], 1e-4);
}

TEST(BakeFromMeshTest, VertexNormalsOfTheSourceAreUsed) {
  // A flat sheet whose vertex normals say it leans towards +y by 30 degrees
  // (a normal-mapped detail the geometry does not show).
  const double angle = 30.0 * M_PI / 180.0;
  Mesh high = Sheet(-0.25, 1.25, -0.25, 1.25, 6, Flat(kAbove), Uniform({9, 9, 9}));
  for (size_t v = 0; v < high.vertex_count(); ++v) {
    high.normals.insert(high.normals.end(),
                        {0.0f, float(std::sin(angle)), float(std::cos(angle))});
  }
  auto result = BakeFromMesh(LowGrid(1), high, Options(16), {});
  ASSERT_TRUE(result.ok()) << result.status().message();
  const auto n = NormalAt(*result, 9, 4);
  EXPECT_NEAR(n[0], 0.0, 1.0 / 127);
  EXPECT_NEAR(n[1], std::sin(angle), 1.0 / 127);
  EXPECT_NEAR(n[2], std::cos(angle), 1.0 / 127);
}

TEST(BakeFromMeshTest, BeyondTheCageEveryTexelFallsBackToTheLowColors) {
  const int size = 64;
  // Low colors (200 x, 200 y, 0): linear on both triangles.
  Mesh low = LowGrid(1);
  low.colors = {0, 0, 0, 200, 0, 0, 0, 200, 0, 200, 200, 0};
  FromMeshReport report;
  auto result = BakeFromMesh(low, RedBlue(0.1), Options(size), {}, &report);
  ASSERT_TRUE(result.ok()) << result.status().message();
  EXPECT_EQ(report.texels_hit, 0u);
  EXPECT_EQ(report.texels_fallback, result->covered_texels);
  EXPECT_EQ(report.texels_fallback, size_t(size * size));
  EXPECT_EQ(report.mean_hit_distance_m, 0.0);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double u = (x + 0.5) / size, v = 1.0 - (y + 0.5) / size;
      const auto c = ColorAt(*result, x, y);
      ASSERT_NEAR(c[0], 200 * u, 1.0) << x << "," << y;
      ASSERT_NEAR(c[1], 200 * v, 1.0) << x << "," << y;
      ASSERT_EQ(c[2], 0);
      ASSERT_EQ(result->maps.normal.at_u8(x, y, 2), 255);
    }
  }
  // A larger cage reaches the sheet.
  FromMeshOptions wide;
  wide.cage_m = 0.2;
  ASSERT_TRUE(BakeFromMesh(low, RedBlue(0.1), Options(size), wide, &report).ok());
  EXPECT_EQ(report.texels_hit, size_t(size * size));

  // Without low colors the fallback is black.
  auto black = BakeFromMesh(LowGrid(1), RedBlue(0.1), Options(16), {});
  ASSERT_TRUE(black.ok()) << black.status().message();
  EXPECT_EQ(ColorAt(*black, 3, 3), (std::array<uint8_t, 3>{0, 0, 0}));
  EXPECT_EQ(ColorAt(*black, 12, 9), (std::array<uint8_t, 3>{0, 0, 0}));
}

TEST(BakeFromMeshTest, OriginsAreHonoured) {
  const int size = 64;
  Mesh low = LowGrid(2);
  low.origin = {1000.0, 2000.0, 5.0};
  Mesh same = RedBlue(kAbove);
  same.origin = low.origin;
  // The same surface stored 100 m east, 50 m south and 3 m up of another
  // origin (dyadic coordinates: the shifted floats are exact).
  Mesh shifted = same;
  const double shift[3] = {100.0, -50.0, 3.0};
  for (size_t i = 0; i < shifted.positions.size(); ++i) {
    shifted.positions[i] = float(double(shifted.positions[i]) - shift[i % 3]);
  }
  for (int k = 0; k < 3; ++k) shifted.origin[k] += shift[k];
  FromMeshReport a_report, b_report;
  auto a = BakeFromMesh(low, same, Options(size), {}, &a_report);
  auto b = BakeFromMesh(low, shifted, Options(size), {}, &b_report);
  ASSERT_TRUE(a.ok()) << a.status().message();
  ASSERT_TRUE(b.ok()) << b.status().message();
  EXPECT_EQ(a_report.texels_hit, size_t(size * size));
  EXPECT_EQ(b_report.texels_hit, size_t(size * size));
  EXPECT_EQ(a->maps.color.data, b->maps.color.data);
  EXPECT_EQ(a->maps.normal.data, b->maps.normal.data);
  EXPECT_EQ(b->mesh.origin, low.origin);
  // Ignoring the origin would put the shifted sheet 3 m away: all fallback.
  Mesh ignored = shifted;
  ignored.origin = low.origin;
  FromMeshReport ignored_report;
  ASSERT_TRUE(BakeFromMesh(low, ignored, Options(size), {}, &ignored_report).ok());
  EXPECT_EQ(ignored_report.texels_hit, 0u);
}

TEST(BakeFromMeshTest, SameBytesWithOneOrTwoThreads) {
  // A wavy sheet with a color gradient over a low grid of 200 faces.
  Mesh high = Sheet(
      -0.2, 1.2, -0.2, 1.2, 150,
      [](double x, double y) { return 0.02 * std::sin(17 * x) * std::cos(13 * y); },
      [](double x, double y) {
        return std::array<uint8_t, 3>{uint8_t(std::clamp(x, 0.0, 1.0) * 255),
                                      uint8_t(std::clamp(y, 0.0, 1.0) * 255), 99};
      });
  Mesh low = LowGrid(10);
  // Squeeze the atlas into [0.1, 0.9]^2 so that there is a gutter.
  for (float& uv : low.uvs) uv = 0.1f + 0.8f * uv;
  BakeOptions one = Options(256), two = Options(256);
  two.threads = 2;
  FromMeshReport one_report, two_report;
  auto a = BakeFromMesh(low, high, one, {}, &one_report);
  auto b = BakeFromMesh(low, high, two, {}, &two_report);
  ASSERT_TRUE(a.ok()) << a.status().message();
  ASSERT_TRUE(b.ok()) << b.status().message();
  EXPECT_GT(one_report.texels_hit, 0.99 * double(a->covered_texels));
  EXPECT_GT(a->gutter_texels, 0u);
  EXPECT_EQ(a->maps.color.data, b->maps.color.data);
  EXPECT_EQ(a->maps.normal.data, b->maps.normal.data);
  EXPECT_EQ(one_report.texels_hit, two_report.texels_hit);
  EXPECT_EQ(one_report.mean_hit_distance_m, two_report.mean_hit_distance_m);
  EXPECT_EQ(a->gutter_texels, b->gutter_texels);
}

TEST(BakeFromMeshTest, ClearErrors) {
  Mesh uncolored = RedBlue(kAbove);
  uncolored.colors.clear();
  auto no_colors = BakeFromMesh(LowGrid(1), uncolored, Options(16), {});
  ASSERT_FALSE(no_colors.ok());
  EXPECT_EQ(no_colors.status().code(), Status::Code::kInvalid);
  EXPECT_THAT(no_colors.status().message(), HasSubstr("source mesh has no vertex colors"));

  Mesh no_uvs = LowGrid(1);
  no_uvs.uvs.clear();
  auto uvs = BakeFromMesh(no_uvs, RedBlue(kAbove), Options(16), {});
  ASSERT_FALSE(uvs.ok());
  EXPECT_EQ(uvs.status().code(), Status::Code::kInvalid);
  EXPECT_THAT(uvs.status().message(), HasSubstr("uvs"));

  FromMeshOptions zero;
  zero.cage_m = 0;
  auto cage = BakeFromMesh(LowGrid(1), RedBlue(kAbove), Options(16), zero);
  ASSERT_FALSE(cage.ok());
  EXPECT_THAT(cage.status().message(), HasSubstr("cage"));

  Mesh broken = RedBlue(kAbove);
  broken.indices[7] = 100000;
  auto bad_index = BakeFromMesh(LowGrid(1), broken, Options(16), {});
  ASSERT_FALSE(bad_index.ok());
  EXPECT_EQ(bad_index.status().code(), Status::Code::kInvalid);
  EXPECT_THAT(bad_index.status().message(), HasSubstr("source mesh"));

  Mesh empty = RedBlue(kAbove);
  empty.indices.clear();
  auto no_faces = BakeFromMesh(LowGrid(1), empty, Options(16), {});
  ASSERT_FALSE(no_faces.ok());
  EXPECT_THAT(no_faces.status().message(), HasSubstr("no faces"));
}

}  // namespace
}  // namespace pb
