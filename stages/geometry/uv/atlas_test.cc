#include "stages/geometry/uv/atlas.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <string>

#include "stages/geometry/core/image.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/synth/scene.h"
#include "stages/geometry/uv/conformal.h"
#include "stages/geometry/uv/pack.h"
#include "stages/geometry/uv/raster_pack.h"
#include "stages/geometry/uv/surface_charts.h"

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

// A sphere of `radius` (an icosahedron subdivided `levels` times) with
// radial bumps of relative height `bump`: curved everywhere, like a scanned
// statue, with no plane to project on.
Mesh MakeBumpySphere(double radius, int levels, double bump) {
  Mesh mesh;
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<std::array<double, 3>> p = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                          {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                          {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<uint32_t, 3>> faces = {
      {0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  auto unit = [](std::array<double, 3> v) {
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    return std::array<double, 3>{v[0] / n, v[1] / n, v[2] / n};
  };
  for (auto& v : p) v = unit(v);
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> middle;
    auto mid = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = middle.find(key);
      if (it != middle.end()) return it->second;
      p.push_back(unit({p[a][0] + p[b][0], p[a][1] + p[b][1], p[a][2] + p[b][2]}));
      return middle[key] = uint32_t(p.size() - 1);
    };
    std::vector<std::array<uint32_t, 3>> next;
    for (const auto& f : faces) {
      const uint32_t ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      next.push_back({f[0], ab, ca});
      next.push_back({f[1], bc, ab});
      next.push_back({f[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    faces = std::move(next);
  }
  for (const auto& v : p) {
    const double r = radius * (1 + bump * std::sin(5 * v[0]) * std::sin(4 * v[1] + 1) *
                                       std::sin(3 * v[2] + 2));
    mesh.positions.insert(mesh.positions.end(),
                          {float(r * v[0]), float(r * v[1]), float(r * v[2])});
  }
  for (const auto& f : faces) mesh.indices.insert(mesh.indices.end(), {f[0], f[1], f[2]});
  return mesh;
}

// A bumpy sphere with radial noise of relative amplitude `noise` per
// vertex (a fixed hash, so the same mesh every run), like a noisy scan:
// its charts fail the stretch bound, are split round after round and
// leave many small charts to join.
Mesh MakeNoisySphere(double radius, int levels, double bump, double noise) {
  Mesh mesh = MakeBumpySphere(radius, levels, bump);
  uint32_t state = 12345;
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    state = state * 1664525u + 1013904223u;
    const double jitter = 1 + noise * (double(state >> 8) / double(1u << 24) - 0.5);
    for (int d = 0; d < 3; ++d) mesh.positions[3 * v + d] *= float(jitter);
  }
  return mesh;
}

// Rasterizes the atlas at its texel size (texel centers) and counts texels
// claimed by two different charts.
uint64_t TexelsWithTwoOwners(const Mesh& mesh, int size) {
  uint32_t chart_count = 0;
  const std::vector<uint32_t> chart = ChartOfFaces(mesh, &chart_count);
  std::vector<uint32_t> owner(size_t(size) * size, std::numeric_limits<uint32_t>::max());
  uint64_t shared = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    double x[3], y[3];
    for (int k = 0; k < 3; ++k) {
      x[k] = mesh.uvs[2 * size_t(mesh.indices[3 * f + k])] * size;
      y[k] = mesh.uvs[2 * size_t(mesh.indices[3 * f + k]) + 1] * size;
    }
    const int x0 = std::max(0, int(std::floor(std::min({x[0], x[1], x[2]}))));
    const int x1 = std::min(size - 1, int(std::ceil(std::max({x[0], x[1], x[2]}))));
    const int y0 = std::max(0, int(std::floor(std::min({y[0], y[1], y[2]}))));
    const int y1 = std::min(size - 1, int(std::ceil(std::max({y[0], y[1], y[2]}))));
    for (int py = y0; py <= y1; ++py) {
      for (int px = x0; px <= x1; ++px) {
        const double cx = px + 0.5, cy = py + 0.5;
        const double d0 = (x[1] - x[0]) * (cy - y[0]) - (y[1] - y[0]) * (cx - x[0]);
        const double d1 = (x[2] - x[1]) * (cy - y[1]) - (y[2] - y[1]) * (cx - x[1]);
        const double d2 = (x[0] - x[2]) * (cy - y[2]) - (y[0] - y[2]) * (cx - x[2]);
        if (!(d0 >= 0 && d1 >= 0 && d2 >= 0)) continue;
        uint32_t& o = owner[size_t(py) * size + px];
        if (o != std::numeric_limits<uint32_t>::max() && o != chart[f]) ++shared;
        o = chart[f];
      }
    }
  }
  return shared;
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

// Regression (c5c37d9): faces of charts settled in an earlier round kept
// their old pending-chart index, so peeling or splitting a chart in a later
// round took in settled neighbours whose old index matched (and wrote out
// of bounds: heap corruption on the bunny's 93k-face Poisson mesh). A
// bumpy sphere with a little scanner-like noise needs eight rounds of
// peeling and splitting at the default bound; without the fix face 10467
// comes out in two charts (and the sanitizer build reports the overflow).
TEST(UvAtlasTest, SplitRoundsKeepEveryFaceInOneChart) {
  Mesh sphere = MakeBumpySphere(1.0, 5, 0.1);  // 20,480 faces
  // Each vertex moved along its radius by up to 0.1 % (Knuth's
  // multiplicative hash of its index: fixed pseudo-random amounts).
  for (size_t v = 0; v < sphere.vertex_count(); ++v) {
    const double u = double((uint32_t(v) * 2654435761u) >> 8) / double(1u << 24) - 0.5;
    for (int d = 0; d < 3; ++d) sphere.positions[3 * v + d] *= float(1 + 0.002 * u);
  }
  const std::vector<FlatChart> charts = MakeFlatCharts(sphere, ChartOptions(), nullptr, {});
  std::vector<int> seen(sphere.face_count(), 0);
  for (const FlatChart& chart : charts) {
    for (uint32_t f : chart.faces) ++seen[f];
  }
  for (size_t f = 0; f < seen.size(); ++f) ASSERT_EQ(seen[f], 1) << "face " << f;
  UnwrapOptions unwrap;
  unwrap.method = UnwrapMethod::kCharts;
  unwrap.size_texels = 2048;
  auto out = UnwrapCharts(sphere, unwrap, nullptr);
  ASSERT_TRUE(out.ok());
  ExpectValidAtlas(sphere, *out, unwrap);
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

TEST(UvConformalTest, LscmUnrollsACylinderWithoutStretch) {
  // A half cylinder is developable: its conformal map is an isometry.
  const Mesh cylinder = MakeCylinder(0.5, 1.0, 24, 6);
  std::vector<uint32_t> corners;
  for (size_t f = 0; f < cylinder.face_count(); ++f) {
    const uint32_t* c = &cylinder.indices[3 * f];
    bool half = true;
    for (int k = 0; k < 3; ++k) half &= c[k] % 24 <= 12;  // angles 0..180 deg
    if (half && !(c[0] % 24 == 12 && c[1] % 24 == 0)) corners.insert(corners.end(), c, c + 3);
  }
  std::vector<double> positions(cylinder.positions.begin(), cylinder.positions.end());
  std::vector<double> uv;
  ASSERT_TRUE(LscmFlatten(positions, corners, &uv));
  FlatChart chart;
  Mesh piece = cylinder;
  piece.indices = corners;
  for (size_t f = 0; f < corners.size() / 3; ++f) chart.faces.push_back(uint32_t(f));
  for (size_t v = 0; v < cylinder.vertex_count(); ++v) chart.vertices.push_back(uint32_t(v));
  chart.corners = corners;
  chart.uv_m = uv;
  // Every face counter-clockwise (nothing mirrored), and no stretch.
  for (size_t f = 0; f < corners.size() / 3; ++f) {
    const double* a = &uv[2 * corners[3 * f]];
    const double* b = &uv[2 * corners[3 * f + 1]];
    const double* c = &uv[2 * corners[3 * f + 2]];
    EXPECT_GT((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]), 0) << f;
  }
  EXPECT_LT(ChartStretchL2(piece, chart), 1.001);
}

// The smallest systems: one unknown vertex (a triangle: the ordering has
// nothing to order) and two (a bent quad). LSCM keeps a triangle's shape,
// pinned at its true side length, and both counter-clockwise.
TEST(UvConformalTest, LscmFlattensATriangleAndABentQuad) {
  auto length = [](const double* p, uint32_t a, uint32_t b, int dims) {
    double d2 = 0;
    for (int k = 0; k < dims; ++k) {
      const double d = p[dims * a + k] - p[dims * b + k];
      d2 += d * d;
    }
    return std::sqrt(d2);
  };
  const std::vector<double> triangle = {0, 0, 0, 2, 0, 1, 0.5, 1.5, -0.5};
  const std::vector<uint32_t> one = {0, 1, 2};
  std::vector<double> uv;
  ASSERT_TRUE(LscmFlatten(triangle, one, &uv));
  for (auto [a, b] : {std::pair{0u, 1u}, {1u, 2u}, {2u, 0u}}) {
    EXPECT_NEAR(length(uv.data(), a, b, 2), length(triangle.data(), a, b, 3), 1e-9);
  }
  auto ccw = [&](uint32_t a, uint32_t b, uint32_t c) {
    return (uv[2 * b] - uv[2 * a]) * (uv[2 * c + 1] - uv[2 * a + 1]) -
               (uv[2 * c] - uv[2 * a]) * (uv[2 * b + 1] - uv[2 * a + 1]) >
           0;
  };
  EXPECT_TRUE(ccw(0, 1, 2));
  // A unit square folded 60 degrees along its diagonal 0-2.
  const double h = 0.5 * std::sqrt(3.0);
  const std::vector<double> quad = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0.25, 0.75, h * std::sqrt(0.5)};
  const std::vector<uint32_t> two = {0, 1, 2, 0, 2, 3};
  ASSERT_TRUE(LscmFlatten(quad, two, &uv));
  EXPECT_TRUE(ccw(0, 1, 2));
  EXPECT_TRUE(ccw(0, 2, 3));
  for (auto [a, b] : {std::pair{0u, 1u}, {1u, 2u}, {0u, 2u}, {2u, 3u}, {3u, 0u}}) {
    EXPECT_NEAR(length(uv.data(), a, b, 2), length(quad.data(), a, b, 3), 1e-6);
  }
}

TEST(UvConformalTest, BumpySphereMeetsTheAtlasTargets) {
  const Mesh sphere = MakeBumpySphere(1.0, 4, 0.08);  // 5,120 faces
  UnwrapOptions options;
  options.method = UnwrapMethod::kConformal;
  options.size_texels = 2048;
  AtlasReport report;
  auto out = UnwrapConformal(sphere, options, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  ExpectValidAtlas(sphere, *out, options);
  if (const char* png = std::getenv("PB_UV_TEST_PNG")) {
    ASSERT_TRUE(WritePng(png, DrawAtlas(*out, 1024)).ok());
  }
  EXPECT_LE(report.charts, sphere.face_count() / 25);
  EXPECT_GE(report.coverage, 0.70);
  EXPECT_LE(report.stretch_l2, 1.05);
  EXPECT_EQ(report.faces_not_ccw, 0u);
  EXPECT_EQ(TexelsWithTwoOwners(*out, options.size_texels), 0u);
  // The planar method needs many more charts and packs worse on it.
  AtlasReport planar;
  options.method = UnwrapMethod::kCharts;
  ASSERT_TRUE(UnwrapCharts(sphere, options, &planar).ok());
  EXPECT_LT(report.charts, planar.charts);
  EXPECT_GT(report.coverage, planar.coverage);
}

TEST(UvConformalTest, TighterStretchBoundSplitsMore) {
  const Mesh sphere = MakeBumpySphere(1.0, 3, 0.0);  // 1,280 faces, a plain sphere
  UnwrapOptions options;
  options.method = UnwrapMethod::kConformal;
  options.size_texels = 1024;
  options.cone_deg = 80;  // large caps, which the bound must split
  AtlasReport loose, tight;
  ASSERT_TRUE(UnwrapConformal(sphere, options, &loose).ok());
  options.max_chart_stretch = 1.005;
  auto out = UnwrapConformal(sphere, options, &tight);
  ASSERT_TRUE(out.ok());
  ExpectValidAtlas(sphere, *out, options);
  EXPECT_GT(tight.charts, loose.charts) << loose.stretch_l2 << " " << tight.stretch_l2;
  EXPECT_LE(tight.stretch_l2, 1.005);
  EXPECT_LE(loose.stretch_l2, 1.03);
}

TEST(UvConformalTest, RoomIsValidAndFlatWallsStayUndistorted) {
  const Mesh room = RoomWalls();
  UnwrapOptions options;
  options.method = UnwrapMethod::kConformal;
  options.size_texels = 2048;
  AtlasReport report;
  auto out = UnwrapConformal(room, options, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  ExpectValidAtlas(room, *out, options);
  EXPECT_LT(report.stretch_l2, 1.001);
  EXPECT_GT(report.coverage, 0.75);
  EXPECT_EQ(TexelsWithTwoOwners(*out, options.size_texels), 0u);
}

TEST(UvConformalTest, DeterministicWhateverTheThreads) {
  const Mesh sphere = MakeBumpySphere(1.0, 4, 0.08);
  UnwrapOptions options;
  options.method = UnwrapMethod::kConformal;
  options.size_texels = 1024;
  options.threads = 1;
  auto one = UnwrapConformal(sphere, options, nullptr);
  auto again = UnwrapConformal(sphere, options, nullptr);
  options.threads = 2;
  auto two = UnwrapConformal(sphere, options, nullptr);
  ASSERT_TRUE(one.ok() && again.ok() && two.ok());
  for (const Mesh* other : {&*again, &*two}) {
    EXPECT_EQ(one->indices, other->indices);
    EXPECT_EQ(one->positions, other->positions);
    EXPECT_EQ(one->uvs, other->uvs);
  }
}

TEST(UvConformalTest, NoisyMeshDeterministicWhateverTheThreads) {
  // Splitting and small-chart joining run in parallel (the joins
  // speculatively, see surface_charts.cc); this noisy sphere (20,480 faces)
  // goes through both: charts split again and again (eight rounds and more
  // when splitting went by rounds), then 427 small charts tried in 41
  // windows, 324 joins, 57 attempts made again because an earlier join
  // changed what they read.
  const Mesh sphere = MakeNoisySphere(1.0, 5, 0.08, 0.05);
  UnwrapOptions options;
  options.method = UnwrapMethod::kConformal;
  options.size_texels = 1024;
  options.threads = 1;
  AtlasReport report;
  auto one = UnwrapConformal(sphere, options, &report);
  options.threads = 2;
  auto two = UnwrapConformal(sphere, options, nullptr);
  ASSERT_TRUE(one.ok() && two.ok());
  ExpectValidAtlas(sphere, *one, options);
  EXPECT_GT(report.charts, 20u);
  EXPECT_EQ(one->indices, two->indices);
  EXPECT_EQ(one->positions, two->positions);
  EXPECT_EQ(one->uvs, two->uvs);
}

// Packs `charts` and checks the atlas: every chart inside the border
// gutter, no two charts closer than the gutter. Returns the packing.
RasterPackResult ExpectValidRasterPacking(const std::vector<FlatChart>& charts, int size,
                                          int gutter) {
  auto packed = RasterPackCharts(charts, size, gutter);
  EXPECT_TRUE(packed.ok()) << packed.status().message();
  if (!packed.ok()) return {};
  const double s = packed->texels_per_meter;
  std::vector<Box2> boxes;
  std::vector<std::array<double, 6>> triangles;
  std::vector<uint32_t> owner;
  for (size_t c = 0; c < charts.size(); ++c) {
    for (size_t f = 0; f < charts[c].faces.size(); ++f) {
      std::array<double, 6> t;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = charts[c].corners[3 * f + k];
        const auto p = PlacedTexel(packed->placements[c], s, charts[c].uv_m[2 * v],
                                   charts[c].uv_m[2 * v + 1]);
        t[2 * k] = p[0];
        t[2 * k + 1] = p[1];
        EXPECT_GE(std::min(p[0], p[1]), gutter - 1e-9);
        EXPECT_LE(std::max(p[0], p[1]), size - gutter + 1e-9);
      }
      triangles.push_back(t);
      owner.push_back(uint32_t(c));
      boxes.push_back({std::min({t[0], t[2], t[4]}) - gutter / 2.0,
                       std::min({t[1], t[3], t[5]}) - gutter / 2.0,
                       std::max({t[0], t[2], t[4]}) + gutter / 2.0,
                       std::max({t[1], t[3], t[5]}) + gutter / 2.0});
    }
  }
  int too_close = 0;
  ForEachIntersectingBoxPair(boxes, [&](uint32_t i, uint32_t j) {
    if (owner[i] != owner[j] && TriangleDistance(triangles[i], triangles[j]) < gutter - 1e-6) {
      ++too_close;
    }
    return true;
  });
  EXPECT_EQ(too_close, 0);
  return *packed;
}

TEST(UvRasterPackTest, ManySmallIrregularChartsFillTheSquare) {
  // 600 small charts: irregular convex polygons (fans of 5-9 triangles) of
  // varied size, as a curved mesh's atlas has.
  std::vector<FlatChart> charts;
  double area = 0;
  uint32_t seed = 12345;
  auto random = [&]() {
    seed = seed * 1664525u + 1013904223u;
    return double(seed >> 8) / double(1u << 24);
  };
  for (int i = 0; i < 600; ++i) {
    FlatChart chart;
    const int sides = 5 + i % 5;
    const double radius = 0.5 + 1.5 * random();
    chart.vertices.push_back(0);
    chart.uv_m = {0, 0};
    for (int k = 0; k < sides; ++k) {
      const double a = 2 * M_PI * (k + 0.3 * random()) / sides;
      const double r = radius * (0.6 + 0.4 * random());
      chart.vertices.push_back(uint32_t(k + 1));
      chart.uv_m.insert(chart.uv_m.end(), {r * std::cos(a), r * std::sin(a)});
    }
    for (int k = 0; k < sides; ++k) {
      chart.faces.push_back(uint32_t(k));
      chart.corners.insert(chart.corners.end(),
                           {0u, uint32_t(k + 1), uint32_t((k + 1) % sides + 1)});
    }
    FitRectangle(&chart);
    for (int k = 0; k < sides; ++k) {
      const double* a = &chart.uv_m[0];
      const double* b = &chart.uv_m[2 * (k + 1)];
      const double* c = &chart.uv_m[2 * ((k + 1) % sides + 1)];
      area += 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
    }
    charts.push_back(std::move(chart));
  }
  const int size = 2048, gutter = 2;
  const RasterPackResult packed = ExpectValidRasterPacking(charts, size, gutter);
  const double s = packed.texels_per_meter;
  EXPECT_GE(area * s * s / (double(size) * size), 0.75);
}

TEST(UvRasterPackTest, SmallChartsNestInsideARing) {
  // A ring (a chart with a hole: two boundary loops) and four squares that
  // fit only in its hole. The packer rasterizes a chart by its boundary
  // loops, filling between them by the even-odd rule: the hole must stay
  // free, and be used.
  std::vector<FlatChart> charts;
  const int kSides = 24;
  FlatChart ring;
  for (int k = 0; k < kSides; ++k) {
    const double a = 2 * M_PI * k / kSides;
    for (double r : {1.0, 0.75}) {  // outer vertex 2k, inner 2k + 1
      ring.vertices.push_back(uint32_t(ring.vertices.size()));
      ring.uv_m.insert(ring.uv_m.end(), {r * std::cos(a), r * std::sin(a)});
    }
  }
  for (int k = 0; k < kSides; ++k) {
    const uint32_t o = 2 * k, in = 2 * k + 1, o2 = 2 * ((k + 1) % kSides), in2 = o2 + 1;
    ring.faces.insert(ring.faces.end(), {uint32_t(2 * k), uint32_t(2 * k + 1)});
    ring.corners.insert(ring.corners.end(), {o, o2, in2, o, in2, in});
  }
  FitRectangle(&ring);
  charts.push_back(std::move(ring));
  for (int i = 0; i < 4; ++i) {
    FlatChart square;
    square.faces = {0, 1};
    square.vertices = {0, 1, 2, 3};
    square.uv_m = {0, 0, 0.4, 0, 0.4, 0.4, 0, 0.4};
    square.corners = {0, 1, 2, 0, 2, 3};
    FitRectangle(&square);
    charts.push_back(std::move(square));
  }
  const int size = 256, gutter = 2;
  const RasterPackResult packed = ExpectValidRasterPacking(charts, size, gutter);
  // As boxes, the squares would need a strip beside the ring's square:
  // 2.4 m a side. In the hole, the ring alone sets the scale.
  EXPECT_FALSE(packed.boxes);
  EXPECT_GT(packed.texels_per_meter, (size - 2.0 * gutter) / 2.2);
  const double s = packed.texels_per_meter;
  const auto centre = PlacedTexel(packed.placements[0], s, 0.5 * charts[0].width_m,
                                  0.5 * charts[0].height_m);
  for (size_t c = 1; c < charts.size(); ++c) {
    const auto p = PlacedTexel(packed.placements[c], s, 0.5 * charts[c].width_m,
                               0.5 * charts[c].height_m);
    EXPECT_LT(std::hypot(p[0] - centre[0], p[1] - centre[1]), 0.75 * s) << "square " << c;
  }
}

// `count` star-shaped charts (fans of 12 triangles around a centre, radii
// 0.35-1 m at random): concave, about half their box, as a scan's charts.
std::vector<FlatChart> MakeStarCharts(int count, uint32_t seed) {
  auto random = [&]() {
    seed = seed * 1664525u + 1013904223u;
    return double(seed >> 8) / double(1u << 24);
  };
  std::vector<FlatChart> charts;
  for (int i = 0; i < count; ++i) {
    FlatChart chart;
    const int sides = 12;
    const double scale = 0.5 + random();
    chart.vertices.push_back(0);
    chart.uv_m = {0, 0};
    for (int k = 0; k < sides; ++k) {
      const double a = 2 * M_PI * k / sides;
      const double r = scale * (k % 2 == 0 ? 0.6 + 0.4 * random() : 0.35 + 0.2 * random());
      chart.vertices.push_back(uint32_t(k + 1));
      chart.uv_m.insert(chart.uv_m.end(), {r * std::cos(a), r * std::sin(a)});
    }
    for (int k = 0; k < sides; ++k) {
      chart.faces.push_back(uint32_t(k));
      chart.corners.insert(chart.corners.end(),
                           {0u, uint32_t(k + 1), uint32_t((k + 1) % sides + 1)});
    }
    FitRectangle(&chart);
    charts.push_back(std::move(chart));
  }
  return charts;
}

TEST(UvRasterPackTest, FewIrregularChartsAlsoTryOtherAngles) {
  // Few concave charts: besides the quarter turns of their minimal
  // rectangles, the packer tries turns by multiples of 30 and 15 degrees
  // at larger scales, kept only when they fit. On these charts they do:
  // some chart ends up turned by another angle, the atlas still valid
  // (inside the border gutter, gutters between charts, every triangle
  // counter-clockwise) and the same for one and two threads.
  const std::vector<FlatChart> charts = MakeStarCharts(24, 777);
  const int size = 512, gutter = 2;
  RasterPackResult one, two;
  tbb::task_arena(1).execute([&]() { one = ExpectValidRasterPacking(charts, size, gutter); });
  tbb::task_arena(2).execute([&]() { two = ExpectValidRasterPacking(charts, size, gutter); });
  int turned = 0, not_ccw = 0;
  const double s = one.texels_per_meter;
  for (size_t c = 0; c < charts.size(); ++c) {
    const RasterPlacement& p = one.placements[c];
    if (p.angle != 0) ++turned;
    for (size_t f = 0; f < charts[c].faces.size(); ++f) {
      std::array<double, 2> t[3];
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = charts[c].corners[3 * f + k];
        t[k] = PlacedTexel(p, s, charts[c].uv_m[2 * v], charts[c].uv_m[2 * v + 1]);
      }
      const double cross =
          (t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[2][0] - t[0][0]) * (t[1][1] - t[0][1]);
      if (!(cross > 0)) ++not_ccw;
    }
    EXPECT_EQ(p.x, two.placements[c].x);
    EXPECT_EQ(p.y, two.placements[c].y);
    EXPECT_EQ(p.quarter_turns, two.placements[c].quarter_turns);
    EXPECT_EQ(p.angle, two.placements[c].angle);
  }
  EXPECT_EQ(one.texels_per_meter, two.texels_per_meter);
  EXPECT_FALSE(one.boxes);
  EXPECT_GT(turned, 0);
  EXPECT_EQ(not_ccw, 0);
}

TEST(UvRasterPackTest, AFoldedChartIsRasterizedFaceByFace) {
  // A unit square (two faces) with a third face folded back over it: its
  // boundary 0-1-4-2-3 leaves out the notch 1-4-2, which the square's
  // face 0-1-2 covers. Small squares that would nest in that notch must
  // not: the folded chart is rasterized face by face.
  std::vector<FlatChart> charts;
  FlatChart folded;
  folded.faces = {0, 1, 2};
  folded.vertices = {0, 1, 2, 3, 4};
  folded.uv_m = {0, 0, 1, 0, 1, 1, 0, 1, 0.4, 0.5};
  folded.corners = {0, 1, 2, 0, 2, 3, 1, 4, 2};  // the last one clockwise
  folded.width_m = folded.height_m = 1;
  charts.push_back(std::move(folded));
  for (int i = 0; i < 12; ++i) {
    FlatChart square;
    square.faces = {0, 1};
    square.vertices = {0, 1, 2, 3};
    square.uv_m = {0, 0, 0.12, 0, 0.12, 0.12, 0, 0.12};
    square.corners = {0, 1, 2, 0, 2, 3};
    square.width_m = square.height_m = 0.12;
    charts.push_back(std::move(square));
  }
  ExpectValidRasterPacking(charts, 128, 2);
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
