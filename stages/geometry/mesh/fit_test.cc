#include "stages/geometry/mesh/fit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

namespace pb {
namespace {

// An open cylinder of radius r along z in [0, h], `sides` around and `rings`
// rings of vertices, its vertices ON the cylinder: every chord cuts inside,
// as a decimated mesh's edges cut inside a pipe. Faces wound outward.
Mesh InscribedCylinder(double r, double h, int sides, int rings) {
  Mesh mesh;
  for (int j = 0; j < rings; ++j) {
    for (int i = 0; i < sides; ++i) {
      const double a = 2 * std::numbers::pi * i / sides;
      mesh.positions.insert(mesh.positions.end(),
                            {static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)),
                             static_cast<float>(h * j / (rings - 1))});
    }
  }
  for (int j = 0; j + 1 < rings; ++j) {
    for (int i = 0; i < sides; ++i) {
      const uint32_t a = j * sides + i, b = j * sides + (i + 1) % sides;
      const uint32_t c = b + sides, d = a + sides;
      mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
    }
  }
  return mesh;
}

// Points on the true cylinder every ~`step` meters, with outward normals.
PointCloud CylinderPoints(double r, double h, double step) {
  PointCloud cloud;
  const int around = static_cast<int>(std::round(2 * std::numbers::pi * r / step));
  const int along = static_cast<int>(std::round(h / step));
  for (int j = 0; j <= along; ++j) {
    for (int i = 0; i < around; ++i) {
      const double a = 2 * std::numbers::pi * (i + 0.5 * (j % 2)) / around;
      cloud.positions.insert(cloud.positions.end(),
                             {static_cast<float>(r * std::cos(a)),
                              static_cast<float>(r * std::sin(a)), static_cast<float>(h * j / along)});
      cloud.normals.insert(cloud.normals.end(),
                           {static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a)), 0.0f});
    }
  }
  return cloud;
}

// Mean over the points of their signed radial offset from the mesh along
// the ray from the axis: the mesh's radius there minus r (negative: inside).
double MeanRadiusOfFaces(const Mesh& mesh) {
  double sum = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    double x = 0, y = 0;
    for (int k = 0; k < 3; ++k) {
      x += mesh.positions[3 * mesh.indices[3 * f + k]] / 3.0;
      y += mesh.positions[3 * mesh.indices[3 * f + k] + 1] / 3.0;
    }
    sum += std::hypot(x, y);
  }
  return sum / static_cast<double>(mesh.face_count());
}

TEST(FitTest, MovesAnInscribedCylinderOntoItsPoints) {
  const double r = 0.1;
  const Mesh mesh = InscribedCylinder(r, 0.3, 12, 7);  // chords 5.2 cm, sagitta 3.4 mm
  const PointCloud points = CylinderPoints(r, 0.3, 0.004);
  FitOptions options;
  options.free_directions = false;  // version 3's fit, along the normals
  options.outside_weight = 0.5;  // plain least squares: the mesh straddles the points
  FitReport report;
  Expected<Mesh> fitted = FitMeshToPoints(mesh, points, options, &report);
  ASSERT_TRUE(fitted.ok()) << fitted.status().message();
  // Faces, order and vertex count kept.
  EXPECT_EQ(fitted->indices, mesh.indices);
  EXPECT_EQ(fitted->vertex_count(), mesh.vertex_count());
  // The chords lay inside (points outside, positive distance); after the fit
  // the mesh straddles the points.
  EXPECT_GT(report.supported_before, points.size() * 9 / 10);
  EXPECT_GT(report.mean_signed_distance_before_m, 0.001);
  EXPECT_LT(std::abs(report.mean_signed_distance_after_m), 0.0003);
  EXPECT_LT(report.mean_abs_distance_after_m, 0.6 * report.mean_abs_distance_before_m);
  EXPECT_EQ(report.vertices_moved, mesh.vertex_count());  // border rings too
  EXPECT_LT(report.max_move_m, 0.01);
  // The faces' mean radius moved outward to about r (it was r cos(15 deg)
  // at the face centroids, less than r - 2 mm).
  EXPECT_LT(MeanRadiusOfFaces(mesh), r - 0.002);
  EXPECT_GT(MeanRadiusOfFaces(*fitted), r - 0.001);
  EXPECT_LT(MeanRadiusOfFaces(*fitted), r + 0.002);
  EXPECT_GT(report.outside_fraction_before, 0.95);  // the chords lie inside
  EXPECT_GT(report.outside_fraction_after, 0.3);
  EXPECT_LT(report.outside_fraction_after, 0.7);

  // The default weighs a point outside three times one inside: the chords
  // move farther out, and fewer points are left outside the mesh (the ones a
  // silhouette would miss).
  FitOptions weighted_options;
  weighted_options.free_directions = false;
  FitReport weighted;
  Expected<Mesh> covering = FitMeshToPoints(mesh, points, weighted_options, &weighted);
  ASSERT_TRUE(covering.ok()) << covering.status().message();
  EXPECT_LT(weighted.mean_signed_distance_after_m, -0.0003);
  EXPECT_LT(weighted.outside_fraction_after, report.outside_fraction_after - 0.1);
  EXPECT_GT(MeanRadiusOfFaces(*covering), MeanRadiusOfFaces(*fitted));
  EXPECT_LT(MeanRadiusOfFaces(*covering), r + 0.003);

  // Free directions on a smooth surface: the same fit, and no vertex slides
  // along it (around the axis or along it) by more than a millimeter; the
  // two rims move out along the axis by the border pass, as along normals.
  FitOptions free_options;  // the default: free directions
  Expected<Mesh> free_fit = FitMeshToPoints(mesh, points, free_options, nullptr);
  ASSERT_TRUE(free_fit.ok()) << free_fit.status().message();
  EXPECT_NEAR(MeanRadiusOfFaces(*free_fit), MeanRadiusOfFaces(*covering), 0.0005);
  for (size_t v = 12; v + 12 < mesh.vertex_count(); ++v) {
    const float* p = &free_fit->positions[3 * v];
    const float* p0 = &mesh.positions[3 * v];
    const double turn = std::remainder(std::atan2(p[1], p[0]) - std::atan2(p0[1], p0[0]),
                                       2 * std::numbers::pi);
    EXPECT_LT(std::hypot(r * turn, p[2] - p0[2]), 0.001)
        << "vertex " << v << " turn " << r * turn << " along " << p[2] - p0[2];
  }
}

TEST(FitTest, SameBytesForAnyThreadCount) {
  const Mesh mesh = InscribedCylinder(0.1, 0.3, 10, 5);
  const PointCloud points = CylinderPoints(0.1, 0.3, 0.005);
  for (const bool free : {false, true}) {
    FitOptions one, two;
    one.free_directions = two.free_directions = free;
    one.threads = 1;
    two.threads = 2;
    Expected<Mesh> a = FitMeshToPoints(mesh, points, one, nullptr);
    Expected<Mesh> b = FitMeshToPoints(mesh, points, two, nullptr);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->positions, b->positions) << (free ? "free directions" : "along normals");
  }
}

// An n x n grid of 10 cm squares (two triangles each) in the plane z = `z`,
// facing +z.
Mesh FlatGrid(int n, float z) {
  Mesh mesh;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      mesh.positions.insert(mesh.positions.end(),
                            {static_cast<float>(0.1 * i), static_cast<float>(0.1 * j), z});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
    }
  }
  return mesh;
}

// A flat grid 5 mm under noisy points on z = 0: the fit lifts it onto the
// plane and the smoothing keeps it flat (the noise does not make it bumpy).
TEST(FitTest, LiftsAGridOntoNoisyPointsAndKeepsItFlat) {
  Mesh mesh = FlatGrid(10, -0.005f);
  // Normals tilted 10 degrees from the faces' (a smoother surface's, as
  // Poisson's are for a decimated mesh): kept, since the faces do not turn.
  const float tilt = static_cast<float>(10 * std::numbers::pi / 180);
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    mesh.normals.insert(mesh.normals.end(), {std::sin(tilt), 0.0f, std::cos(tilt)});
  }
  PointCloud points;
  uint64_t state = 12345;
  for (int j = 0; j <= 200; ++j) {
    for (int i = 0; i <= 200; ++i) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      const double noise = (static_cast<double>(state >> 11) * 0x1.0p-53 - 0.5) * 0.004;
      points.positions.insert(points.positions.end(),
                              {static_cast<float>(0.005 * i), static_cast<float>(0.005 * j),
                               static_cast<float>(noise)});
    }
  }
  for (const bool free : {false, true}) {
    SCOPED_TRACE(free ? "free directions" : "along normals");
    FitOptions options;
    options.free_directions = free;
    options.iterations = 6;
    options.outside_weight = 0.5;
    options.border_reach_edges = 0;  // the border pass would move the rim outward (next test)
    FitReport report;
    Expected<Mesh> fitted = FitMeshToPoints(mesh, points, options, &report);
    ASSERT_TRUE(fitted.ok()) << fitted.status().message();
    double lo = 1, hi = -1;
    for (size_t v = 0; v < fitted->vertex_count(); ++v) {
      lo = std::min<double>(lo, fitted->positions[3 * v + 2]);
      hi = std::max<double>(hi, fitted->positions[3 * v + 2]);
      // Along the vertex normal only; free, a vertex slides along the plane
      // by a few micrometers of noise at most.
      EXPECT_NEAR(fitted->positions[3 * v], mesh.positions[3 * v], free ? 2e-5 : 1e-6);
      EXPECT_NEAR(fitted->positions[3 * v + 1], mesh.positions[3 * v + 1], free ? 2e-5 : 1e-6);
      EXPECT_NEAR(fitted->normals[3 * v], std::sin(tilt), 5e-3);
      EXPECT_NEAR(fitted->normals[3 * v + 2], std::cos(tilt), 5e-3);
    }
    EXPECT_GT(lo, -0.0015);
    EXPECT_LT(hi, 0.0015);
    EXPECT_LT(hi - lo, 0.0015);  // noise amplitude 4 mm
    EXPECT_LT(report.mean_abs_distance_after_m, report.mean_abs_distance_before_m);
  }
}

// True when (x, y) lies in the xy projection of one of the mesh's faces.
bool CoveredFromAbove(const Mesh& mesh, double x, double y) {
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    double px[3], py[3];
    for (int k = 0; k < 3; ++k) {
      px[k] = mesh.positions[3 * size_t{mesh.indices[3 * f + k]}];
      py[k] = mesh.positions[3 * size_t{mesh.indices[3 * f + k]} + 1];
    }
    bool negative = false, positive = false;
    for (int k = 0; k < 3; ++k) {
      const int l = (k + 1) % 3;
      const double side = (px[l] - px[k]) * (y - py[k]) - (py[l] - py[k]) * (x - px[k]);
      negative |= side < 0;
      positive |= side > 0;
    }
    if (!(negative && positive)) return true;
  }
  return false;
}

// A 1 m grid whose rim lies 3 cm inside the scan's outline (as a decimation
// that cut its border into the surface leaves it): the border pass moves the
// rim outward in the plane until it passes the outermost points, by about
// half a local spacing and never farther than border_reach_edges of an edge;
// off, the rim stays.
TEST(FitTest, TheBorderPassMovesTheRimOutToTheScansOutline) {
  const Mesh mesh = FlatGrid(10, 0.0f);
  PointCloud points;
  for (int j = 0; j <= 212; ++j) {
    for (int i = 0; i <= 212; ++i) {
      points.positions.insert(points.positions.end(), {static_cast<float>(-0.03 + 0.005 * i),
                                                       static_cast<float>(-0.03 + 0.005 * j), 0.0f});
    }
  }
  FitOptions options;
  options.iterations = 2;
  FitReport report;
  Expected<Mesh> fitted = FitMeshToPoints(mesh, points, options, &report);
  ASSERT_TRUE(fitted.ok()) << fitted.status().message();
  EXPECT_EQ(report.border_vertices_moved, 40u);  // the whole rim of the 11 x 11 vertices
  double min_x = 1, max_x = 0, min_y = 1, max_y = 0;
  for (size_t v = 0; v < fitted->vertex_count(); ++v) {
    const double x = fitted->positions[3 * v], y = fitted->positions[3 * v + 1];
    min_x = std::min(min_x, x);
    max_x = std::max(max_x, x);
    min_y = std::min(min_y, y);
    max_y = std::max(max_y, y);
    EXPECT_NEAR(fitted->positions[3 * v + 2], 0.0, 1e-6);  // in the plane
    // At most half an edge (the grid's edges: 0.1 m, diagonals 0.14 m).
    const double move = std::hypot(x - mesh.positions[3 * v], y - mesh.positions[3 * v + 1]);
    EXPECT_LE(move, 0.5 * 0.1 * (1 + std::sqrt(2.0)) / 2 * 1.5 + 1e-6);
  }
  // Past the outermost points (at -0.03 and 1.03) by a fraction of their
  // local spacing (5 mm grid: 4.4 mm inside, 6 mm on the outline).
  for (double low : {min_x, min_y}) {
    EXPECT_LT(low, -0.0315);
    EXPECT_GT(low, -0.0375);
  }
  for (double high : {max_x, max_y}) {
    EXPECT_GT(high, 1.0315);
    EXPECT_LT(high, 1.0375);
  }
  for (size_t i = 0; i < points.size(); i += 7) {
    ASSERT_TRUE(CoveredFromAbove(*fitted, points.positions[3 * i], points.positions[3 * i + 1]))
        << "point " << i << " at " << points.positions[3 * i] << ", " << points.positions[3 * i + 1];
  }

  // Off: the rim stays where the decimation left it.
  options.border_reach_edges = 0;
  Expected<Mesh> kept = FitMeshToPoints(mesh, points, options, &report);
  ASSERT_TRUE(kept.ok());
  EXPECT_EQ(report.border_vertices_moved, 0u);
  EXPECT_EQ(kept->positions, mesh.positions);
  EXPECT_FALSE(CoveredFromAbove(*kept, -0.02, 0.5));

  // A short leash: the rim stops at border_reach_edges of the vertices' mean
  // edge, short of the points.
  options.border_reach_edges = 0.1;
  Expected<Mesh> short_leash = FitMeshToPoints(mesh, points, options, &report);
  ASSERT_TRUE(short_leash.ok());
  for (size_t v = 0; v < short_leash->vertex_count(); ++v) {
    const double move = std::hypot(short_leash->positions[3 * v] - mesh.positions[3 * v],
                                   short_leash->positions[3 * v + 1] - mesh.positions[3 * v + 1]);
    EXPECT_LE(move, 0.1 * 0.1 * (1 + std::sqrt(2.0)) / 2 * 1.5 + 1e-6);
  }
  EXPECT_FALSE(CoveredFromAbove(*short_leash, -0.028, 0.5));

  options.border_margin_spacings = -1;
  EXPECT_FALSE(FitMeshToPoints(mesh, points, options, nullptr).ok());
}

// A flat grid under points spread uniformly over z in [-a, a] (a = 2 mm):
// the weighted least-squares fit settles at the points' expectile of level w,
// e = a (sqrt(w) - sqrt(1 - w)) / (sqrt(w) + sqrt(1 - w)), with (a - e) / 2a
// of them above it: z = 0 and half for w = 0.5, 0.536 mm and 36.6 % for
// 0.75, 1 mm and 25 % for 0.9.
TEST(FitTest, OutsideWeightSettlesTheSurfaceAtThePointsExpectile) {
  const Mesh mesh = FlatGrid(8, -0.003f);
  const double half_spread = 0.002;
  PointCloud points;
  uint64_t state = 777;
  for (int j = 0; j <= 160; ++j) {
    for (int i = 0; i <= 160; ++i) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      const double z = (static_cast<double>(state >> 11) * 0x1.0p-53 * 2 - 1) * half_spread;
      points.positions.insert(points.positions.end(),
                              {static_cast<float>(0.005 * i), static_cast<float>(0.005 * j),
                               static_cast<float>(z)});
    }
  }
  for (const double w : {0.5, 0.75, 0.9}) {
    FitOptions options;
    options.outside_weight = w;
    options.support_spacings = 10;  // the whole spread supports the grid from 3 mm under it
    FitReport report;
    Expected<Mesh> fitted = FitMeshToPoints(mesh, points, options, &report);
    ASSERT_TRUE(fitted.ok()) << fitted.status().message();
    const double e = half_spread * (std::sqrt(w) - std::sqrt(1 - w)) / (std::sqrt(w) + std::sqrt(1 - w));
    double mean_z = 0;
    for (size_t v = 0; v < fitted->vertex_count(); ++v) mean_z += fitted->positions[3 * v + 2];
    mean_z /= static_cast<double>(fitted->vertex_count());
    EXPECT_NEAR(mean_z, e, 0.00015) << "outside_weight " << w;
    EXPECT_NEAR(report.outside_fraction_after, (half_spread - e) / (2 * half_spread), 0.04)
        << "outside_weight " << w;
    EXPECT_EQ(report.supported_after, points.size()) << "outside_weight " << w;
  }
  FitOptions bad;
  bad.outside_weight = 1;
  EXPECT_FALSE(FitMeshToPoints(mesh, points, bad, nullptr).ok());
}

// Unit normals of every face.
std::vector<std::array<double, 3>> FaceNormals(const Mesh& mesh) {
  std::vector<std::array<double, 3>> normals;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    double u[3], w[3];
    for (int c = 0; c < 3; ++c) {
      u[c] = mesh.positions[3 * t[1] + c] - mesh.positions[3 * t[0] + c];
      w[c] = mesh.positions[3 * t[2] + c] - mesh.positions[3 * t[0] + c];
    }
    std::array<double, 3> n = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                               u[0] * w[1] - u[1] * w[0]};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (double& x : n) x /= len;
    normals.push_back(n);
  }
  return normals;
}

Mesh FlatGrid(int n, double step) {
  Mesh mesh;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      mesh.positions.insert(mesh.positions.end(),
                            {static_cast<float>(step * i), static_cast<float>(step * j), 0.0f});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
    }
  }
  return mesh;
}

// A cluster of points 8 cm above the middle vertex of a grid of 10 cm
// faces pulls it up by 8 cm, which would turn its faces by ~38 degrees: the
// guard halves the step until no face turns by more than the limit.
TEST(FitTest, NeverTurnsAFaceByMoreThanTheLimit) {
  const Mesh mesh = FlatGrid(4, 0.1);  // middle vertex 12 at (0.2, 0.2)
  PointCloud points;
  for (int j = -3; j <= 3; ++j) {
    for (int i = -3; i <= 3; ++i) {
      points.positions.insert(points.positions.end(),
                              {0.2f + 0.002f * i, 0.2f + 0.002f * j, 0.08f});
    }
  }
  FitOptions options;
  options.iterations = 1;
  options.support_edges = 1.5;
  options.smoothness = 0;
  options.max_step_edges = 2;
  options.max_offset_edges = 2;
  options.damping = 1;
  options.max_turn_deg = 20;
  FitReport report;
  Expected<Mesh> fitted = FitMeshToPoints(mesh, points, options, &report);
  ASSERT_TRUE(fitted.ok()) << fitted.status().message();
  EXPECT_GT(report.steps_halved, 0u);
  EXPECT_GT(fitted->positions[3 * 12 + 2], 0.01);  // moved, as far as allowed
  const auto before = FaceNormals(mesh), after = FaceNormals(*fitted);
  for (size_t f = 0; f < before.size(); ++f) {
    EXPECT_GE(before[f][0] * after[f][0] + before[f][1] * after[f][1] + before[f][2] * after[f][2],
              std::cos(20.0 * std::numbers::pi / 180) - 1e-6)
        << "face " << f;
  }
  // Without the limit (179 degrees) the same pull goes the whole way.
  options.max_turn_deg = 179;
  Expected<Mesh> free = FitMeshToPoints(mesh, points, options, nullptr);
  ASSERT_TRUE(free.ok());
  EXPECT_NEAR(free->positions[3 * 12 + 2], 0.08, 0.002);
  // The offset limit holds it at half its mean edge (10 cm; the middle
  // vertex's six edges average 11.4 cm) however many rounds pull.
  options.max_offset_edges = 0.5;
  options.iterations = 8;
  options.max_step_edges = 0.25;
  Expected<Mesh> held = FitMeshToPoints(mesh, points, options, nullptr);
  ASSERT_TRUE(held.ok());
  const double edge = (4 * 0.1 + 2 * 0.1 * std::sqrt(2.0)) / 6;
  EXPECT_NEAR(held->positions[3 * 12 + 2], 0.5 * edge, 1e-5);
}

// A right-angled edge along y, rounded off as a coarse Poisson solve and its
// decimation leave it: the profile (x, z) runs along the top z = 0 from
// x = -0.3 to a chamfer of legs `chamfer`, then down the side x = 0 to
// z = -0.3, extruded over y in [0, 0.4] in 8 slices. The points lie on the
// sharp edge's two faces every 3 mm, with their normals.
struct Crease {
  Mesh mesh;
  PointCloud points;
};
Crease ChamferedCrease(double chamfer) {
  const std::vector<std::array<double, 2>> profile = {
      {-0.3, 0}, {-0.15, 0}, {-chamfer, 0}, {0, -chamfer}, {0, -0.15}, {0, -0.3}};
  const int slices = 8;
  Crease c;
  for (int j = 0; j <= slices; ++j) {
    for (const auto& [x, z] : profile) {
      c.mesh.positions.insert(c.mesh.positions.end(),
                              {static_cast<float>(x), static_cast<float>(0.4 * j / slices),
                               static_cast<float>(z)});
    }
  }
  const uint32_t n = static_cast<uint32_t>(profile.size());
  for (uint32_t j = 0; j < static_cast<uint32_t>(slices); ++j) {
    for (uint32_t i = 0; i + 1 < n; ++i) {
      // Wound so that the normals face +z on the top and +x on the side.
      const uint32_t a = j * n + i, b = a + 1, c2 = b + n, d = a + n;
      c.mesh.indices.insert(c.mesh.indices.end(), {a, b, c2, a, c2, d});
    }
  }
  for (double y = 0; y <= 0.4 + 1e-9; y += 0.003) {
    for (double t = 0; t <= 0.3 + 1e-9; t += 0.003) {
      c.points.positions.insert(c.points.positions.end(),
                                {static_cast<float>(-t), static_cast<float>(y), 0.0f});
      c.points.normals.insert(c.points.normals.end(), {0.0f, 0.0f, 1.0f});
      if (t == 0) continue;
      c.points.positions.insert(c.points.positions.end(),
                                {0.0f, static_cast<float>(y), static_cast<float>(-t)});
      c.points.normals.insert(c.points.normals.end(), {1.0f, 0.0f, 0.0f});
    }
  }
  return c;
}

// Largest distance, over the inner slices, from the sharp edge (x = z = 0)
// to the mesh's chamfer there (the segment of profile vertices 2 and 3).
double ChamferInset(const Mesh& mesh) {
  double worst = 0;
  for (int j = 2; j <= 6; ++j) {
    const float* c = &mesh.positions[3 * (6 * j + 2)];
    const float* d = &mesh.positions[3 * (6 * j + 3)];
    const double ux = d[0] - c[0], uz = d[2] - c[2];
    const double length = std::hypot(ux, uz);
    // Distance of the origin from the line through c and d, in (x, z).
    const double inset = length > 1e-9 ? std::abs(c[0] * uz - c[2] * ux) / length
                                       : std::hypot(c[0], c[2]);
    worst = std::max(worst, inset);
  }
  return worst;
}

TEST(FitTest, FreeDirectionsMoveARoundedEdgeOutToTheCrease) {
  const Crease crease = ChamferedCrease(0.012);
  ASSERT_NEAR(ChamferInset(crease.mesh), 0.012 / std::sqrt(2.0), 1e-6);
  FitOptions along_normals;
  along_normals.free_directions = false;
  FitReport report_normals;
  Expected<Mesh> normals = FitMeshToPoints(crease.mesh, crease.points, along_normals,
                                           &report_normals);
  ASSERT_TRUE(normals.ok()) << normals.status().message();
  FitOptions free = along_normals;
  free.free_directions = true;  // the default
  FitReport report_free;
  Expected<Mesh> moved = FitMeshToPoints(crease.mesh, crease.points, free, &report_free);
  ASSERT_TRUE(moved.ok()) << moved.status().message();
  // Along the normals the chamfer's corners can only move diagonally, which
  // bends both faces: the edge stays well inside (8.5 mm at the start).
  EXPECT_GT(ChamferInset(*normals), 0.005);
  // Free, they slide out along the faces to the crease.
  EXPECT_LT(ChamferInset(*moved), 0.003);  // 1.8 mm; along the normals 6.8 mm
  EXPECT_LT(report_free.mean_abs_distance_after_m, report_normals.mean_abs_distance_after_m);
  // The flat parts stay on their planes and barely slide.
  for (size_t v = 0; v < moved->vertex_count(); ++v) {
    const int i = static_cast<int>(v % 6);
    const float* p = &moved->positions[3 * v];
    const float* p0 = &crease.mesh.positions[3 * v];
    if (i <= 1) {
      EXPECT_NEAR(p[2], 0.0, 0.001) << "top vertex " << v;
    }
    if (i >= 4) {
      EXPECT_NEAR(p[0], 0.0, 0.001) << "side vertex " << v;
    }
    if (i == 0 || i == 5) {
      EXPECT_LT(std::hypot(p[0] - p0[0], p[1] - p0[1], p[2] - p0[2]), 0.005) << "vertex " << v;
    }
  }
  // Faces and their order are kept; none turned over.
  EXPECT_EQ(moved->indices, crease.mesh.indices);

  // The chamfer's faces turn about 40 degrees from its vertices' normals:
  // with crease_deg above that no vertex is on a crease, all move along
  // their normals, and the chamfer stays.
  FitOptions gated = free;
  gated.crease_deg = 60;
  Expected<Mesh> held = FitMeshToPoints(crease.mesh, crease.points, gated, nullptr);
  ASSERT_TRUE(held.ok());
  EXPECT_GT(ChamferInset(*held), 0.005);
}

TEST(FitTest, RejectsBadInput) {
  const Mesh mesh = InscribedCylinder(0.1, 0.3, 8, 3);
  const PointCloud points = CylinderPoints(0.1, 0.3, 0.01);
  Mesh no_faces = mesh;
  no_faces.indices.clear();
  EXPECT_NE(FitMeshToPoints(no_faces, points, {}, nullptr).status().message().find("no faces"),
            std::string::npos);
  PointCloud few;
  few.positions = {0, 0, 0, 1, 0, 0};
  EXPECT_EQ(FitMeshToPoints(mesh, few, {}, nullptr).status().code(), Status::Code::kInvalid);
  FitOptions bad;
  bad.damping = 0;
  EXPECT_NE(FitMeshToPoints(mesh, points, bad, nullptr).status().message().find("damping"),
            std::string::npos);
  FitOptions no_tangent;
  no_tangent.tangent_weight = 0;
  EXPECT_NE(
      FitMeshToPoints(mesh, points, no_tangent, nullptr).status().message().find("tangent_weight"),
      std::string::npos);
  Mesh broken = mesh;
  broken.indices.push_back(1000);
  broken.indices.push_back(0);
  broken.indices.push_back(1);
  EXPECT_EQ(FitMeshToPoints(broken, points, {}, nullptr).status().code(), Status::Code::kInvalid);
}

}  // namespace
}  // namespace pb
