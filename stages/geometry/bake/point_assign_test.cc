#include "stages/geometry/bake/point_assign.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>

namespace pb {
namespace {

// A mesh from corner positions, uvs and triangles.
Mesh MakeMesh(std::vector<float> positions, std::vector<float> uvs, std::vector<uint32_t> indices) {
  Mesh mesh;
  mesh.positions = std::move(positions);
  mesh.uvs = std::move(uvs);
  mesh.indices = std::move(indices);
  return mesh;
}

// The unit square in z = `z`, uv = xy: face 0 = (0,1,2) holds x >= y,
// face 1 = (0,2,3) holds y >= x. Normal +z.
Mesh UnitSquare(float z = 0) {
  return MakeMesh({0, 0, z, 1, 0, z, 1, 1, z, 0, 1, z}, {0, 0, 1, 0, 1, 1, 0, 1}, {0, 1, 2, 0, 2, 3});
}

// Appends a point; normal and color only when the cloud already has them or
// when it is the first point.
void AddPoint(PointCloud& cloud, std::array<float, 3> p, std::array<float, 3> n = {0, 0, 1},
              std::array<uint8_t, 3> c = {10, 20, 30}) {
  const bool first = cloud.empty();
  cloud.positions.insert(cloud.positions.end(), p.begin(), p.end());
  if (first || cloud.has_normals()) cloud.normals.insert(cloud.normals.end(), n.begin(), n.end());
  if (first || cloud.has_colors()) cloud.colors.insert(cloud.colors.end(), c.begin(), c.end());
}

struct Assigned {
  uint32_t face;
  float s, t;
};

// Every assigned point with its face, in output order.
std::vector<Assigned> Flatten(const MappedPoints& mapped) {
  std::vector<Assigned> out;
  for (size_t f = 0; f + 1 < mapped.face_begin.size(); ++f)
    for (uint64_t i = mapped.face_begin[f]; i < mapped.face_begin[f + 1]; ++i)
      out.push_back({uint32_t(f), mapped.st[2 * i], mapped.st[2 * i + 1]});
  return out;
}

AssignOptions Options(double max_distance_m, double max_angle_deg = 90, int size = 64) {
  AssignOptions options;
  options.max_distance_m = max_distance_m;
  options.max_angle_deg = max_angle_deg;
  options.size = size;
  return options;
}

TEST(PointAssignTest, PlaneOfTwoTrianglesExactFaceAndTexel) {
  PointCloud cloud;
  AddPoint(cloud, {0.75f, 0.25f, 0.003f});   // above face 0
  AddPoint(cloud, {0.25f, 0.625f, -0.002f});  // below face 1
  AddPoint(cloud, {1.002f, 0.5f, 0.0f});      // just past face 0's right edge
  AssignReport report;
  auto mapped = AssignPointsToFaces(UnitSquare(), std::move(cloud), Options(0.01), &report);
  ASSERT_TRUE(mapped.ok()) << mapped.status().message();
  EXPECT_EQ(report.points, 3u);
  EXPECT_EQ(report.assigned, 3u);
  EXPECT_EQ(report.faces_with_points, 2u);
  EXPECT_NEAR(report.mean_distance_m, (0.003 + 0.002 + 0.002) / 3, 1e-6);
  const auto points = Flatten(*mapped);
  ASSERT_EQ(points.size(), 3u);
  // Face 0 sorted by s: (48, 16) then the edge point (64, 32).
  EXPECT_EQ(points[0].face, 0u);
  EXPECT_NEAR(points[0].s, 0.75 * 64, 1e-4);
  EXPECT_NEAR(points[0].t, (1 - 0.25) * 64, 1e-4);
  EXPECT_EQ(points[1].face, 0u);
  EXPECT_NEAR(points[1].s, 64, 1e-4);
  EXPECT_NEAR(points[1].t, 32, 1e-4);
  EXPECT_EQ(points[2].face, 1u);
  EXPECT_NEAR(points[2].s, 0.25 * 64, 1e-4);
  EXPECT_NEAR(points[2].t, (1 - 0.625) * 64, 1e-4);
  ASSERT_EQ(mapped->colors.size(), 9u);
  ASSERT_EQ(mapped->normals.size(), 9u);
  EXPECT_EQ(mapped->colors[0], 10);
  EXPECT_EQ(mapped->normals[2], 1.0f);
}

TEST(PointAssignTest, PointsBeyondMaxDistanceAreDropped) {
  PointCloud cloud;
  AddPoint(cloud, {0.5f, 0.2f, 0.02f}, {0, 0, 1}, {1, 1, 1});   // 2 cm above
  AddPoint(cloud, {0.5f, 0.2f, 0.009f}, {0, 0, 1}, {2, 2, 2});  // 9 mm above
  AddPoint(cloud, {1.011f, 0.5f, 0.0f}, {0, 0, 1}, {3, 3, 3});  // 11 mm past the edge
  AddPoint(cloud, {5.0f, 5.0f, 5.0f}, {0, 0, 1}, {4, 4, 4});    // outside the grid
  AssignReport report;
  auto mapped = AssignPointsToFaces(UnitSquare(), std::move(cloud), Options(0.01), &report);
  ASSERT_TRUE(mapped.ok());
  EXPECT_EQ(report.assigned, 1u);
  EXPECT_EQ(report.too_far, 3u);
  EXPECT_EQ(report.wrong_angle, 0u);
  ASSERT_EQ(mapped->size(), 1u);
  ASSERT_EQ(mapped->colors.size(), 3u);
  EXPECT_EQ(mapped->colors[0], 2);  // the kept point's own color
  EXPECT_EQ(mapped->normals.size(), 3u);
}

TEST(PointAssignTest, AngleThreshold) {
  const double rad = 100 * std::numbers::pi / 180;
  const std::array<float, 3> normal = {float(std::sin(rad)), 0, float(std::cos(rad))};  // 100 deg off +z
  for (double max_angle : {120.0, 90.0, 45.0}) {
    PointCloud cloud;
    AddPoint(cloud, {0.7f, 0.2f, 0.001f}, normal);
    AddPoint(cloud, {0.3f, 0.6f, 0.001f}, {0, 0, 1});
    AssignReport report;
    auto mapped = AssignPointsToFaces(UnitSquare(), std::move(cloud), Options(0.01, max_angle), &report);
    ASSERT_TRUE(mapped.ok());
    const bool kept = max_angle > 100;
    EXPECT_EQ(report.assigned, kept ? 2u : 1u) << max_angle;
    EXPECT_EQ(report.wrong_angle, kept ? 0u : 1u) << max_angle;
    EXPECT_EQ(report.too_far, 0u);
    EXPECT_EQ(mapped->face_begin[1], kept ? 1u : 0u) << max_angle;  // face 0's count
  }
}

TEST(PointAssignTest, WrongAngleFaceIsSkippedForAFartherGoodOne) {
  // Two planes: z = 0 facing +z, z = 0.01 facing -z (reversed winding). A
  // point at z = 0.006 with normal +z is nearer the upper plane but goes to
  // the lower one.
  Mesh mesh = MakeMesh({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 0, 0.01f, 1, 1, 0.01f, 1, 0, 0.01f},
                       {0, 0, 1, 0, 1, 1, 0, 0, 1, 1, 1, 0}, {0, 1, 2, 3, 4, 5});
  PointCloud cloud;
  AddPoint(cloud, {0.8f, 0.2f, 0.006f});
  AssignReport report;
  auto mapped = AssignPointsToFaces(mesh, std::move(cloud), Options(0.01, 90), &report);
  ASSERT_TRUE(mapped.ok());
  ASSERT_EQ(report.assigned, 1u);
  EXPECT_EQ(mapped->face_begin[1], 1u);  // face 0
  // Without the angle test the nearer face 1 wins.
  PointCloud again;
  AddPoint(again, {0.8f, 0.2f, 0.006f});
  mapped = AssignPointsToFaces(mesh, std::move(again), Options(0.01, 180), &report);
  ASSERT_TRUE(mapped.ok());
  EXPECT_EQ(mapped->face_begin[1], 0u);
  EXPECT_EQ(mapped->face_begin[2], 1u);
}

TEST(PointAssignTest, NearestOfTwoParallelPlanes) {
  // Faces 0, 1 at z = 0 (uv in the left half), faces 2, 3 at z = 0.01 (right
  // half).
  Mesh mesh = MakeMesh({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 0.01f, 1, 0, 0.01f, 1, 1, 0.01f, 0, 1, 0.01f},
                       {0, 0, 0.5f, 0, 0.5f, 1, 0, 1, 0.5f, 0, 1, 0, 1, 1, 0.5f, 1},
                       {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7});
  PointCloud cloud;
  AddPoint(cloud, {0.8f, 0.2f, 0.007f});  // nearer the upper plane: face 2
  AddPoint(cloud, {0.2f, 0.8f, 0.003f});  // nearer the lower plane: face 1
  auto mapped = AssignPointsToFaces(mesh, std::move(cloud), Options(0.02), nullptr);
  ASSERT_TRUE(mapped.ok());
  const auto points = Flatten(*mapped);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[0].face, 1u);
  EXPECT_NEAR(points[0].s, 0.1 * 64, 1e-4);
  EXPECT_NEAR(points[0].t, 0.2 * 64, 1e-4);
  EXPECT_EQ(points[1].face, 2u);
  EXPECT_NEAR(points[1].s, 0.9 * 64, 1e-4);
  EXPECT_NEAR(points[1].t, 0.8 * 64, 1e-4);
}

TEST(PointAssignTest, TieGoesToTheLowerFaceIndex) {
  // Vertices 0-2 and 6-8 are the same triangle with different uvs (left and
  // right half of the atlas); 3-5 a far triangle.
  const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5, 6, 5, 5, 5, 6, 5, 0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::vector<float> uvs = {0, 0, 0.5f, 0, 0, 0.5f, 0.5f, 0.5f, 1, 0.5f, 0.5f, 1, 0.5f, 0, 1, 0, 0.5f, 0.5f};
  for (bool left_first : {true, false}) {
    const Mesh mesh = MakeMesh(positions, uvs,
                               left_first ? std::vector<uint32_t>{3, 4, 5, 0, 1, 2, 6, 7, 8}
                                          : std::vector<uint32_t>{3, 4, 5, 6, 7, 8, 0, 1, 2});
    PointCloud cloud;
    AddPoint(cloud, {0.25f, 0.25f, 0.001f});
    auto mapped = AssignPointsToFaces(mesh, std::move(cloud), Options(0.01), nullptr);
    ASSERT_TRUE(mapped.ok());
    const auto points = Flatten(*mapped);
    ASSERT_EQ(points.size(), 1u);
    EXPECT_EQ(points[0].face, 1u);
    EXPECT_NEAR(points[0].s, (left_first ? 0.125 : 0.625) * 64, 1e-4);
  }
  // On the shared diagonal of the unit square both faces are at the same
  // distance: face 0 wins.
  PointCloud diagonal;
  AddPoint(diagonal, {0.5f, 0.5f, 0.001f});
  auto mapped = AssignPointsToFaces(UnitSquare(), std::move(diagonal), Options(0.01), nullptr);
  ASSERT_TRUE(mapped.ok());
  EXPECT_EQ(mapped->face_begin[1], 1u);
}

TEST(PointAssignTest, DegenerateFaceIsNeverChosen) {
  // Face 0 is a zero-area sliver 1 mm above the point's foot; face 1 the
  // real triangle 3 mm below the point.
  Mesh mesh = MakeMesh({0, 0, 0.004f, 1, 0, 0.004f, 0.5f, 0, 0.004f, 0, 0, 0, 1, 0, 0, 0, 1, 0},
                       {0, 0, 1, 0, 0.5f, 0, 0, 0, 1, 0, 0, 1}, {0, 1, 2, 3, 4, 5});
  PointCloud cloud;
  AddPoint(cloud, {0.5f, 0.0f, 0.003f});
  AssignReport report;
  auto mapped = AssignPointsToFaces(mesh, std::move(cloud), Options(0.01, 180), &report);
  ASSERT_TRUE(mapped.ok());
  EXPECT_EQ(report.assigned, 1u);
  EXPECT_EQ(mapped->face_begin[1], 0u);
  EXPECT_EQ(mapped->face_begin[2], 1u);
}

TEST(PointAssignTest, CloudOriginDifferentFromMeshOrigin) {
  Mesh mesh = UnitSquare();
  mesh.origin = {500000.0, 4000000.0, 100.0};
  PointCloud local, shifted;
  shifted.origin = {500003.25, 3999998.5, 101.0};
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0, 1), height(-0.004f, 0.004f);
  for (int i = 0; i < 200; ++i) {
    const float x = unit(rng), y = unit(rng), z = height(rng);
    AddPoint(local, {x, y, z});
    AddPoint(shifted, {x - 3.25f, y + 1.5f, z - 1.0f});
  }
  local.origin = mesh.origin;
  auto a = AssignPointsToFaces(mesh, std::move(local), Options(0.01), nullptr);
  auto b = AssignPointsToFaces(mesh, std::move(shifted), Options(0.01), nullptr);
  ASSERT_TRUE(a.ok());
  ASSERT_TRUE(b.ok());
  ASSERT_EQ(a->face_begin, b->face_begin);
  ASSERT_EQ(a->size(), 200u);
  // Same points up to the float rounding of the shifted coordinates, so
  // compare as sets: each point of a has one within 1e-4 texel in b.
  for (size_t f = 0; f < 2; ++f)
    for (uint64_t i = a->face_begin[f]; i < a->face_begin[f + 1]; ++i) {
      double nearest = 1e9;
      for (uint64_t j = b->face_begin[f]; j < b->face_begin[f + 1]; ++j)
        nearest = std::min(nearest, std::hypot(double(a->st[2 * i]) - b->st[2 * j], double(a->st[2 * i + 1]) - b->st[2 * j + 1]));
      EXPECT_LT(nearest, 1e-4);
    }
}

TEST(PointAssignTest, WithoutNormalsOrColors) {
  PointCloud cloud;
  for (float x : {0.2f, 0.6f}) cloud.positions.insert(cloud.positions.end(), {x, 0.1f, 0.001f});
  auto mapped = AssignPointsToFaces(UnitSquare(), std::move(cloud), Options(0.01, 0), nullptr);
  ASSERT_TRUE(mapped.ok());
  EXPECT_EQ(mapped->size(), 2u);  // no angle test without normals, even at 0 degrees
  EXPECT_TRUE(mapped->normals.empty());
  EXPECT_TRUE(mapped->colors.empty());
  EXPECT_NEAR(mapped->st[0], 0.2 * 64, 1e-4);
  EXPECT_NEAR(mapped->st[2], 0.6 * 64, 1e-4);

  PointCloud colors_only;
  colors_only.positions = {0.2f, 0.1f, 0.001f};
  colors_only.colors = {1, 2, 3};
  mapped = AssignPointsToFaces(UnitSquare(), std::move(colors_only), Options(0.01), nullptr);
  ASSERT_TRUE(mapped.ok());
  EXPECT_TRUE(mapped->normals.empty());
  EXPECT_EQ(mapped->colors, (std::vector<uint8_t>{1, 2, 3}));
}

TEST(PointAssignTest, NonFinitePointsAreDroppedAndCounted) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  PointCloud cloud;
  AddPoint(cloud, {0.5f, 0.2f, 0.001f});
  AddPoint(cloud, {nan, 0.2f, 0.001f});
  AddPoint(cloud, {0.5f, std::numeric_limits<float>::infinity(), 0.001f});
  AddPoint(cloud, {0.5f, 0.3f, 0.001f}, {nan, nan, nan});  // normal unknown: no angle test
  AssignReport report;
  auto mapped = AssignPointsToFaces(UnitSquare(), std::move(cloud), Options(0.01, 45), &report);
  ASSERT_TRUE(mapped.ok());
  EXPECT_EQ(report.non_finite, 2u);
  EXPECT_EQ(report.assigned, 2u);
  EXPECT_EQ(report.too_far + report.wrong_angle, 0u);
  EXPECT_EQ(mapped->size(), 2u);
}

TEST(PointAssignTest, BadOptionsAndInputs) {
  auto run = [](const Mesh& mesh, AssignOptions options) {
    PointCloud cloud;
    AddPoint(cloud, {0.5f, 0.2f, 0.0f});
    return AssignPointsToFaces(mesh, std::move(cloud), options, nullptr).status();
  };
  const Mesh square = UnitSquare();
  for (double d : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    const Status s = run(square, Options(d));
    EXPECT_EQ(s.code(), Status::Code::kInvalid);
    EXPECT_NE(s.message().find("max_distance_m"), std::string::npos) << s.message();
  }
  for (double a : {-1.0, 181.0, std::nan("")}) {
    const Status s = run(square, Options(0.01, a));
    EXPECT_NE(s.message().find("max_angle_deg"), std::string::npos) << s.message();
  }
  const Status size = run(square, Options(0.01, 90, 0));
  EXPECT_NE(size.message().find("size"), std::string::npos) << size.message();
  Mesh no_uvs = square;
  no_uvs.uvs.clear();
  EXPECT_NE(run(no_uvs, Options(0.01)).message().find("no uvs"), std::string::npos);
  Mesh bad_index = square;
  bad_index.indices[4] = 9;
  EXPECT_EQ(run(bad_index, Options(0.01)).code(), Status::Code::kInvalid);
  Mesh nan_uv = square;
  nan_uv.uvs[3] = std::nanf("");
  EXPECT_NE(run(nan_uv, Options(0.01)).message().find("vertex 1"), std::string::npos);
  PointCloud short_normals;
  AddPoint(short_normals, {0.5f, 0.2f, 0.0f});
  short_normals.normals.pop_back();
  EXPECT_EQ(AssignPointsToFaces(square, std::move(short_normals), Options(0.01), nullptr).status().code(),
            Status::Code::kInvalid);
}

// A bumpy height field of (cells x cells) quads plus a few loose triangles,
// uvs spread over the atlas.
Mesh BumpyMesh(int cells, std::mt19937& rng) {
  std::uniform_real_distribution<float> bump(-0.02f, 0.02f);
  Mesh mesh;
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i) {
      mesh.positions.insert(mesh.positions.end(), {i * 0.1f, j * 0.1f, bump(rng)});
      mesh.uvs.insert(mesh.uvs.end(), {float(i) / cells, float(j) / cells});
    }
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      const uint32_t v = uint32_t(j * (cells + 1) + i);
      mesh.indices.insert(mesh.indices.end(), {v, v + 1, v + uint32_t(cells) + 2, v, v + uint32_t(cells) + 2,
                                               v + uint32_t(cells) + 1});
    }
  std::uniform_real_distribution<float> any(0, 0.1f * cells), uv(0, 1);
  for (int t = 0; t < 40; ++t) {
    const uint32_t first = uint32_t(mesh.vertex_count());
    const float x = any(rng), y = any(rng);
    for (int c = 0; c < 3; ++c) {
      mesh.positions.insert(mesh.positions.end(), {x + 0.1f * uv(rng), y + 0.1f * uv(rng), 0.05f * uv(rng)});
      mesh.uvs.insert(mesh.uvs.end(), {uv(rng), uv(rng)});
    }
    mesh.indices.insert(mesh.indices.end(), {first, first + 1, first + 2});
  }
  return mesh;
}

PointCloud RandomCloud(size_t count, float extent, std::mt19937& rng) {
  std::uniform_real_distribution<float> xy(-0.05f, extent + 0.05f), z(-0.04f, 0.06f), n(-1, 1);
  std::uniform_int_distribution<int> byte(0, 255);
  PointCloud cloud;
  for (size_t i = 0; i < count; ++i) {
    AddPoint(cloud, {xy(rng), xy(rng), z(rng)}, {0.3f * n(rng), 0.3f * n(rng), n(rng)},
             {uint8_t(byte(rng)), uint8_t(byte(rng)), uint8_t(byte(rng))});
  }
  return cloud;
}

// Brute force reference, written independently: closest point as the
// projection on the plane when inside, else the nearest of the three edges.
struct Reference {
  int64_t face = -1;
  double second_gap = 1;  // distance to the runner-up minus the best
  double s = 0, t = 0;
};
Reference BruteForce(const Mesh& mesh, const std::array<double, 3>& p, const std::array<double, 3>& normal,
                     double max_d, double max_angle_deg, int size) {
  using V = std::array<double, 3>;
  auto sub = [](V a, V b) { return V{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  auto dot = [](V a, V b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  auto cross = [](V a, V b) { return V{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; };
  Reference ref;
  double best = 1e300, second = 1e300;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    V c[3];
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) c[k][j] = mesh.positions[3 * mesh.indices[3 * f + k] + j];
    const V n = cross(sub(c[1], c[0]), sub(c[2], c[0]));
    const double area2 = std::sqrt(dot(n, n));
    if (area2 == 0) continue;
    const V un = {n[0] / area2, n[1] / area2, n[2] / area2};
    const double cos_angle = dot(un, normal) / std::sqrt(dot(normal, normal));
    if (cos_angle < std::cos(max_angle_deg * std::numbers::pi / 180)) continue;
    // Barycentrics of the projection.
    const double h = dot(sub(p, c[0]), un);
    const V q = {p[0] - h * un[0], p[1] - h * un[1], p[2] - h * un[2]};
    double bary[3];
    for (int k = 0; k < 3; ++k) bary[k] = dot(cross(sub(c[(k + 2) % 3], c[(k + 1) % 3]), sub(q, c[(k + 1) % 3])), un) / area2;
    double dist;
    double b[3] = {bary[0], bary[1], bary[2]};
    if (bary[0] >= 0 && bary[1] >= 0 && bary[2] >= 0) {
      dist = std::abs(h);
    } else {
      dist = 1e300;
      for (int k = 0; k < 3; ++k) {
        const V e = sub(c[(k + 1) % 3], c[k]);
        const double along = std::clamp(dot(sub(p, c[k]), e) / dot(e, e), 0.0, 1.0);
        const V x = {c[k][0] + along * e[0], c[k][1] + along * e[1], c[k][2] + along * e[2]};
        const V d = sub(p, x);
        const double len = std::sqrt(dot(d, d));
        if (len < dist) {
          dist = len;
          b[k] = 1 - along;
          b[(k + 1) % 3] = along;
          b[(k + 2) % 3] = 0;
        }
      }
    }
    if (dist > max_d) continue;
    if (dist < best) {
      second = best;
      best = dist;
      ref.face = int64_t(f);
      double u = 0, v = 0;
      for (int k = 0; k < 3; ++k) {
        u += b[k] * mesh.uvs[2 * mesh.indices[3 * f + k]];
        v += b[k] * mesh.uvs[2 * mesh.indices[3 * f + k] + 1];
      }
      ref.s = u * size;
      ref.t = (1 - v) * size;
    } else {
      second = std::min(second, dist);
    }
  }
  ref.second_gap = second - best;
  return ref;
}

TEST(PointAssignTest, MatchesBruteForceOnARandomCase) {
  std::mt19937 rng(12345);
  const Mesh mesh = BumpyMesh(12, rng);  // 288 + 40 faces
  ASSERT_EQ(mesh.face_count(), 328u);
  const PointCloud cloud = RandomCloud(5000, 1.2f, rng);
  const double max_d = 0.03, max_angle = 60;
  const int size = 1024;
  AssignReport report;
  PointCloud copy = cloud;
  auto mapped = AssignPointsToFaces(mesh, std::move(copy), Options(max_d, max_angle, size), &report);
  ASSERT_TRUE(mapped.ok());
  // For each expected assignment, find the point in its face's slice.
  size_t expected_assigned = 0, compared = 0;
  std::vector<uint64_t> used(mapped->size(), 0);
  for (size_t i = 0; i < cloud.size(); ++i) {
    const std::array<double, 3> p = {cloud.positions[3 * i], cloud.positions[3 * i + 1], cloud.positions[3 * i + 2]};
    const std::array<double, 3> n = {cloud.normals[3 * i], cloud.normals[3 * i + 1], cloud.normals[3 * i + 2]};
    const Reference ref = BruteForce(mesh, p, n, max_d, max_angle, size);
    if (ref.face < 0) continue;
    ++expected_assigned;
    if (ref.second_gap < 1e-7) continue;  // a near tie: either answer is right
    const auto f = size_t(ref.face);
    bool found = false;
    for (uint64_t j = mapped->face_begin[f]; j < mapped->face_begin[f + 1] && !found; ++j) {
      if (std::abs(mapped->st[2 * j] - ref.s) < 2e-3 && std::abs(mapped->st[2 * j + 1] - ref.t) < 2e-3 &&
          std::equal(&mapped->colors[3 * j], &mapped->colors[3 * j] + 3, &cloud.colors[3 * i])) {
        found = true;
        ++used[j];
      }
    }
    EXPECT_TRUE(found) << "point " << i << " expected on face " << f << " at (" << ref.s << ", " << ref.t << ")";
    ++compared;
  }
  EXPECT_EQ(report.assigned, expected_assigned);
  EXPECT_GT(compared, 1000u);  // the random case exercises something
  std::printf("brute force: %zu compared, %zu assigned, %zu too far, %zu wrong angle\n", compared, report.assigned,
              report.too_far, report.wrong_angle);
  EXPECT_GT(report.too_far, 100u);
  EXPECT_GT(report.wrong_angle, 100u);
  EXPECT_EQ(report.points, report.assigned + report.too_far + report.wrong_angle + report.non_finite);
}

TEST(PointAssignTest, FaceBeginConsistentAndSortedWithinFaces) {
  std::mt19937 rng(99);
  const Mesh mesh = BumpyMesh(10, rng);
  PointCloud cloud = RandomCloud(20000, 1.0f, rng);
  AssignReport report;
  auto mapped = AssignPointsToFaces(mesh, std::move(cloud), Options(0.03, 120, 512), &report);
  ASSERT_TRUE(mapped.ok());
  ASSERT_EQ(mapped->face_begin.size(), mesh.face_count() + 1);
  EXPECT_EQ(mapped->face_begin.front(), 0u);
  EXPECT_EQ(mapped->face_begin.back(), report.assigned);
  EXPECT_EQ(mapped->size(), report.assigned);
  EXPECT_EQ(mapped->colors.size(), 3 * report.assigned);
  EXPECT_EQ(mapped->normals.size(), 3 * report.assigned);
  size_t nonempty = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    ASSERT_LE(mapped->face_begin[f], mapped->face_begin[f + 1]);
    nonempty += mapped->face_begin[f] < mapped->face_begin[f + 1];
    // Each point lies in its face's uv triangle (texel space).
    double uv[3][2];
    for (int k = 0; k < 3; ++k) {
      uv[k][0] = mesh.uvs[2 * mesh.indices[3 * f + k]] * 512.0;
      uv[k][1] = (1 - mesh.uvs[2 * mesh.indices[3 * f + k] + 1]) * 512.0;
    }
    const double area = (uv[1][0] - uv[0][0]) * (uv[2][1] - uv[0][1]) - (uv[2][0] - uv[0][0]) * (uv[1][1] - uv[0][1]);
    for (uint64_t i = mapped->face_begin[f]; i < mapped->face_begin[f + 1]; ++i) {
      const double s = mapped->st[2 * i], t = mapped->st[2 * i + 1];
      for (int k = 0; k < 3; ++k) {
        const double* a = uv[k];
        const double* b = uv[(k + 1) % 3];
        const double side = ((b[0] - a[0]) * (t - a[1]) - (s - a[0]) * (b[1] - a[1])) / area;
        EXPECT_GE(side * std::abs(area) / std::hypot(b[0] - a[0], b[1] - a[1]), -1e-3);
      }
      if (i > mapped->face_begin[f]) {
        const float ps = mapped->st[2 * i - 2], pt = mapped->st[2 * i - 1];
        EXPECT_TRUE(ps < s || (ps == s && pt <= t)) << "face " << f;
      }
    }
  }
  EXPECT_EQ(nonempty, report.faces_with_points);
}

TEST(PointAssignTest, ThreadCountDoesNotChangeTheOutput) {
  std::mt19937 rng(4);
  const Mesh mesh = BumpyMesh(20, rng);
  const PointCloud cloud = RandomCloud(300000, 2.0f, rng);
  MappedPoints results[3];
  AssignReport reports[3];
  const int threads[3] = {1, 2, 0};
  for (int r = 0; r < 3; ++r) {
    PointCloud copy = cloud;
    AssignOptions options = Options(0.03, 100, 2048);
    options.threads = threads[r];
    auto mapped = AssignPointsToFaces(mesh, std::move(copy), options, &reports[r]);
    ASSERT_TRUE(mapped.ok());
    results[r] = std::move(*mapped);
  }
  ASSERT_GT(results[0].size(), 10000u);
  for (int r = 1; r < 3; ++r) {
    EXPECT_EQ(results[0].face_begin, results[r].face_begin);
    EXPECT_EQ(results[0].st, results[r].st);
    EXPECT_EQ(results[0].colors, results[r].colors);
    EXPECT_EQ(results[0].normals, results[r].normals);
    EXPECT_EQ(reports[0].mean_distance_m, reports[r].mean_distance_m);
    EXPECT_EQ(reports[0].wrong_angle, reports[r].wrong_angle);
  }
}

// The order of the points in the cloud does not matter either: the face a
// point gets may not depend on which face the previous point got (the search
// starts there; a float bound once pruned near-ties order-dependently).
TEST(PointAssignTest, PointOrderDoesNotChangeTheOutput) {
  std::mt19937 rng(11);
  const Mesh mesh = BumpyMesh(24, rng);
  const PointCloud cloud = RandomCloud(200000, 2.0f, rng);
  PointCloud reversed = cloud;
  const size_t n = cloud.size();
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      reversed.positions[3 * i + k] = cloud.positions[3 * (n - 1 - i) + k];
      if (cloud.has_normals()) reversed.normals[3 * i + k] = cloud.normals[3 * (n - 1 - i) + k];
      if (cloud.has_colors()) reversed.colors[3 * i + k] = cloud.colors[3 * (n - 1 - i) + k];
    }
  }
  PointCloud forward = cloud;
  auto a = AssignPointsToFaces(mesh, std::move(forward), Options(0.03, 100, 2048));
  auto b = AssignPointsToFaces(mesh, std::move(reversed), Options(0.03, 100, 2048));
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_GT(a->size(), 10000u);
  EXPECT_EQ(a->face_begin, b->face_begin);
  EXPECT_EQ(a->st, b->st);
  EXPECT_EQ(a->colors, b->colors);
  EXPECT_EQ(a->normals, b->normals);
}

TEST(PointAssignTest, ManyPointsOnOneFaceUseTheInPlaceSort) {
  // More points on one face than the gathered sort takes (2^14): the heap
  // sort path must order them the same way.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0, 1);
  PointCloud cloud;
  for (int i = 0; i < 40000; ++i) {
    const float x = unit(rng), y = unit(rng) * x;  // face 0: y <= x
    AddPoint(cloud, {x, y, 0.001f}, {0, 0, 1}, {uint8_t(i), 0, 0});
  }
  // Duplicated positions with different colors order by color.
  AddPoint(cloud, {0.5f, 0.25f, 0.001f}, {0, 0, 1}, {7, 0, 0});
  AddPoint(cloud, {0.5f, 0.25f, 0.001f}, {0, 0, 1}, {3, 0, 0});
  auto mapped = AssignPointsToFaces(UnitSquare(), std::move(cloud), Options(0.01, 90, 4096), nullptr);
  ASSERT_TRUE(mapped.ok());
  ASSERT_EQ(mapped->face_begin[1], 40002u);
  bool saw_duplicate = false;
  for (size_t i = 1; i < mapped->face_begin[1]; ++i) {
    const float ps = mapped->st[2 * i - 2], pt = mapped->st[2 * i - 1], s = mapped->st[2 * i], t = mapped->st[2 * i + 1];
    ASSERT_TRUE(ps < s || (ps == s && pt <= t)) << i;
    if (ps == s && pt == t) {
      EXPECT_LE(mapped->colors[3 * (i - 1)], mapped->colors[3 * i]);
      saw_duplicate |= mapped->colors[3 * (i - 1)] == 3 && mapped->colors[3 * i] == 7;
    }
  }
  EXPECT_TRUE(saw_duplicate);
}

}  // namespace
}  // namespace pb
