#include "stages/geometry/core/tangents.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace pb {
namespace {

using V3 = std::array<double, 3>;

V3 Tangent(const std::vector<float>& t, size_t v) { return {t[4 * v], t[4 * v + 1], t[4 * v + 2]}; }
V3 Normal(const std::vector<float>& n, size_t v) { return {n[3 * v], n[3 * v + 1], n[3 * v + 2]}; }
double Dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V3 Cross(const V3& a, const V3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

// A unit quad in the plane z = 0, its edges along `x_axis` and `y_axis`
// (unit, orthogonal, in the plane), uv (0,0) (1,0) (1,1) (0,1) at the corners
// 0, x, x+y, y; `mirror_u` flips u.
Mesh Quad(V3 x_axis, V3 y_axis, bool mirror_u) {
  Mesh mesh;
  const double corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (const auto& c : corners) {
    for (int k = 0; k < 3; ++k) {
      mesh.positions.push_back(static_cast<float>(c[0] * x_axis[k] + c[1] * y_axis[k]));
    }
    mesh.normals.insert(mesh.normals.end(), {0, 0, 1});
    mesh.uvs.push_back(static_cast<float>(mirror_u ? 1 - c[0] : c[0]));
    mesh.uvs.push_back(static_cast<float>(c[1]));
  }
  mesh.indices = {0, 1, 2, 0, 2, 3};
  return mesh;
}

TEST(TangentsTest, FlatQuadTangentIsTheDirectionOfPlusU) {
  const double a = 30 * std::numbers::pi / 180;
  const V3 x{std::cos(a), std::sin(a), 0}, y{-std::sin(a), std::cos(a), 0};
  TangentReport report;
  auto tangents = ComputeTangents(Quad(x, y, false), &report);
  ASSERT_TRUE(tangents.ok()) << tangents.status().message();
  for (size_t v = 0; v < 4; ++v) {
    const V3 t = Tangent(*tangents, v);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(t[k], x[k], 1e-6) << v;
    EXPECT_EQ((*tangents)[4 * v + 3], 1.0f);
    // bitangent = w * cross(n, t) is the direction of +v.
    const V3 b = Cross({0, 0, 1}, t);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(b[k], y[k], 1e-6);
  }
  EXPECT_EQ(report.degenerate_uv_faces, 0u);
  EXPECT_EQ(report.fallback_vertices, 0u);
  EXPECT_EQ(report.mirrored_vertices, 0u);
}

TEST(TangentsTest, MirroredUvsGiveNegativeHandedness) {
  const V3 x{1, 0, 0}, y{0, 1, 0};
  TangentReport report;
  auto tangents = ComputeTangents(Quad(x, y, true), &report);
  ASSERT_TRUE(tangents.ok());
  for (size_t v = 0; v < 4; ++v) {
    const V3 t = Tangent(*tangents, v);
    EXPECT_NEAR(t[0], -1, 1e-6);  // +u now runs along -x
    const float w = (*tangents)[4 * v + 3];
    EXPECT_EQ(w, -1.0f);
    const V3 n_cross_t = Cross({0, 0, 1}, t);
    EXPECT_NEAR(w * n_cross_t[1], 1, 1e-6);  // bitangent still along +v = +y
  }
  EXPECT_EQ(report.mirrored_vertices, 4u);
}

TEST(TangentsTest, ShearedUvsGiveTheUDerivativeOrthogonalizedAgainstTheNormal) {
  // u = x + y, v = y: dP/du = +x, dP/dv = (-1, 1, 0).
  Mesh mesh = Quad({1, 0, 0}, {0, 1, 0}, false);
  for (size_t v = 0; v < 4; ++v) mesh.uvs[2 * v] = mesh.positions[3 * v] + mesh.positions[3 * v + 1];
  auto tangents = ComputeTangents(mesh);
  ASSERT_TRUE(tangents.ok());
  for (size_t v = 0; v < 4; ++v) {
    EXPECT_NEAR((*tangents)[4 * v], 1, 1e-6);
    EXPECT_EQ((*tangents)[4 * v + 3], 1.0f);
  }
}

// A cylinder of radius 1 and height 2 around z: `segments` columns (the
// seam duplicated at u = 1), `rings` + 1 rows; u around (counter-clockwise
// seen from +z), v up; outward normals, outward-facing triangles.
Mesh Cylinder(int segments, int rings) {
  Mesh mesh;
  for (int i = 0; i <= rings; ++i) {
    for (int j = 0; j <= segments; ++j) {
      const double angle = 2 * std::numbers::pi * j / segments;
      mesh.positions.insert(mesh.positions.end(), {float(std::cos(angle)), float(std::sin(angle)),
                                                   float(2.0 * i / rings)});
      mesh.uvs.insert(mesh.uvs.end(), {float(double(j) / segments), float(double(i) / rings)});
    }
  }
  const uint32_t row = segments + 1;
  for (int i = 0; i < rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      const uint32_t a = i * row + j, b = a + 1, c = a + row + 1, d = a + row;
      mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
    }
  }
  return mesh;
}

TEST(TangentsTest, CylinderTangentsAreSmoothAndOrthogonalToNormals) {
  const int segments = 32, rings = 4;
  const Mesh mesh = Cylinder(segments, rings);  // no normals: computed
  TangentReport report;
  auto tangents = ComputeTangents(mesh, &report);
  ASSERT_TRUE(tangents.ok());
  const std::vector<float> normals = ComputeVertexNormals(mesh);
  EXPECT_EQ(report.fallback_vertices, 0u);
  EXPECT_EQ(report.mirrored_vertices, 0u);
  const double step = 2 * std::numbers::pi / segments;
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    const V3 t = Tangent(*tangents, v), n = Normal(normals, v);
    EXPECT_NEAR(Dot(t, t), 1, 1e-6);
    EXPECT_NEAR(Dot(t, n), 0, 1e-6) << v;
    EXPECT_EQ((*tangents)[4 * v + 3], 1.0f);
    // +u runs around the axis, horizontally: in the tangent plane that is
    // cross(z, n), at every vertex, the seam columns included.
    V3 around = Cross({0, 0, 1}, n);
    const double length = std::sqrt(Dot(around, around));
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(t[k], around[k] / length, 1e-5) << v;
    // Close to the exact circle tangent (-sin, cos, 0): area-weighted normals
    // tilt by up to a segment's angle / 2 at the seam and / 6 on the
    // top and bottom rings, where the triangulation is one-sided.
    const double angle = std::atan2(mesh.positions[3 * v + 1], mesh.positions[3 * v]);
    const double error = std::acos(std::clamp(Dot(t, {-std::sin(angle), std::cos(angle), 0}), -1.0, 1.0));
    EXPECT_LT(error, step / 2 + 1e-3) << v;
    // Smooth: neighbours around the ring turn by at most one segment's angle.
    if (v % (segments + 1) != size_t(segments)) {
      const double turn = std::acos(std::clamp(Dot(t, Tangent(*tangents, v + 1)), -1.0, 1.0));
      EXPECT_LT(turn, step + 1e-3) << v;
    }
  }
}

TEST(TangentsTest, VertexNormalsAreAreaWeighted) {
  // Two triangles at vertex 0: a large one in z = 0 (normal +z, area 2) and a
  // small one in x = 0 (normal +x, area 0.5).
  Mesh mesh;
  mesh.positions = {0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 1, 0, 1, 0};
  mesh.indices = {0, 1, 2, 0, 4, 3};
  const std::vector<float> normals = ComputeVertexNormals(mesh);
  const double length = std::hypot(2.0, 0.5);
  EXPECT_NEAR(normals[0], 0.5 / length, 1e-6);
  EXPECT_NEAR(normals[1], 0, 1e-6);
  EXPECT_NEAR(normals[2], 2 / length, 1e-6);
  EXPECT_NEAR(normals[3 * 1 + 2], 1, 1e-6);  // vertex 1: only the large one
  EXPECT_NEAR(normals[3 * 3], 1, 1e-6);      // vertex 3: only the small one
}

TEST(TangentsTest, DegenerateUvTrianglesContributeNothingAndVerticesGetAFallbackFrame) {
  Mesh mesh = Quad({1, 0, 0}, {0, 1, 0}, false);
  mesh.positions.insert(mesh.positions.end(), {5, 0, 0, 6, 0, 0, 5, 1, 0});
  mesh.normals.insert(mesh.normals.end(), {0, 0, 1, 0, 0, 1, 0, 0, 1});
  mesh.uvs.insert(mesh.uvs.end(), {0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f});  // zero UV area
  mesh.indices.insert(mesh.indices.end(), {4, 5, 6});
  TangentReport report;
  auto tangents = ComputeTangents(mesh, &report);
  ASSERT_TRUE(tangents.ok());
  EXPECT_EQ(report.degenerate_uv_faces, 1u);
  EXPECT_EQ(report.fallback_vertices, 3u);
  for (size_t v = 0; v < 4; ++v) EXPECT_NEAR((*tangents)[4 * v], 1, 1e-6);  // the quad is unaffected
  for (size_t v = 4; v < 7; ++v) {
    const V3 t = Tangent(*tangents, v);
    EXPECT_NEAR(Dot(t, t), 1, 1e-6);
    EXPECT_NEAR(t[2], 0, 1e-6);  // in the tangent plane of n = +z
    EXPECT_EQ((*tangents)[4 * v + 3], 1.0f);
  }
}

TEST(TangentsTest, ZeroNormalsFallBackToFaceNormals) {
  Mesh mesh = Quad({1, 0, 0}, {0, 1, 0}, false);
  std::fill(mesh.normals.begin(), mesh.normals.begin() + 3, 0.0f);
  auto tangents = ComputeTangents(mesh);
  ASSERT_TRUE(tangents.ok());
  EXPECT_NEAR((*tangents)[0], 1, 1e-6);
  EXPECT_EQ((*tangents)[3], 1.0f);
}

TEST(TangentsTest, MeshWithoutUvsIsAnError) {
  Mesh mesh = Quad({1, 0, 0}, {0, 1, 0}, false);
  mesh.uvs.clear();
  auto tangents = ComputeTangents(mesh);
  ASSERT_FALSE(tangents.ok());
  EXPECT_EQ(tangents.status().code(), Status::Code::kInvalid);
  EXPECT_NE(tangents.status().message().find("no uvs"), std::string::npos);
  mesh = Quad({1, 0, 0}, {0, 1, 0}, false);
  mesh.indices.push_back(9);
  mesh.indices.push_back(0);
  mesh.indices.push_back(1);
  EXPECT_FALSE(ComputeTangents(mesh).ok());
}

}  // namespace
}  // namespace pb
