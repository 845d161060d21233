// The reference renderer: determinism, texture reproduction, normal maps,
// z-buffer, near clipping, and ground truth against the rasterized truth mesh.
#include "stages/geometry/render/render.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

#include "stages/geometry/core/tangents.h"

namespace pb {
namespace {

// A square of half-size h in the plane y = y0, facing -y (toward an eye on
// -y), u along +x, v along +z, one color.
Mesh Quad(double h, float y0, std::array<uint8_t, 3> color, std::array<double, 3> origin = {0, 0, 0}) {
  Mesh mesh;
  mesh.origin = origin;
  const float s = float(h);
  mesh.positions = {-s, y0, -s, s, y0, -s, s, y0, s, -s, y0, s};
  mesh.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  for (int i = 0; i < 4; ++i) mesh.colors.insert(mesh.colors.end(), color.begin(), color.end());
  mesh.indices = {0, 1, 2, 0, 2, 3};
  return mesh;
}

// Appends `b` to `a` (indices shifted); both at the same origin.
void Append(Mesh& a, const Mesh& b) {
  const uint32_t base = uint32_t(a.vertex_count());
  a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
  a.uvs.insert(a.uvs.end(), b.uvs.begin(), b.uvs.end());
  a.colors.insert(a.colors.end(), b.colors.begin(), b.colors.end());
  for (uint32_t i : b.indices) a.indices.push_back(base + i);
}

// Eye on -y at distance d from the origin, looking at it, so that a quad of
// half-size d * tan(fov / 2) fills the frame exactly.
RenderCamera HeadOn(double d, int size, std::array<double, 3> origin = {0, 0, 0}) {
  RenderCamera camera;
  camera.eye = {origin[0], origin[1] - d, origin[2]};
  camera.target = origin;
  camera.fov_deg = 60;
  camera.size = size;
  return camera;
}

Image NoiseTexture(int size, uint32_t seed) {
  Image image = Image::Make(size, size, 3, Image::PixelType::kU8);
  for (auto& byte : image.data) {
    seed = seed * 1664525u + 1013904223u;
    byte = uint8_t(seed >> 24);
  }
  return image;
}

Image ConstantNormalMap(int size, std::array<uint8_t, 3> value) {
  Image image = Image::Make(size, size, 3, Image::PixelType::kU8);
  for (size_t i = 0; i < image.data.size(); ++i) image.data[i] = value[i % 3];
  return image;
}

// A bent sheet (a quarter cylinder of radius 1 around the z axis, facing the
// axis) with uvs, normals and tangents: frames vary over the surface.
Mesh BentSheet() {
  Mesh mesh;
  mesh.origin = {500000.0, 4000000.0, 200.0};  // georeferenced-size origin
  const int n = 24;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const double a = std::numbers::pi * (0.25 + 0.5 * i / n);
      mesh.positions.insert(mesh.positions.end(), {float(std::cos(a)), float(std::sin(a)), float(-0.5 + double(j) / n)});
      mesh.uvs.insert(mesh.uvs.end(), {float(i) / n, float(j) / n});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      mesh.indices.insert(mesh.indices.end(), {a, d, c, a, c, b});  // facing the axis
    }
  }
  mesh.normals = ComputeVertexNormals(mesh);
  mesh.tangents = ComputeTangents(mesh).value();
  return mesh;
}

RenderCamera SheetCamera(const Mesh& mesh, int size) {
  RenderCamera camera;
  camera.eye = {mesh.origin[0], mesh.origin[1] - 0.2, mesh.origin[2] + 0.1};
  camera.target = {mesh.origin[0], mesh.origin[1] + 1.0, mesh.origin[2]};
  camera.size = size;
  return camera;
}

TEST(RenderTest, SrgbRoundTripsEveryByte) {
  for (int i = 0; i < 256; ++i) EXPECT_EQ(LinearToSrgbByte(SrgbByteToLinear(uint8_t(i))), i);
  EXPECT_EQ(LinearToSrgbByte(-1.0), 0);
  EXPECT_EQ(LinearToSrgbByte(2.0), 255);
}

TEST(RenderTest, SameBytesForOneAndTwoThreads) {
  const SynthScene scene = MakeSynthScene("room", 3, Vec3{3.0, 2.5, 2.0}).value();
  const Mesh truth = SynthTruthMesh(scene, 0.03);
  const Mesh sheet = BentSheet();
  const MipTexture color = BuildColorTexture(NoiseTexture(64, 5)).value();
  const MipTexture normal = BuildNormalTexture(NoiseTexture(64, 9)).value();
  RenderCamera camera;
  camera.eye = {-1.0, -0.8, 1.2};
  camera.target = {1.5, 0.5, 0.8};
  camera.size = 96;
  RenderOptions options;
  auto render_all = [&](int threads) {
    std::vector<Image> images;
    tbb::task_arena arena(threads);
    arena.execute([&] {
      images.push_back(RenderMesh(truth, {}, camera, options).value());
      images.push_back(RenderSynthScene(scene, camera, options).value());
      images.push_back(RenderMesh(sheet, {&color, &normal}, SheetCamera(sheet, 96), options).value());
    });
    return images;
  };
  const std::vector<Image> one = render_all(1), two = render_all(2);
  for (size_t i = 0; i < one.size(); ++i) {
    EXPECT_EQ(one[i].data, two[i].data) << "image " << i;
    size_t covered = 0;
    for (int y = 0; y < 96; ++y)
      for (int x = 0; x < 96; ++x) covered += one[i].at_u8(x, y, 3) == 255;
    EXPECT_GT(covered, 96u * 96u / 2) << "image " << i;  // the views do show geometry
  }
}

// The open scenes (synth/objects.h): the analytic truth frame and a render
// of the truth mesh agree (same coverage, colors within the aliasing of
// 2 cm brick and tessera patterns on a 1 cm mesh).
TEST(RenderTest, OpenSceneTruthFramesMatchTheirTruthMesh) {
  struct View {
    const char* preset;
    std::array<double, 3> eye, target;
  };
  for (const View& view : {View{"facade", {3.8, -1.2, 2.4}, {-1.2, 1.4, 0.6}},
                           View{"sculpture", {0.9, -1.1, 1.9}, {0.0, 0.0, 1.45}}}) {
    SCOPED_TRACE(view.preset);
    const SynthScene scene = MakeSynthScene(view.preset, 1).value();
    const Mesh truth = SynthTruthMesh(scene, 0.01);
    RenderCamera camera;
    camera.eye = view.eye, camera.target = view.target, camera.fov_deg = 60, camera.size = 96;
    RenderOptions options;
    const Image analytic = RenderSynthScene(scene, camera, options).value();
    const Image mesh = RenderMesh(truth, {}, camera, options).value();
    size_t covered_analytic = 0, covered_mesh = 0, both = 0;
    double difference = 0;
    for (int y = 0; y < 96; ++y) {
      for (int x = 0; x < 96; ++x) {
        const bool a = analytic.at_u8(x, y, 3) == 255, m = mesh.at_u8(x, y, 3) == 255;
        covered_analytic += a, covered_mesh += m;
        if (!a || !m) continue;
        ++both;
        for (int c = 0; c < 3; ++c) difference += std::abs(analytic.at_u8(x, y, c) - mesh.at_u8(x, y, c));
      }
    }
    EXPECT_GT(covered_analytic, 96u * 96u / 2);
    EXPECT_NEAR(static_cast<double>(covered_mesh), static_cast<double>(covered_analytic), 0.01 * 96 * 96);
    EXPECT_LT(difference / (3 * both), 8.0);  // measured 4.2 (facade), 2.4 (sculpture)
  }
}

// One sample per pixel, texture texels = pixels: every pixel centre maps onto
// a texel centre, bilinear weights are 0/1 and the LOD is 0, so the texture
// comes back. The tolerance of 1 level covers float rounding of the
// projection (a texel-centre position off by ~1e-6 texel blends in that much
// of a neighbour, and a LOD of ~1e-7 that much of level 1): it can only move
// a value that sits on an sRGB rounding threshold. We also require almost
// all bytes to be exact.
TEST(RenderTest, TexturedQuadHeadOnReproducesItsTexture) {
  const int size = 64;
  const double d = 2.0, h = d * std::tan(std::numbers::pi / 6);
  const std::array<double, 3> origin = {1000.0, 2000.0, 30.0};
  const Mesh quad = Quad(h, 0.0f, {0, 0, 0}, origin);
  const Image texture = NoiseTexture(size, 1);
  const MipTexture color = BuildColorTexture(texture).value();
  RenderOptions options;
  options.lighting = RenderLighting::kUnlit;
  options.supersample = 1;
  const Image image = RenderMesh(quad, {&color, nullptr}, HeadOn(d, size, origin), options).value();
  int max_diff = 0;
  size_t exact = 0;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      ASSERT_EQ(image.at_u8(x, y, 3), 255) << x << "," << y;
      for (int c = 0; c < 3; ++c) {
        const int diff = std::abs(int(image.at_u8(x, y, c)) - int(texture.at_u8(x, y, c)));
        max_diff = std::max(max_diff, diff);
        exact += diff == 0;
      }
    }
  }
  EXPECT_LE(max_diff, 1);
  EXPECT_GE(double(exact), 0.99 * size * size * 3);
}

// 8-bit maps keep level 0 as bytes and decode per fetch: the picture must
// be the one of the same map decoded up front (a float image of the decoded
// values), for color and normal maps.
TEST(RenderTest, EightBitMapsRenderAsTheirDecodedFloatImages) {
  const Mesh sheet = BentSheet();
  const Image color8 = NoiseTexture(32, 3), normal8 = NoiseTexture(32, 4);
  Image color32 = Image::Make(32, 32, 3, Image::PixelType::kF32), normal32 = color32;
  for (size_t i = 0; i < color8.data.size(); ++i) {
    color32.f32()[i] = SrgbByteToLinear(color8.data[i]);
    const int c = int(normal8.data[i]) - 128;
    normal32.f32()[i] = c >= 0 ? float(c) / 127.0f : float(c) / 128.0f;
  }
  const MipTexture c8 = BuildColorTexture(color8).value(), n8 = BuildNormalTexture(normal8).value();
  const MipTexture c32 = BuildColorTexture(color32).value(), n32 = BuildNormalTexture(normal32).value();
  EXPECT_FALSE(c8.level0_bytes.empty());
  EXPECT_TRUE(c32.level0_bytes.empty());
  ASSERT_EQ(c8.levels.size(), 6u);  // 32, 16, 8, 4, 2, 1
  EXPECT_EQ(c8.levels[1].rgb, c32.levels[1].rgb);
  EXPECT_EQ(n8.levels[5].rgb, n32.levels[5].rgb);
  const Image a = RenderMesh(sheet, {&c8, &n8}, SheetCamera(sheet, 64), RenderOptions{}).value();
  const Image b = RenderMesh(sheet, {&c32, &n32}, SheetCamera(sheet, 64), RenderOptions{}).value();
  EXPECT_EQ(a.data, b.data);
}

TEST(RenderTest, FlatNormalMapGivesTheSameBytesAsNone) {
  const Mesh sheet = BentSheet();
  const MipTexture color = BuildColorTexture(NoiseTexture(32, 7)).value();
  const MipTexture flat = BuildNormalTexture(ConstantNormalMap(32, {128, 128, 255})).value();
  RenderOptions options;
  const Image without = RenderMesh(sheet, {&color, nullptr}, SheetCamera(sheet, 128), options).value();
  const Image with = RenderMesh(sheet, {&color, &flat}, SheetCamera(sheet, 128), options).value();
  EXPECT_EQ(without.data, with.data);
  // A nearly flat map (one level off in x) must differ somewhere: the
  // comparison above is not vacuous.
  const MipTexture tilted = BuildNormalTexture(ConstantNormalMap(32, {133, 128, 255})).value();
  const Image other = RenderMesh(sheet, {&color, &tilted}, SheetCamera(sheet, 128), options).value();
  EXPECT_NE(without.data, other.data);
}

// White quad head-on with a constant normal map: the rendered byte is the
// Lambert value of the decoded normal. The default light is up and to the
// left of the view axis, so tilting the normal right (+t) darkens and
// tilting it up (+b, image up, toward the light) brightens.
TEST(RenderTest, NormalMapTiltChangesShadingAsExpected) {
  const int size = 32;
  const double d = 2.0, h = d * std::tan(std::numbers::pi / 6);
  Mesh quad = Quad(h, 0.0f, {255, 255, 255});
  quad.normals = ComputeVertexNormals(quad);
  quad.tangents = ComputeTangents(quad).value();
  const MipTexture white = BuildColorTexture(ConstantNormalMap(4, {255, 255, 255})).value();
  RenderOptions options;
  auto center_byte = [&](std::array<uint8_t, 3> n) {
    const MipTexture map = BuildNormalTexture(ConstantNormalMap(4, n)).value();
    return int(RenderMesh(quad, {&white, &map}, HeadOn(d, size), options).value().at_u8(size / 2, size / 2, 0));
  };
  auto expected = [&](double tx, double ty, double tz) {
    // Camera frame: right = +x, up = +z, forward = +y; t = +x, b = +z, n = -y.
    const double length = std::sqrt(tx * tx + ty * ty + tz * tz);
    const std::array<double, 3> normal = {tx / length, -tz / length, ty / length};
    const auto& l = options.light_camera;  // (right, up, forward) = (x, z, y)
    const std::array<double, 3> light = {l[0], l[2], l[1]};
    const double ll = std::sqrt(light[0] * light[0] + light[1] * light[1] + light[2] * light[2]);
    const double dot = (normal[0] * light[0] + normal[1] * light[1] + normal[2] * light[2]) / ll;
    return int(LinearToSrgbByte(options.ambient + options.diffuse * std::max(0.0, dot)));
  };
  auto decode = [](int byte) { return byte >= 128 ? (byte - 128) / 127.0 : (byte - 128) / 128.0; };
  const int flat = center_byte({128, 128, 255});
  // 30 degrees right: (0.5, 0, 0.866) -> bytes (191, 128, 238).
  const int right = center_byte({191, 128, 238});
  // 14 degrees up, toward the light: (0, 0.242, 0.970) -> (159, 128+31, 251).
  const int up = center_byte({128, 159, 251});
  EXPECT_NEAR(flat, expected(0, 0, 1), 1);
  EXPECT_NEAR(right, expected(decode(191), 0, decode(238)), 1);
  EXPECT_NEAR(up, expected(0, decode(159), decode(251)), 1);
  EXPECT_LT(right, flat - 5);
  EXPECT_GT(up, flat);
}

TEST(RenderTest, ZBufferKeepsTheNearerQuadInEitherOrder) {
  const int size = 32;
  const Mesh near_quad = Quad(0.5, -0.5f, {255, 0, 0});
  const Mesh far_quad = Quad(2.0, 0.5f, {0, 0, 255});
  RenderOptions options;
  options.lighting = RenderLighting::kUnlit;
  for (bool near_first : {true, false}) {
    Mesh mesh = near_first ? near_quad : far_quad;
    Append(mesh, near_first ? far_quad : near_quad);
    const Image image = RenderMesh(mesh, {}, HeadOn(2.0, size), options).value();
    EXPECT_EQ(image.at_u8(size / 2, size / 2, 0), 255) << near_first;
    EXPECT_EQ(image.at_u8(size / 2, size / 2, 2), 0) << near_first;
    EXPECT_EQ(image.at_u8(1, 1, 0), 0) << near_first;  // outside the near quad
    EXPECT_EQ(image.at_u8(1, 1, 2), 255) << near_first;
  }
  // Equal depth: the lower triangle index wins.
  Mesh coplanar = Quad(1.0, 0.0f, {0, 255, 0});
  Append(coplanar, Quad(1.0, 0.0f, {255, 0, 255}));
  const Image tie = RenderMesh(coplanar, {}, HeadOn(2.0, size), options).value();
  EXPECT_EQ(tie.at_u8(size / 2, size / 2, 1), 255);
  EXPECT_EQ(tie.at_u8(size / 2, size / 2, 0), 0);
}

TEST(RenderTest, StatsCountTheSamplesThatSeeAFacesBack) {
  const int size = 32;
  RenderOptions options;
  options.supersample = 2;
  // The near quad faces the eye; the far one, behind it and larger, is wound
  // the other way round: its ring around the near quad shows its back.
  const Mesh near_quad = Quad(0.5, -0.5f, {255, 0, 0});
  Mesh far_quad = Quad(2.0, 0.5f, {0, 0, 255});
  for (size_t f = 0; f < far_quad.indices.size(); f += 3) std::swap(far_quad.indices[f + 1], far_quad.indices[f + 2]);
  RenderStats front;
  ASSERT_TRUE(RenderMesh(near_quad, {}, HeadOn(2.0, size), options, &front).ok());
  EXPECT_GT(front.covered_samples, 0u);
  EXPECT_EQ(front.back_samples, 0u);
  RenderStats back;
  ASSERT_TRUE(RenderMesh(far_quad, {}, HeadOn(2.0, size), options, &back).ok());
  EXPECT_EQ(back.covered_samples, size_t(size * size * 4));  // it fills the frame
  EXPECT_EQ(back.back_samples, back.covered_samples);
  Mesh both = near_quad;
  Append(both, far_quad);
  RenderStats ring;
  ASSERT_TRUE(RenderMesh(both, {}, HeadOn(2.0, size), options, &ring).ok());
  EXPECT_EQ(ring.covered_samples, size_t(size * size * 4));
  EXPECT_EQ(ring.back_samples, ring.covered_samples - front.covered_samples);
}

// A 200 m floor seen from 1.5 m up, looking level: its triangles reach
// behind the eye and are clipped; the floor covers the lower half exactly.
TEST(RenderTest, NearPlaneClipsTrianglesBehindTheEye) {
  Mesh floor;
  floor.positions = {-100, -100, 0, 100, -100, 0, 100, 100, 0, -100, 100, 0};
  floor.indices = {0, 1, 2, 0, 2, 3};
  RenderCamera camera;
  camera.eye = {0, 0, 1.5};
  camera.target = {0, 1, 1.5};
  camera.size = 64;
  RenderStats stats;
  const Image image = RenderMesh(floor, {}, camera, RenderOptions{}, &stats).value();
  EXPECT_EQ(stats.clipped, 2u);
  for (int y = 0; y < 64; ++y) {
    // Row 33 and below are well below the horizon (the floor's far edge at
    // 100 m is 0.86 degrees below it, less than a row of 0.94 degrees).
    if (y <= 30) {
      EXPECT_EQ(image.at_u8(10, y, 3), 0) << y;
    }
    if (y >= 33) {
      EXPECT_EQ(image.at_u8(10, y, 3), 255) << y;
    }
  }
  EXPECT_EQ(image.at_u8(32, 63, 3), 255);
}

// The analytic truth and the truth mesh drawn by the rasterizer agree on
// average. Both at 4 x 4 samples per pixel, the mesh at 5 mm cells: what is
// left is the mesh's own error (10 mm mortar joints on 5 mm cells have
// blurred edges and relief, vertex albedo is rounded to sRGB bytes) and
// aliasing of joint edges. Measured on the three views: mean |difference|
// 3.75, 1.86, 2.21 levels per channel (the first looks straight at a brick
// wall whose joints are half a pixel wide), mean signed difference 0.94,
// 1.01, 0.47 (the mesh is lighter: its interpolated joint edges blend dark
// brick with light mortar over a whole 5 mm cell).
TEST(RenderTest, TruthRenderMatchesRasterizedTruthMesh) {
  const SynthScene scene = MakeSynthScene("room", 1, Vec3{3.0, 2.4, 2.0}).value();
  const Mesh mesh = SynthTruthMesh(scene, 0.005);
  RenderOptions options;
  options.supersample = 4;
  const std::array<std::array<double, 3>, 3> targets = {{{1.5, 0.3, 0.9}, {-0.4, 1.2, 0.6}, {0.2, -1.2, 0.2}}};
  for (const auto& target : targets) {
    RenderCamera camera;
    camera.eye = {-0.6, -0.3, 1.1};
    camera.target = target;
    camera.size = 128;
    const Image truth = RenderSynthScene(scene, camera, options).value();
    const Image raster = RenderMesh(mesh, {}, camera, options).value();
    double sum_abs = 0, sum_signed = 0;
    size_t count = 0, alpha_mismatch = 0;
    for (int y = 0; y < 128; ++y) {
      for (int x = 0; x < 128; ++x) {
        alpha_mismatch += truth.at_u8(x, y, 3) != raster.at_u8(x, y, 3);
        for (int c = 0; c < 3; ++c, ++count) {
          const int diff = int(raster.at_u8(x, y, c)) - int(truth.at_u8(x, y, c));
          sum_abs += std::abs(diff);
          sum_signed += diff;
        }
      }
    }
    const double mad = sum_abs / double(count), bias = sum_signed / double(count);
    std::printf("truth vs rasterized truth mesh: mean |diff| %.3f, mean diff %.3f levels\n", mad, bias);
    EXPECT_LT(mad, 4.5);
    EXPECT_GT(mad, 0.5);  // two different renderings, not one picture twice
    EXPECT_LT(std::abs(bias), 1.5);
    EXPECT_LT(alpha_mismatch, 128u * 128u / 100);  // openings agree up to edge pixels
  }
}

// Each bad input fails for its own reason, named in the message.
TEST(RenderTest, BadCameraAndMaterialAreErrors) {
  const Mesh quad = Quad(1.0, 0.0f, {1, 2, 3});
  auto expect_invalid = [](const Expected<Image>& result, const std::string& why) {
    ASSERT_FALSE(result.ok()) << why;
    EXPECT_EQ(result.status().code(), Status::Code::kInvalid) << result.status().message();
    EXPECT_NE(result.status().message().find(why), std::string::npos) << result.status().message();
  };
  RenderCamera camera = HeadOn(2.0, 16);
  camera.target = camera.eye;
  expect_invalid(RenderMesh(quad, {}, camera, RenderOptions{}), "eye and target are the same point");
  camera = HeadOn(2.0, 16);
  camera.up = {0, 1, 0};  // parallel to the view
  expect_invalid(RenderMesh(quad, {}, camera, RenderOptions{}),
                 "up is zero or parallel to the view direction");
  camera = HeadOn(2.0, 16);
  camera.fov_deg = 180;
  expect_invalid(RenderMesh(quad, {}, camera, RenderOptions{}), "fov_deg must be in (0, 180), got 180");
  const MipTexture texture = BuildColorTexture(NoiseTexture(4, 1)).value();
  expect_invalid(RenderMesh(quad, {&texture, &texture}, HeadOn(2.0, 16), RenderOptions{}),
                 "a normal map needs a color map and a mesh with uvs and tangents");
  Mesh broken = quad;
  broken.indices.push_back(99);
  broken.indices.push_back(0);
  broken.indices.push_back(1);
  expect_invalid(RenderMesh(broken, {}, HeadOn(2.0, 16), RenderOptions{}),
                 "face 2 refers to vertex 99 but the mesh has 4 vertices");
}

}  // namespace
}  // namespace pb
