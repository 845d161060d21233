#include "stages/geometry/uv/atlas.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>

#include "stages/geometry/core/image.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/synth/scene.h"
#include "stages/geometry/uv/pack.h"

namespace pb {
namespace {

// An open cylinder around z (outward normals, colors by row), `segments`
// around and `rows` up.
Mesh MakeCylinder(double radius, double height, int segments, int rows) {
  Mesh mesh;
  mesh.origin = {100.0, -50.0, 2.0};
  for (int j = 0; j <= rows; ++j) {
    for (int i = 0; i < segments; ++i) {
      const double a = 2 * M_PI * i / segments;
      mesh.positions.insert(
          mesh.positions.end(),
          {float(radius * std::cos(a)), float(radius * std::sin(a)), float(height * j / rows)});
      mesh.normals.insert(mesh.normals.end(), {float(std::cos(a)), float(std::sin(a)), 0.0f});
      mesh.colors.insert(mesh.colors.end(), {uint8_t(j * 7), uint8_t(i * 3), 99});
      mesh.tangents.insert(mesh.tangents.end(), {float(-std::sin(a)), float(std::cos(a)), 0, 1});
    }
  }
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < segments; ++i) {
      const uint32_t a = j * segments + i, b = j * segments + (i + 1) % segments;
      const uint32_t c = b + segments, d = a + segments;
      mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
    }
  }
  return mesh;
}

// A ramp winding twice around z (r in [1, 2], rising 0.3 m a turn): its
// normals are all within 10 degrees of +z, so one planar chart would lie on
// top of itself.
Mesh MakeSpiralRamp() {
  Mesh mesh;
  const int steps = 200;
  for (int i = 0; i <= steps; ++i) {
    const double a = 4 * M_PI * i / steps, z = 0.3 * a / (2 * M_PI);
    for (double r : {1.0, 2.0}) {
      mesh.positions.insert(mesh.positions.end(),
                            {float(r * std::cos(a)), float(r * std::sin(a)), float(z)});
    }
  }
  for (int i = 0; i < steps; ++i) {
    const uint32_t in0 = 2 * i, out0 = 2 * i + 1, in1 = 2 * i + 2, out1 = 2 * i + 3;
    mesh.indices.insert(mesh.indices.end(), {in0, out0, out1, in0, out1, in1});
  }
  return mesh;
}

// A brick wall panel in the x-y plane facing +z, 2 m x 0.6 m on a 5 mm grid:
// bricks 215 x 65 mm in running bond, 10 mm joints recessed 4 mm with 2 mm
// bevels (the relief SynthScene gives its walls, here resolved by the grid).
Mesh MakeBrickPanel() {
  Mesh mesh;
  const double cell = 0.005;
  const int nx = 400, ny = 120;
  auto relief = [](double x, double y) {
    const double course = 0.075, length = 0.225;
    const int row = int(std::floor(y / course));
    const double offset = (row % 2) * 0.5 * length;
    const double in_x = std::fmod(x + offset, length), in_y = std::fmod(y, course);
    // Distance into the brick face from its nearest edge (joint at the end).
    const double dx = std::min(in_x, length - 0.010 - in_x),
                 dy = std::min(in_y, course - 0.010 - in_y);
    const double d = std::min(dx, dy);
    if (d <= 0) return -0.004;
    return d >= 0.002 ? 0.0 : -0.004 * (1 - d / 0.002);
  };
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      mesh.positions.insert(mesh.positions.end(),
                            {float(i * cell), float(j * cell), float(relief(i * cell, j * cell))});
    }
  }
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const uint32_t a = j * (nx + 1) + i, b = a + 1, c = a + nx + 2, d = a + nx + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
    }
  }
  return mesh;
}

Mesh RoomWalls() { return SynthTruthMesh(*MakeSynthScene("room", 1), 0.05); }

// Every atlas property the unwrappers promise, at `options`.
void ExpectValidAtlas(const Mesh& in, const Mesh& out, const UnwrapOptions& options) {
  ASSERT_TRUE(Validate(out).ok());
  ASSERT_EQ(out.face_count(), in.face_count());
  ASSERT_EQ(out.uvs.size(), 2 * out.vertex_count());
  // Faces keep their order and winding: the same positions, corner by corner.
  for (size_t i = 0; i < out.indices.size(); ++i) {
    for (int d = 0; d < 3; ++d) {
      ASSERT_EQ(out.positions[3 * size_t(out.indices[i]) + d],
                in.positions[3 * size_t(in.indices[i]) + d])
          << "corner " << i;
    }
  }
  MeasureOptions measure;
  measure.check_overlaps = true;
  measure.gap_probe_texels = 2.0 * options.gutter_texels + 2;
  const AtlasReport r = MeasureAtlas(out, options.size_texels, measure);
  EXPECT_EQ(r.faces_outside, 0u);
  EXPECT_EQ(r.faces_not_ccw, 0u);
  EXPECT_EQ(r.overlapping_faces, 0u);
  EXPECT_EQ(r.overlapping_chart_pairs, 0u);
  if (r.charts > 1) {
    EXPECT_GE(r.min_chart_gap_texels, options.gutter_texels - 1e-3);
  }
  EXPECT_GE(r.min_border_gap_texels, options.gutter_texels - 1e-3);
  EXPECT_GT(r.coverage, 0.0);
  EXPECT_LE(r.coverage, 1.0);
}

TEST(UvAtlasTest, PlaneIsOneUndistortedChart) {
  Mesh plane;
  const int n = 30;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      plane.positions.insert(plane.positions.end(), {float(i) / n * 2, float(j) / n, 0.5f});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      plane.indices.insert(plane.indices.end(), {a, b, c, a, c, d});
    }
  }
  UnwrapOptions options;
  options.size_texels = 1024;
  AtlasReport report;
  auto out = UnwrapCharts(plane, options, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  ExpectValidAtlas(plane, *out, options);
  EXPECT_EQ(report.charts, 1u);
  EXPECT_EQ(out->vertex_count(), plane.vertex_count());
  EXPECT_NEAR(report.stretch_l2, 1.0, 1e-4);
  EXPECT_NEAR(report.stretch_linf, 1.0, 1e-3);
  EXPECT_EQ(report.seam_length_m, 0.0);
  // A 2:1 rectangle fills half the atlas, less the gutter.
  EXPECT_GT(report.coverage, 0.49);
  EXPECT_NEAR(report.texels_per_meter, (1024 - 8) / 2.0, 3.0);
}

TEST(UvAtlasTest, CylinderHasBoundedStretch) {
  const Mesh cylinder = MakeCylinder(0.5, 1.0, 96, 20);
  UnwrapOptions options;
  options.size_texels = 2048;
  options.gutter_texels = 4;
  AtlasReport report;
  auto out = UnwrapCharts(cylinder, options, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  ExpectValidAtlas(cylinder, *out, options);
  EXPECT_GE(report.charts, 4u);
  EXPECT_LE(report.charts, 8u);
  EXPECT_LT(report.stretch_l2, 1.1);
  EXPECT_GE(report.stretch_l2, 1.0);
  EXPECT_LT(report.stretch_linf, 1.35);
  // Each seam is a cut up the cylinder's height (with a jog or two).
  EXPECT_GE(report.seam_length_m, report.charts * 1.0 - 1e-3);
  EXPECT_LE(report.seam_length_m, report.charts * 1.05);
  EXPECT_GT(report.coverage, 0.5);
}

TEST(UvAtlasTest, BlenderAngleAloneStretchesMore) {
  // The stretch bound is what keeps the cylinder undistorted: with
  // max_stretch out of the way, 66 degrees gives fewer, more stretched charts.
  const Mesh cylinder = MakeCylinder(0.5, 1.0, 96, 20);
  UnwrapOptions options;
  options.size_texels = 2048;
  options.max_stretch = 100;
  AtlasReport report;
  auto out = UnwrapCharts(cylinder, options, &report);
  ASSERT_TRUE(out.ok());
  ExpectValidAtlas(cylinder, *out, options);
  EXPECT_LE(report.charts, 4u);
  EXPECT_GT(report.stretch_linf, 1.8);
}

TEST(UvAtlasTest, BrickRoomIsValidWithBoundedStretch) {
  const Mesh room = RoomWalls();
  UnwrapOptions options;
  options.size_texels = 4096;
  AtlasReport report;
  auto out = UnwrapCharts(room, options, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  ExpectValidAtlas(room, *out, options);
  EXPECT_LT(report.stretch_l2, 1.1);
  EXPECT_LT(report.stretch_linf, 1.25 * 1.15);
  EXPECT_GT(report.coverage, 0.3);
  EXPECT_GT(report.seam_length_m, 0.0);
}

TEST(UvAtlasTest, BrickReliefPanelIsValidWithBoundedStretch) {
  const Mesh panel = MakeBrickPanel();
  UnwrapOptions options;
  options.size_texels = 4096;
  AtlasReport report;
  auto out = UnwrapCharts(panel, options, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  ExpectValidAtlas(panel, *out, options);
  // The bevels (63 degrees) and joint flanks leave the brick faces' chart.
  EXPECT_GT(report.charts, 10u);
  EXPECT_LT(report.stretch_l2, 1.1);
  EXPECT_LT(report.stretch_linf, 1.25 * 1.2 + 0.01);
}

TEST(UvAtlasTest, SpiralThatWouldOverlapIsSplit) {
  const Mesh ramp = MakeSpiralRamp();
  UnwrapOptions options;
  options.size_texels = 1024;
  AtlasReport report;
  auto out = UnwrapCharts(ramp, options, &report);
  ASSERT_TRUE(out.ok());
  ExpectValidAtlas(ramp, *out, options);
  EXPECT_GE(report.charts, 2u);
}

TEST(UvAtlasTest, SliversBecomeOneTexelTriangles) {
  // A cylinder plus a needle 1 m long and 1 nm high: float UVs cannot hold
  // the needle at its true shape, so it gets a fixed triangle and stays CCW.
  Mesh mesh = MakeCylinder(0.5, 1.0, 24, 4);
  const uint32_t base = uint32_t(mesh.vertex_count());
  for (float x : {0.0f, 1.0f, 0.5f}) {
    mesh.positions.insert(mesh.positions.end(), {x, x == 0.5f ? 1e-9f : 0.0f, 3.0f});
    mesh.normals.insert(mesh.normals.end(), {0, 0, 1});
    mesh.colors.insert(mesh.colors.end(), {1, 2, 3});
    mesh.tangents.insert(mesh.tangents.end(), {1, 0, 0, 1});
  }
  mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2});
  UnwrapOptions options;
  options.size_texels = 512;
  AtlasReport report;
  auto out = UnwrapCharts(mesh, options, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  ExpectValidAtlas(mesh, *out, options);
  EXPECT_EQ(report.isolated_faces, 1u);
  const size_t f = mesh.face_count() - 1;
  const float* a = &out->uvs[2 * size_t(out->indices[3 * f])];
  const float* b = &out->uvs[2 * size_t(out->indices[3 * f + 1])];
  EXPECT_NEAR((b[0] - a[0]) * 512, 1.0, 1e-3);  // one texel along u
  EXPECT_LT(report.stretch_linf, 1.5);          // the needle is left out of Linf
}

TEST(UvAtlasTest, MeasureFindsOverlapsAndNarrowGaps) {
  // Two triangles of different charts, overlapping; then 2 texels apart.
  Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1};
  mesh.indices = {0, 1, 2, 3, 4, 5};
  mesh.uvs = {0.1f, 0.1f, 0.5f, 0.1f, 0.1f, 0.5f, 0.2f, 0.2f, 0.6f, 0.2f, 0.2f, 0.6f};
  MeasureOptions measure;
  measure.check_overlaps = true;
  AtlasReport r = MeasureAtlas(mesh, 100, measure);
  EXPECT_EQ(r.charts, 2u);
  EXPECT_EQ(r.overlapping_faces, 1u);
  EXPECT_EQ(r.overlapping_chart_pairs, 1u);
  EXPECT_EQ(r.min_chart_gap_texels, 0.0);
  mesh.uvs = {0.1f, 0.1f, 0.5f, 0.1f, 0.1f, 0.5f, 0.52f, 0.1f, 0.9f, 0.1f, 0.52f, 0.5f};
  r = MeasureAtlas(mesh, 100, measure);
  EXPECT_EQ(r.overlapping_faces, 0u);
  // Closest: the first's corner (0.5, 0.1) and the second's (0.52, 0.1).
  EXPECT_NEAR(r.min_chart_gap_texels, 2.0, 1e-3);
  EXPECT_NEAR(r.min_border_gap_texels, 10.0, 1e-3);
  // Mirrored: clockwise in UV.
  mesh.uvs = {0.1f, 0.1f, 0.1f, 0.5f, 0.5f, 0.1f, 0.52f, 0.1f, 0.9f, 0.1f, 0.52f, 0.5f};
  r = MeasureAtlas(mesh, 100, measure);
  EXPECT_EQ(r.faces_not_ccw, 1u);
}

TEST(UvAtlasTest, SeamVerticesCarryTheirAttributes) {
  const Mesh cylinder = MakeCylinder(0.5, 1.0, 48, 6);
  UnwrapOptions options;
  options.size_texels = 1024;
  auto out = UnwrapCharts(cylinder, options, nullptr);
  ASSERT_TRUE(out.ok());
  EXPECT_GT(out->vertex_count(), cylinder.vertex_count());  // seams split vertices
  ASSERT_EQ(out->normals.size(), 3 * out->vertex_count());
  ASSERT_EQ(out->colors.size(), 3 * out->vertex_count());
  ASSERT_EQ(out->tangents.size(), 4 * out->vertex_count());
  EXPECT_EQ(out->origin, cylinder.origin);
  for (size_t i = 0; i < out->indices.size(); ++i) {
    const size_t o = out->indices[i], v = cylinder.indices[i];
    for (int d = 0; d < 3; ++d) {
      EXPECT_EQ(out->normals[3 * o + d], cylinder.normals[3 * v + d]);
      EXPECT_EQ(out->colors[3 * o + d], cylinder.colors[3 * v + d]);
    }
    for (int d = 0; d < 4; ++d) EXPECT_EQ(out->tangents[4 * o + d], cylinder.tangents[4 * v + d]);
  }
}

TEST(UvAtlasTest, DeterministicWhateverTheThreads) {
  const Mesh room = RoomWalls();
  UnwrapOptions options;
  options.size_texels = 2048;
  options.threads = 1;
  auto one = UnwrapCharts(room, options, nullptr);
  auto again = UnwrapCharts(room, options, nullptr);
  options.threads = 2;
  auto two = UnwrapCharts(room, options, nullptr);
  ASSERT_TRUE(one.ok() && again.ok() && two.ok());
  for (const Mesh* other : {&*again, &*two}) {
    EXPECT_EQ(one->indices, other->indices);
    EXPECT_EQ(one->positions, other->positions);
    EXPECT_EQ(one->uvs, other->uvs);
    EXPECT_EQ(one->colors, other->colors);
  }
}

TEST(UvAtlasTest, PerTriangleBaseline) {
  const Mesh cylinder = MakeCylinder(0.5, 1.0, 24, 5);
  UnwrapOptions options;
  options.method = UnwrapMethod::kPerTriangle;
  options.size_texels = 512;
  options.gutter_texels = 3;
  AtlasReport report;
  auto out = UnwrapMesh(cylinder, options, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  ExpectValidAtlas(cylinder, *out, options);
  EXPECT_EQ(report.charts, cylinder.face_count());
  EXPECT_EQ(out->vertex_count(), 3 * cylinder.face_count());
  EXPECT_GT(report.stretch_l2, 1.1);  // right isosceles triangles distort
  // 240 faces on 512 texels: 16 cells a row of 31 texels, legs of 28.
  EXPECT_NEAR(report.coverage, 240 * 0.5 * 28.0 * 28.0 / (512.0 * 512.0), 1e-4);

  options.size_texels = 64;
  auto too_small = UnwrapMesh(cylinder, options, nullptr);
  ASSERT_FALSE(too_small.ok());
  EXPECT_NE(too_small.status().message().find("raise `size`"), std::string::npos);
}

TEST(UvAtlasTest, NonManifoldEdgesBecomeSeams) {
  // Three faces on one edge (a fin): each face is its own chart there.
  Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 0.5f, 1, 0, 0.5f, -1, 0, 0.5f, 0, 1};
  mesh.indices = {0, 1, 2, 1, 0, 3, 1, 0, 4};
  UnwrapOptions options;
  options.size_texels = 256;
  AtlasReport report;
  auto out = UnwrapCharts(mesh, options, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  ExpectValidAtlas(mesh, *out, options);
  EXPECT_EQ(report.charts, 3u);
}

TEST(UvAtlasTest, RejectsBadOptionsAndMeshes) {
  const Mesh cylinder = MakeCylinder(0.5, 1.0, 12, 2);
  UnwrapOptions options;
  options.max_angle_deg = 95;
  EXPECT_FALSE(UnwrapCharts(cylinder, options, nullptr).ok());
  options = {};
  options.gutter_texels = -1;
  EXPECT_FALSE(UnwrapCharts(cylinder, options, nullptr).ok());
  options = {};
  options.size_texels = 4;
  EXPECT_FALSE(UnwrapCharts(cylinder, options, nullptr).ok());
  Mesh broken = cylinder;
  broken.indices.push_back(9999);
  broken.indices.push_back(0);
  broken.indices.push_back(1);
  EXPECT_FALSE(UnwrapCharts(broken, {}, nullptr).ok());
  // Too many charts for the gutter: 20 separate triangles in 8 texels (each
  // needs 2 x 2 with its gutter, 3 x 3 fit).
  Mesh soup;
  for (int i = 0; i < 20; ++i) {
    const float x = float(i);
    soup.positions.insert(soup.positions.end(), {x, 0, 0, x + 1, 0, 0, x, 1, 0});
    soup.indices.insert(soup.indices.end(),
                        {uint32_t(3 * i), uint32_t(3 * i + 1), uint32_t(3 * i + 2)});
  }
  options = {};
  options.size_texels = 8;
  options.gutter_texels = 1;
  auto packed = UnwrapCharts(soup, options, nullptr);
  ASSERT_FALSE(packed.ok());
  EXPECT_NE(packed.status().message().find("do not fit"), std::string::npos);
}

TEST(UvPackTest, FillsTheAtlasWithTheGutter) {
  std::vector<ChartExtent> charts;
  for (int i = 0; i < 50; ++i) charts.push_back({1.0 + 0.1 * (i % 7), 0.5 + 0.05 * (i % 5)});
  auto packed = PackCharts(charts, 1024, 4);
  ASSERT_TRUE(packed.ok());
  const double s = packed->texels_per_meter;
  double area = 0;
  for (size_t i = 0; i < charts.size(); ++i) {
    const double x0 = double(packed->x_texels[i]), y0 = double(packed->y_texels[i]);
    const double w = packed->turned[i] ? charts[i].height : charts[i].width;
    const double h = packed->turned[i] ? charts[i].width : charts[i].height;
    const double x1 = x0 + std::ceil(w * s), y1 = y0 + std::ceil(h * s);
    EXPECT_GE(x0, 4);
    EXPECT_GE(y0, 4);
    EXPECT_LE(x1, 1020);
    EXPECT_LE(y1, 1020);
    area += (x1 - x0) * (y1 - y0);
    for (size_t j = 0; j < i; ++j) {
      const double u0 = double(packed->x_texels[j]), v0 = double(packed->y_texels[j]);
      const double wj = packed->turned[j] ? charts[j].height : charts[j].width;
      const double hj = packed->turned[j] ? charts[j].width : charts[j].height;
      const double u1 = u0 + std::ceil(wj * s), v1 = v0 + std::ceil(hj * s);
      const bool apart = x0 >= u1 + 4 || u0 >= x1 + 4 || y0 >= v1 + 4 || v0 >= y1 + 4;
      EXPECT_TRUE(apart) << i << " vs " << j;
    }
  }
  EXPECT_GT(area / (1024.0 * 1024.0), 0.6);
}

}  // namespace
}  // namespace pb
