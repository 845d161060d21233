#include "stages/geometry/mesh/distance.h"
#include "stages/geometry/testing/meshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

namespace pb {
namespace {

double Dist(const Vec3& a, const Vec3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

// Independent reference: the nearest of the plane projection (if it falls
// inside the triangle) and the three edges' closest points.
double BruteForceDistance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  auto segment = [&](const Vec3& s, const Vec3& t) {
    Vec3 d = {t[0] - s[0], t[1] - s[1], t[2] - s[2]};
    const double len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    double u = ((p[0] - s[0]) * d[0] + (p[1] - s[1]) * d[1] + (p[2] - s[2]) * d[2]) / len2;
    u = std::clamp(u, 0.0, 1.0);
    return Dist(p, {s[0] + u * d[0], s[1] + u * d[1], s[2] + u * d[2]});
  };
  double best = std::min({segment(a, b), segment(b, c), segment(c, a)});
  const Vec3 u = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const Vec3 v = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const Vec3 w = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
  auto dot = [](const Vec3& x, const Vec3& y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; };
  const double uu = dot(u, u), uv = dot(u, v), vv = dot(v, v), wu = dot(w, u), wv = dot(w, v);
  const double det = uu * vv - uv * uv;
  const double s = (vv * wu - uv * wv) / det, t = (uu * wv - uv * wu) / det;
  if (s >= 0 && t >= 0 && s + t <= 1) {
    best = std::min(best, Dist(p, {a[0] + s * u[0] + t * v[0], a[1] + s * u[1] + t * v[1],
                                   a[2] + s * u[2] + t * v[2]}));
  }
  return best;
}

// A sphere of `radius` around the origin: testing::Icosphere scaled, faces
// outward, positions only.
Mesh Sphere(double radius, int levels) {
  Mesh mesh = testing::Icosphere(levels);
  for (float& p : mesh.positions) p = static_cast<float>(radius * p);
  mesh.normals.clear();
  mesh.colors.clear();
  return mesh;
}

TEST(MeshDistanceTest, ClosestPointMatchesBruteForce) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 20000; ++i) {
    const Vec3 a = {u(rng), u(rng), u(rng)}, b = {u(rng), u(rng), u(rng)},
               c = {u(rng), u(rng), u(rng)};
    const Vec3 p = {2 * u(rng), 2 * u(rng), 2 * u(rng)};
    const Vec3 q = ClosestPointOnTriangle(p, a, b, c);
    ASSERT_NEAR(Dist(p, q), BruteForceDistance(p, a, b, c), 1e-9) << "case " << i;
  }
  // Points on vertices, edges and the interior are their own closest point.
  const Vec3 a = {0, 0, 0}, b = {1, 0, 0}, c = {0, 1, 0};
  for (const Vec3& p : {a, b, c, Vec3{0.5, 0, 0}, Vec3{0.25, 0.25, 0}}) {
    EXPECT_NEAR(Dist(p, ClosestPointOnTriangle(p, a, b, c)), 0, 1e-15);
  }
  // Degenerate triangles: a segment and a point.
  EXPECT_NEAR(Dist({0.5, 1, 0}, ClosestPointOnTriangle({0.5, 1, 0}, a, b, {2, 0, 0})), 1, 1e-12);
  EXPECT_NEAR(Dist({0, 0, 3}, ClosestPointOnTriangle({0, 0, 3}, a, a, a)), 3, 1e-12);
}

// Both engines of TriangleBvh (distance.h) against brute force, and against
// each other bit for bit.
class TriangleBvhEngineTest : public ::testing::TestWithParam<TriangleBvh::Engine> {};

TEST_P(TriangleBvhEngineTest, MatchesBruteForceOverAllTriangles) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-5, 5), small(-0.3, 0.3);
  Mesh soup;
  soup.origin = {1000, -2000, 50};
  for (int t = 0; t < 2000; ++t) {
    const Vec3 center = {u(rng), u(rng), u(rng)};
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < 3; ++a)
        soup.positions.push_back(static_cast<float>(center[a] + small(rng)));
      soup.indices.push_back(static_cast<uint32_t>(soup.indices.size()));
    }
  }
  const TriangleBvh bvh(soup, GetParam());
  ASSERT_EQ(bvh.engine(), GetParam());
  const TriangleBvh other(soup, GetParam() == TriangleBvh::Engine::kEmbree
                                    ? TriangleBvh::Engine::kBuiltin
                                    : TriangleBvh::Engine::kEmbree);
  for (int i = 0; i < 300; ++i) {
    const Vec3 local = {1.3 * u(rng), 1.3 * u(rng), 1.3 * u(rng)};
    double best = 1e300;
    for (size_t t = 0; t < soup.face_count(); ++t) {
      Vec3 corner[3];
      for (int k = 0; k < 3; ++k) {
        for (int a = 0; a < 3; ++a) corner[k][a] = soup.positions[9 * t + 3 * k + a];
      }
      best = std::min(best, BruteForceDistance(local, corner[0], corner[1], corner[2]));
    }
    const Vec3 absolute = {local[0] + 1000, local[1] - 2000, local[2] + 50};
    ASSERT_NEAR(bvh.Distance(absolute), best, 1e-9) << "query " << i;
    // Nearest names the face: its own distance is the best, the closest
    // point is in absolute coordinates.
    const TriangleBvh::Hit hit = bvh.Nearest(absolute);
    ASSERT_LT(hit.face, soup.face_count());
    Vec3 corner[3];
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < 3; ++a) corner[k][a] = soup.positions[9 * hit.face + 3 * k + a];
    }
    EXPECT_NEAR(BruteForceDistance(local, corner[0], corner[1], corner[2]), best, 1e-9);
    EXPECT_NEAR(std::sqrt(hit.squared_distance_m2), best, 1e-9);
    EXPECT_NEAR(Dist(hit.closest, absolute), best, 1e-9);
    // Any hint (the answer, a random face, none) gives the same hit, bit for bit.
    for (const uint32_t hint : {hit.face, static_cast<uint32_t>(rng() % soup.face_count()),
                                static_cast<uint32_t>(soup.face_count() - 1 - hit.face),
                                UINT32_MAX}) {
      const TriangleBvh::Hit hinted = bvh.Nearest(absolute, hint);
      ASSERT_EQ(hinted.face, hit.face) << "query " << i << ", hint " << hint;
      ASSERT_EQ(hinted.squared_distance_m2, hit.squared_distance_m2);
      ASSERT_EQ(hinted.closest, hit.closest);
      const TriangleBvh::Hit theirs = other.Nearest(absolute, hint);
      ASSERT_EQ(theirs.face, hit.face) << "query " << i << ", hint " << hint;
      ASSERT_EQ(theirs.squared_distance_m2, hit.squared_distance_m2);
      ASSERT_EQ(theirs.closest, hit.closest);
    }
  }
  EXPECT_EQ(TriangleBvh(Mesh{}, GetParam()).Nearest({0, 0, 0}).face, UINT32_MAX);
  EXPECT_EQ(TriangleBvh(Mesh{}, GetParam()).Nearest({0, 0, 0}, 0).face, UINT32_MAX);
}

// Ties go to the lowest face index: two copies of one triangle.
TEST(MeshDistanceTest, NearestBreaksTiesByFaceIndex) {
  Mesh mesh;
  for (int copy = 0; copy < 6; ++copy) {
    mesh.positions.insert(mesh.positions.end(), {0, 0, 0, 1, 0, 0, 0, 1, 0});
    for (int k = 0; k < 3; ++k) mesh.indices.push_back(static_cast<uint32_t>(3 * copy + k));
  }
  const TriangleBvh bvh(mesh);
  EXPECT_EQ(bvh.Nearest({0.2, 0.2, 1}).face, 0u);
  EXPECT_EQ(bvh.Nearest({-3, 5, -1}).face, 0u);
  // A hint at an equally near copy still gives the lowest.
  EXPECT_EQ(bvh.Nearest({0.2, 0.2, 1}, 5).face, 0u);
  EXPECT_EQ(bvh.Nearest({-3, 5, -1}, 3).face, 0u);
}

// Ties go to the lowest face index: two copies of one triangle.
TEST_P(TriangleBvhEngineTest, NearestBreaksTiesByFaceIndex) {
  Mesh mesh;
  for (int copy = 0; copy < 6; ++copy) {
    mesh.positions.insert(mesh.positions.end(), {0, 0, 0, 1, 0, 0, 0, 1, 0});
    for (int k = 0; k < 3; ++k) mesh.indices.push_back(static_cast<uint32_t>(3 * copy + k));
  }
  const TriangleBvh bvh(mesh, GetParam());
  EXPECT_EQ(bvh.Nearest({0.2, 0.2, 1}).face, 0u);
  EXPECT_EQ(bvh.Nearest({-3, 5, -1}).face, 0u);
  // A hint at an equally near copy still gives the lowest.
  EXPECT_EQ(bvh.Nearest({0.2, 0.2, 1}, 5).face, 0u);
  EXPECT_EQ(bvh.Nearest({-3, 5, -1}, 3).face, 0u);
}

// Queries far from the mesh, the mesh far from its origin, a triangle
// without area: the same answers from both engines.
TEST(MeshDistanceTest, EnginesAgreeFarAwayAndOnDegenerateTriangles) {
  Mesh mesh = Sphere(2, 2);
  mesh.origin = {-3e5, 4e6, 120};
  const uint32_t base = static_cast<uint32_t>(mesh.vertex_count());
  mesh.positions.insert(mesh.positions.end(), {3, 0, 0, 4, 0, 0, 5, 0, 0});  // a segment
  mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2});
  const TriangleBvh embree(mesh, TriangleBvh::Engine::kEmbree);
  const TriangleBvh builtin(mesh, TriangleBvh::Engine::kBuiltin);
  ASSERT_EQ(embree.engine(), TriangleBvh::Engine::kEmbree);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 500; ++i) {
    const double scale = i % 5 == 0 ? 1e4 : (i % 5 == 1 ? 0.01 : 6);
    const Vec3 p = {mesh.origin[0] + scale * u(rng), mesh.origin[1] + scale * u(rng),
                    mesh.origin[2] + scale * u(rng)};
    const uint32_t hint = static_cast<uint32_t>(rng() % mesh.face_count());
    for (const uint32_t h : {UINT32_MAX, hint}) {
      const TriangleBvh::Hit a = embree.Nearest(p, h);
      const TriangleBvh::Hit b = builtin.Nearest(p, h);
      ASSERT_EQ(a.face, b.face) << "query " << i;
      ASSERT_EQ(a.squared_distance_m2, b.squared_distance_m2) << "query " << i;
      ASSERT_EQ(a.closest, b.closest) << "query " << i;
    }
  }
  // The segment's nearest point from beyond its end.
  const TriangleBvh::Hit hit =
      embree.Nearest({mesh.origin[0] + 7, mesh.origin[1], mesh.origin[2] + 0.5});
  EXPECT_EQ(hit.face, mesh.face_count() - 1);
  EXPECT_NEAR(hit.squared_distance_m2, 4 + 0.25, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Engines, TriangleBvhEngineTest,
                         ::testing::Values(TriangleBvh::Engine::kEmbree,
                                           TriangleBvh::Engine::kBuiltin),
                         [](const ::testing::TestParamInfo<TriangleBvh::Engine>& info) {
                           return info.param == TriangleBvh::Engine::kEmbree ? std::string("Embree")
                                                                             : std::string("Builtin");
                         });

TEST(MeshDistanceTest, SamplingIsDeterministicAndOnTheSurface) {
  Mesh sphere = Sphere(1, 3);
  sphere.origin = {10, 20, 30};
  const std::vector<Vec3> p1 = SampleMeshSurface(sphere, 1000, 42);
  const std::vector<Vec3> p2 = SampleMeshSurface(sphere, 1000, 42);
  ASSERT_EQ(p1.size(), 1000u);
  EXPECT_EQ(p1, p2);
  EXPECT_NE(p1, SampleMeshSurface(sphere, 1000, 43));
  const TriangleBvh bvh(sphere);
  for (const Vec3& p : p1) ASSERT_LT(bvh.Distance(p), 1e-6);
  // Area-uniform: about half the samples in the upper hemisphere.
  int upper = 0;
  for (const Vec3& p : p1) upper += p[2] > 30;
  EXPECT_NEAR(upper, 500, 60);
}

TEST(MeshDistanceTest, StatsNearestRankPercentile) {
  std::vector<double> d;
  for (int i = 1; i <= 100; ++i) d.push_back(i * 0.001);
  const DistanceStats s = ComputeDistanceStats(d);
  EXPECT_EQ(s.samples, 100u);
  EXPECT_NEAR(s.mean_m, 0.0505, 1e-12);
  EXPECT_NEAR(s.p95_m, 0.095, 1e-12);
  EXPECT_NEAR(s.max_m, 0.1, 1e-12);
  EXPECT_NEAR(s.rms_m, std::sqrt(338350.0 / 100) * 0.001, 1e-12);
}

TEST(MeshDistanceTest, SphereOffsetByOneCentimeter) {
  const Mesh inner = Sphere(1.0, 5), outer = Sphere(1.01, 5);
  MeshDistanceOptions options;
  options.samples = 20000;
  Expected<MeshDistanceResult> r = MeasureMeshDistance(inner, outer, nullptr, options);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_FALSE(r->analytic_mesh_to_truth);
  EXPECT_EQ(r->mesh_to_truth.samples, 20000u);
  EXPECT_NEAR(r->mesh_to_truth.mean_m, 0.01, 2e-4);
  EXPECT_NEAR(r->truth_to_mesh.mean_m, 0.01, 2e-4);
  EXPECT_NEAR(r->mesh_to_truth.rms_m, 0.01, 2e-4);
  EXPECT_NEAR(r->symmetric.max_m, 0.01, 2e-4);
  EXPECT_NEAR(r->symmetric.mean_m, 0.01, 2e-4);
  EXPECT_EQ(r->symmetric.samples, 40000u);
}

TEST(MeshDistanceTest, IdenticalMeshesAreZeroBothWays) {
  const Mesh sphere = Sphere(2.0, 4);
  MeshDistanceOptions options;
  options.samples = 10000;
  double last = -1;
  options.progress = [&](double f) {
    EXPECT_GE(f, last);
    last = f;
  };
  Expected<MeshDistanceResult> r = MeasureMeshDistance(sphere, sphere, nullptr, options);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_LT(r->mesh_to_truth.max_m, 1e-6);
  EXPECT_LT(r->truth_to_mesh.max_m, 1e-6);
  EXPECT_EQ(last, 1.0);
}

TEST(MeshDistanceTest, MissingHalfShowsOnlyTruthToMesh) {
  const Mesh truth = Sphere(1.0, 4);
  Mesh half = truth;
  half.indices.clear();
  for (size_t f = 0; f < truth.face_count(); ++f) {
    bool below = true;
    for (int k = 0; k < 3; ++k)
      below = below && truth.positions[3 * truth.indices[3 * f + k] + 2] <= 0;
    if (below)
      half.indices.insert(half.indices.end(), &truth.indices[3 * f], &truth.indices[3 * f + 3]);
  }
  MeshDistanceOptions options;
  options.samples = 20000;
  Expected<MeshDistanceResult> r = MeasureMeshDistance(half, truth, nullptr, options);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_LT(r->mesh_to_truth.max_m, 1e-6);
  EXPECT_GT(r->truth_to_mesh.max_m, 1.3);   // the pole to the rim: about sqrt(2)
  EXPECT_GT(r->truth_to_mesh.mean_m, 0.2);  // half the samples are far
  EXPECT_EQ(r->symmetric.max_m, r->truth_to_mesh.max_m);
}

TEST(MeshDistanceTest, SynthRoomAgainstItselfWithAnalyticTruth) {
  Expected<SynthScene> scene = MakeSynthScene("room", 1, {});
  ASSERT_TRUE(scene.ok()) << scene.status().message();
  const Mesh truth = SynthTruthMesh(*scene, 0.1);
  MeshDistanceOptions options;
  options.samples = 20000;
  Expected<MeshDistanceResult> r = MeasureMeshDistance(truth, truth, &*scene, options);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_TRUE(r->analytic_mesh_to_truth);
  EXPECT_LT(r->truth_to_mesh.max_m, 1e-5);
  // The 10 cm mesh aliases the relief (mortar joints 4 mm, floor <= 1 cm).
  EXPECT_LT(r->mesh_to_truth.mean_m, 0.005);
  EXPECT_LT(r->mesh_to_truth.max_m, 0.02);
}

TEST(MeshDistanceTest, VertexDistanceToTruthMatchesBruteForce) {
  Mesh inner = Sphere(1.0, 2);
  inner.origin = {0.001, -0.002, 0.003};  // absolute coordinates, both sides
  const Mesh outer = Sphere(1.05, 2);
  Expected<std::vector<float>> d = VertexDistanceToTruth(inner, outer, nullptr);
  ASSERT_TRUE(d.ok()) << d.status().message();
  ASSERT_EQ(d->size(), inner.vertex_count());
  const auto corner = [&](size_t f, int k) {
    const uint32_t v = outer.indices[3 * f + k];
    return Vec3{outer.positions[3 * v], outer.positions[3 * v + 1], outer.positions[3 * v + 2]};
  };
  for (size_t v = 0; v < inner.vertex_count(); ++v) {
    const Vec3 p = {inner.origin[0] + inner.positions[3 * v], inner.origin[1] + inner.positions[3 * v + 1],
                    inner.origin[2] + inner.positions[3 * v + 2]};
    double best = 1e9;
    for (size_t f = 0; f < outer.face_count(); ++f)
      best = std::min(best, BruteForceDistance(p, corner(f, 0), corner(f, 1), corner(f, 2)));
    ASSERT_NEAR((*d)[v], best, 1e-6) << v;
  }
}

TEST(MeshDistanceTest, VertexDistanceToTheAnalyticTruth) {
  Expected<SynthScene> scene = MakeSynthScene("room", 1, {});
  ASSERT_TRUE(scene.ok()) << scene.status().message();
  Mesh moved = SynthTruthMesh(*scene, 0.1);
  ASSERT_TRUE(moved.has_normals());
  for (size_t i = 0; i < moved.positions.size(); ++i) moved.positions[i] += 0.05f * moved.normals[i];
  // No truth triangles: only the scene can answer.
  Expected<std::vector<float>> d = VertexDistanceToTruth(moved, Mesh{}, &*scene);
  ASSERT_TRUE(d.ok()) << d.status().message();
  std::vector<float> sorted = *d;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  EXPECT_NEAR(sorted[sorted.size() / 2], 0.05, 0.005);
  EXPECT_FALSE(VertexDistanceToTruth(moved, Mesh{}, nullptr).ok());
}

TEST(MeshDistanceTest, RejectsMeshWithoutArea) {
  Mesh empty;
  MeshDistanceOptions options;
  Expected<MeshDistanceResult> r = MeasureMeshDistance(empty, Sphere(1, 1), nullptr, options);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(), "evaluated mesh: no faces with positive area");
  r = MeasureMeshDistance(Sphere(1, 1), empty, nullptr, options);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(), "truth mesh: no faces with positive area");
}

}  // namespace
}  // namespace pb
