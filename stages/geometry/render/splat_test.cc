// The splat renderer: a plane of points seen head-on covers the pixels of its
// extent with its color, a nearer surface hides a farther one, splats of one
// surface blend, the bytes do not depend on the thread count, and it agrees
// with the mesh renderer about where a surface is on screen.
#include "stages/geometry/render/splat.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <vector>

#include "stages/geometry/render/render.h"

namespace pb {
namespace {

// Points on a square grid of step `step` covering [-h, h]^2 in the plane
// y = y0 (x right, z up as seen from an eye on -y), one color.
void AddPlane(PointCloud& cloud, double h, double step, float y0, std::array<uint8_t, 3> color) {
  const int count = int(std::lround(2 * h / step));
  for (int j = 0; j <= count; ++j)
    for (int i = 0; i <= count; ++i) {
      cloud.positions.insert(cloud.positions.end(), {float(-h + i * step), y0, float(-h + j * step)});
      cloud.colors.insert(cloud.colors.end(), color.begin(), color.end());
    }
}

RenderCamera HeadOn(int size, std::array<double, 3> origin = {0, 0, 0}) {
  RenderCamera camera;
  camera.eye = {origin[0], origin[1] - 5, origin[2]};
  camera.target = {origin[0], origin[1] + 5, origin[2]};
  camera.fov_deg = 60;
  camera.size = size;
  return camera;
}

// Where the ray through the center of pixel (x, y) of HeadOn(size) meets the
// plane y = y0: (x, z) in meters.
std::array<double, 2> PlaneHit(int size, int x, int y, double y0) {
  const double focal = size / 2.0 / std::tan(M_PI / 6);
  const double distance = y0 + 5;
  return {(x + 0.5 - size / 2.0) / focal * distance, (size / 2.0 - (y + 0.5)) / focal * distance};
}

TEST(SplatTest, PlaneHeadOnCoversItsExtentWithItsColor) {
  PointCloud cloud;
  cloud.origin = {300000.0, 5000000.0, 100.0};  // georeferenced: the camera moves into local coordinates
  const double h = 1.0, step = 0.05;
  AddPlane(cloud, h, step, 0.0f, {200, 30, 90});
  const std::vector<float> radius(cloud.size(), float(step));
  SplatOptions options;
  options.supersample = 1;
  SplatStats stats;
  const int size = 64;
  Expected<Image> image = RenderSplats(cloud, {radius}, HeadOn(size, cloud.origin), options, &stats);
  ASSERT_TRUE(image.ok()) << image.status().message();
  EXPECT_EQ(stats.points, cloud.size());
  EXPECT_EQ(stats.drawn, cloud.size());
  int inside = 0, outside = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const auto [px, pz] = PlaneHit(size, x, y, 0.0);
      const uint8_t* p = &image->at_u8(x, y, 0);
      if (std::abs(px) <= h && std::abs(pz) <= h) {
        ++inside;
        EXPECT_EQ(p[3], 255) << x << "," << y;
        EXPECT_EQ(p[0], 200) << x << "," << y;
        EXPECT_EQ(p[1], 30) << x << "," << y;
        EXPECT_EQ(p[2], 90) << x << "," << y;
      } else if (std::abs(px) > h + step || std::abs(pz) > h + step) {
        ++outside;
        EXPECT_EQ(p[3], 0) << x << "," << y;
        EXPECT_EQ(p[0], 0) << x << "," << y;
      }
    }
  // The plane spans 2 m of the 5.77 m the frame sees at 5 m: ~22 of 64 px.
  EXPECT_GT(inside, 20 * 20);
  EXPECT_GT(outside, 64 * 64 - 25 * 25);
  int covered_pixels = 0;  // one sample per pixel: covered samples = covered pixels
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) covered_pixels += image->at_u8(x, y, 3) == 255;
  EXPECT_EQ(stats.covered_samples, size_t(covered_pixels));
}

TEST(SplatTest, NearerSurfaceWins) {
  PointCloud cloud;
  AddPlane(cloud, 1.0, 0.05, 1.0f, {220, 0, 0});    // far, red, 2 x 2 m
  AddPlane(cloud, 0.3, 0.02, -1.0f, {0, 200, 0});   // near, green, smaller; drawn after
  std::vector<float> radius(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) radius[i] = cloud.positions[i * 3 + 1] > 0 ? 0.05f : 0.02f;
  SplatOptions options;
  options.supersample = 2;
  const int size = 64;
  Expected<Image> image = RenderSplats(cloud, {radius}, HeadOn(size), options);
  ASSERT_TRUE(image.ok()) << image.status().message();
  // The center sees the near plane only: pure green despite the red behind.
  const uint8_t* center = &image->at_u8(size / 2, size / 2, 0);
  EXPECT_EQ(center[0], 0);
  EXPECT_EQ(center[1], 200);
  // Beside the near plane (0.3 m at 4 m is ~4.5 px from the center, the far
  // plane reaches ~9 px), the far plane shows.
  const uint8_t* side = &image->at_u8(size / 2 + 6, size / 2, 0);
  EXPECT_EQ(side[0], 220);
  EXPECT_EQ(side[1], 0);
  EXPECT_EQ(side[3], 255);

  // The same cloud in the other order: the same picture (no draw order).
  PointCloud reversed;
  std::vector<float> reversed_radius;
  for (size_t i = cloud.size(); i-- > 0;) {
    reversed.positions.insert(reversed.positions.end(), &cloud.positions[i * 3], &cloud.positions[i * 3] + 3);
    reversed.colors.insert(reversed.colors.end(), &cloud.colors[i * 3], &cloud.colors[i * 3] + 3);
    reversed_radius.push_back(radius[i]);
  }
  Expected<Image> again = RenderSplats(reversed, {reversed_radius}, HeadOn(size), options);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->at_u8(size / 2, size / 2, 1), 200);
  EXPECT_EQ(again->at_u8(size / 2 + 6, size / 2, 0), 220);
}

TEST(SplatTest, SplatsOfOneSurfaceBlendWithinTheDepthTolerance) {
  // Two interleaved grids 1 mm apart in depth, red and blue: within the
  // tolerance they blend to purple; with no tolerance the nearer one wins.
  PointCloud cloud;
  AddPlane(cloud, 0.5, 0.04, 0.0f, {255, 0, 0});
  AddPlane(cloud, 0.5, 0.04, 0.001f, {0, 0, 255});
  const std::vector<float> radius(cloud.size(), 0.05f);
  SplatOptions options;
  options.supersample = 1;
  const int size = 32;
  Expected<Image> blended = RenderSplats(cloud, {radius}, HeadOn(size), options);
  ASSERT_TRUE(blended.ok());
  const uint8_t* p = &blended->at_u8(size / 2, size / 2, 0);
  EXPECT_GT(p[0], 100);
  EXPECT_GT(p[2], 100);
  options.depth_tolerance = 0;
  Expected<Image> front = RenderSplats(cloud, {radius}, HeadOn(size), options);
  ASSERT_TRUE(front.ok());
  EXPECT_EQ(front->at_u8(size / 2, size / 2, 0), 255);
  EXPECT_EQ(front->at_u8(size / 2, size / 2, 2), 0);
}

TEST(SplatTest, SameBytesForAnyThreadCount) {
  PointCloud cloud;
  uint32_t state = 12345;
  auto next = [&] {
    state = state * 1664525u + 1013904223u;
    return (state >> 8) / double(1 << 24);
  };
  for (int i = 0; i < 30000; ++i) {
    cloud.positions.insert(cloud.positions.end(),
                           {float(next() * 4 - 2), float(next() * 3), float(next() * 4 - 2)});
    for (int c = 0; c < 3; ++c) cloud.colors.push_back(uint8_t(next() * 255));
  }
  std::vector<float> radius(cloud.size());
  for (float& r : radius) r = float(0.01 + 0.05 * next());
  SplatOptions options;
  RenderCamera camera = HeadOn(200);
  camera.eye = {0.3, -4, 0.5};
  std::vector<Image> images;
  for (int threads : {1, 2, 4}) {
    tbb::task_arena arena(threads);
    Expected<Image> image = Status::Internal("not run");
    arena.execute([&] { image = RenderSplats(cloud, {radius}, camera, options); });
    ASSERT_TRUE(image.ok());
    images.push_back(std::move(*image));
  }
  EXPECT_EQ(images[0].data, images[1].data);
  EXPECT_EQ(images[0].data, images[2].data);
}

TEST(SplatTest, CoversWhatTheMeshRendererCovers) {
  // A dense grid and the quad it samples: the same pixels, but for the rim of
  // half a splat radius.
  PointCloud cloud;
  AddPlane(cloud, 1.0, 0.01, 0.0f, {128, 128, 128});
  const std::vector<float> radius(cloud.size(), 0.01f);
  Mesh quad;
  quad.positions = {-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1};
  quad.indices = {0, 1, 2, 0, 2, 3};
  const int size = 96;
  SplatOptions splat_options;
  RenderOptions mesh_options;
  mesh_options.lighting = RenderLighting::kUnlit;
  Expected<Image> splats = RenderSplats(cloud, {radius}, HeadOn(size), splat_options);
  Expected<Image> mesh = RenderMesh(quad, {}, HeadOn(size), mesh_options);
  ASSERT_TRUE(splats.ok() && mesh.ok());
  int differ = 0, covered = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      covered += mesh->at_u8(x, y, 3) == 255;
      differ += (mesh->at_u8(x, y, 3) == 255) != (splats->at_u8(x, y, 3) == 255);
    }
  EXPECT_GT(covered, 30 * 30);
  EXPECT_LE(differ, 4 * 34);  // at most the one-pixel ring around the quad
}

// A grid of step `step` over [-h, h]^2 tilted by `tilt` radians about the x
// axis (toward the eye at -y): z' = z cos, y' = -z sin; and the quad it samples.
void AddTiltedPlane(PointCloud& cloud, std::vector<float>& normals, double h, double step, double tilt) {
  const int count = int(std::lround(2 * h / step));
  for (int j = 0; j <= count; ++j)
    for (int i = 0; i <= count; ++i) {
      const double z = -h + j * step;
      cloud.positions.insert(cloud.positions.end(),
                             {float(-h + i * step), float(-z * std::sin(tilt)), float(z * std::cos(tilt))});
      normals.insert(normals.end(), {0.0f, float(std::cos(tilt)), float(std::sin(tilt))});
    }
}

Mesh TiltedQuad(double h, double tilt) {
  Mesh quad;
  const float s = float(h * std::sin(tilt)), c = float(h * std::cos(tilt)), x = float(h);
  quad.positions = {-x, s, -c, x, s, -c, x, -s, c, -x, -s, c};
  quad.indices = {0, 1, 2, 0, 2, 3};
  return quad;
}

// Pixels covered by exactly one of the two frames.
int CoverageDifference(const Image& a, const Image& b) {
  int differ = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) differ += (a.at_u8(x, y, 3) == 255) != (b.at_u8(x, y, 3) == 255);
  return differ;
}

TEST(SplatTest, TangentDisksFollowAnObliqueSurfaceCameraFacingOnesOverhangIt) {
  // A plane seen at 75 degrees from head-on: its top and bottom edges are
  // where a camera-facing disk stands out by its whole radius, a tangent disk
  // by its radius foreshortened (x cos 75 = 0.26).
  PointCloud cloud;
  std::vector<float> normals;
  const double tilt = 75 * M_PI / 180, step = 0.02;
  AddTiltedPlane(cloud, normals, 1.0, step, tilt);
  const std::vector<float> radius(cloud.size(), float(2.5 * step));
  const int size = 128;
  RenderOptions mesh_options;
  mesh_options.lighting = RenderLighting::kUnlit;
  Expected<Image> mesh = RenderMesh(TiltedQuad(1.0, tilt), {}, HeadOn(size), mesh_options);
  Expected<Image> facing = RenderSplats(cloud, {radius}, HeadOn(size), {});
  Expected<Image> tangent = RenderSplats(cloud, {radius, normals}, HeadOn(size), {});
  ASSERT_TRUE(mesh.ok() && facing.ok() && tangent.ok()) << tangent.status().message();
  const int facing_differ = CoverageDifference(*mesh, *facing);
  const int tangent_differ = CoverageDifference(*mesh, *tangent);
  EXPECT_LT(tangent_differ, facing_differ / 2) << tangent_differ << " vs " << facing_differ;
  // What is left: the sides (left, right), where both stand out by a radius
  // (1.1 px x 11.5 px each), and the edges' anti-aliased rim.
  EXPECT_LT(tangent_differ, 100);
}

TEST(SplatTest, ClipLinesCutTheDisksAtTheBorder) {
  // The right-hand column's disks are clipped at their centers: the covered
  // area ends at x = h, where the quad ends, instead of a radius beyond.
  PointCloud cloud;
  std::vector<float> normals;
  const double h = 1.0, step = 0.02;
  AddTiltedPlane(cloud, normals, h, step, 0.0);
  const std::vector<float> radius(cloud.size(), float(3 * step));
  std::vector<float> clip(cloud.size() * 4, 0.0f);
  for (size_t p = 0; p < cloud.size(); ++p)
    if (cloud.positions[p * 3] > float(h - 3.5 * step)) {
      clip[p * 4] = 1.0f;  // outward +x, cut at x = h
      clip[p * 4 + 3] = float(h) - cloud.positions[p * 3];
    }
  const int size = 96;
  Expected<Image> whole = RenderSplats(cloud, {radius, normals}, HeadOn(size), {});
  Expected<Image> clipped = RenderSplats(cloud, {radius, normals, clip}, HeadOn(size), {});
  ASSERT_TRUE(whole.ok() && clipped.ok()) << clipped.status().message();
  const auto last_covered_column = [&](const Image& image) {
    int last = -1;
    for (int x = 0; x < size; ++x)
      if (image.at_u8(x, size / 2, 3) == 255) last = x;
    return last;
  };
  // x = h is at pixel 48 + focal * h / 5 = 48 + 83.1 / 5 = 64.6: pixel 64 is
  // the last one it reaches (its samples at 64.25 and 64.75 with 2x2).
  EXPECT_EQ(last_covered_column(*clipped), 64);
  EXPECT_GE(last_covered_column(*whole), 65);  // 3 steps = 0.5 px farther
  // The left side, not clipped, is the same in both.
  for (int x = 0; x < size / 2; ++x) EXPECT_EQ(whole->at_u8(x, size / 2, 3), clipped->at_u8(x, size / 2, 3)) << x;
}

TEST(SplatTest, SampleMaskHoldsTheVisiblePointsOnly) {
  // A dense plane (2 cm) 1 m behind a sparse one (0.2 m grid) drawn with
  // disks that close it: the sparse plane hides the dense one, so the mask
  // holds the sparse plane's points only (one pixel each where the point
  // falls in its pixel's middle half), not the dense plane's hundreds; alone,
  // the dense plane fills its square.
  const int size = 64;
  auto mask_pixels = [&](bool front) {
    PointCloud cloud;
    AddPlane(cloud, 1.0, 0.02, 1.0f, {0, 200, 0});
    const size_t dense = cloud.size();
    if (front) AddPlane(cloud, 1.0, 0.2, 0.0f, {200, 0, 0});
    std::vector<float> radius(cloud.size(), 0.03f);
    for (size_t i = dense; i < cloud.size(); ++i) radius[i] = 0.2f;
    Image samples;
    SplatStats stats;
    Expected<Image> image = RenderSplats(cloud, {radius}, HeadOn(size), SplatOptions{}, &stats, nullptr, &samples);
    EXPECT_TRUE(image.ok()) << image.status().message();
    EXPECT_EQ(samples.channels, 1);
    EXPECT_EQ(samples.width, size);
    size_t count = 0;
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) count += samples.at_u8(x, y, 0) == 255;
    EXPECT_EQ(count, stats.sample_pixels);
    return count;
  };
  const size_t alone = mask_pixels(false), hidden = mask_pixels(true);
  // The dense square spans 2 / 6 x 55.4 = 18.5 px per side at 6 m.
  EXPECT_GT(alone, 300u);
  EXPECT_LE(hidden, 11u * 11u);  // at most one pixel per sparse point
  EXPECT_GT(hidden, 10u);
}

TEST(SplatTest, SampleMaskTakesTheGivenSamplePositions) {
  // The same plane with every sample position moved one output pixel to the
  // right (5 m away): the mask moves with them, the splats' image does not.
  const int size = 64;
  PointCloud cloud;
  AddPlane(cloud, 1.0, 0.1, 0.0f, {200, 0, 0});
  const std::vector<float> radius(cloud.size(), 0.1f);
  const double pixel_m = 5.0 / (size / 2.0 / std::tan(M_PI / 6));
  std::vector<float> moved = cloud.positions;
  for (size_t i = 0; i < cloud.size(); ++i) moved[i * 3] = float(moved[i * 3] + pixel_m);
  Image raw_mask, moved_mask;
  Expected<Image> raw = RenderSplats(cloud, {radius}, HeadOn(size), SplatOptions{}, nullptr, nullptr, &raw_mask);
  SplatShapes shapes{radius};
  shapes.sample_at = moved;
  Expected<Image> shifted = RenderSplats(cloud, shapes, HeadOn(size), SplatOptions{}, nullptr, nullptr, &moved_mask);
  ASSERT_TRUE(raw.ok() && shifted.ok());
  EXPECT_EQ(raw->data, shifted->data);
  size_t count = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x + 1 < size; ++x) {
      EXPECT_EQ(moved_mask.at_u8(x + 1, y, 0), raw_mask.at_u8(x, y, 0)) << x << " " << y;
      count += raw_mask.at_u8(x, y, 0) == 255;
    }
  EXPECT_GT(count, 40u);  // of 441 points, those in their pixel's middle half
  shapes.sample_at = std::span<const float>(moved).first(6);
  EXPECT_FALSE(RenderSplats(cloud, shapes, HeadOn(size), SplatOptions{}, nullptr, nullptr, &moved_mask).ok());
}

TEST(SplatTest, RejectsBadInput) {
  PointCloud cloud;
  AddPlane(cloud, 0.1, 0.05, 0.0f, {1, 2, 3});
  const std::vector<float> radius(cloud.size(), 0.05f);
  EXPECT_FALSE(RenderSplats(cloud, {std::span<const float>(radius).first(2)}, HeadOn(16), {}).ok());
  RenderCamera same = HeadOn(16);
  same.target = same.eye;
  EXPECT_FALSE(RenderSplats(cloud, {radius}, same, {}).ok());
  SplatOptions options;
  options.depth_tolerance = -1;
  EXPECT_FALSE(RenderSplats(cloud, {radius}, HeadOn(16), options).ok());
  // Points behind the eye are skipped, not an error: an empty frame.
  RenderCamera away = HeadOn(16);
  away.target = {0, -10, 0};
  const std::vector<float> normals(cloud.size() * 3, 1.0f), clip(cloud.size() * 4, 0.0f);
  EXPECT_FALSE(RenderSplats(cloud, {radius, std::span<const float>(normals).first(3)}, HeadOn(16), {}).ok());
  EXPECT_FALSE(RenderSplats(cloud, {radius, {}, clip}, HeadOn(16), {}).ok());  // clip lines need normals
  EXPECT_TRUE(RenderSplats(cloud, {radius, normals, clip}, HeadOn(16), {}).ok());
  Expected<Image> empty = RenderSplats(cloud, {radius}, away, {});
  ASSERT_TRUE(empty.ok());
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) EXPECT_EQ(empty->at_u8(x, y, 3), 0);
}

}  // namespace
}  // namespace pb
