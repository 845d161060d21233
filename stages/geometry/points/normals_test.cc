#include "stages/geometry/points/normals.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <random>
#include <vector>

#include "stages/geometry/testing/clouds.h"
#include "stages/geometry/synth/scan_without_stations.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

const double kCos2Deg = std::cos(2.0 * std::numbers::pi / 180.0);

double Dot(const float* n, const double v[3]) { return n[0] * v[0] + n[1] * v[1] + n[2] * v[2]; }

using testing::AddBoxFaces;
using testing::AddSphere;
using testing::AddZenithCeiling;

TEST(NormalsTest, SmallestEigenvector) {
  const double diagonal[9] = {3, 0, 0, 0, 1, 0, 0, 0, 2};
  double v[3];
  EXPECT_DOUBLE_EQ(SmallestEigenvector(diagonal, v), 1.0);
  EXPECT_DOUBLE_EQ(std::fabs(v[1]), 1.0);
  // I + u u^T has eigenvalue 1 (twice) orthogonal to u and 1 + |u|^2 along u;
  // 5 I - 2 w w^T (|w| = 1) has its smallest eigenvalue 3 along w.
  const double w[3] = {1 / std::sqrt(14.0), 2 / std::sqrt(14.0), 3 / std::sqrt(14.0)};
  double m[9];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m[3 * r + c] = (r == c ? 5.0 : 0.0) - 2 * w[r] * w[c];
  }
  EXPECT_NEAR(SmallestEigenvector(m, v), 3.0, 1e-12);
  EXPECT_NEAR(std::fabs(v[0] * w[0] + v[1] * w[1] + v[2] * w[2]), 1.0, 1e-12);
}

// The closed form agrees with Jacobi on covariances of surfaces, lines
// (where it falls back to Jacobi) and blobs, and is Jacobi's axis for zero.
TEST(NormalsTest, PlaneNormalMatchesJacobi) {
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    // Spreads along three random orthogonal-ish axes: a surface (0), a line
    // (1), an isotropic blob (2) or a single repeated point (3).
    const int kind = trial % 4;
    const double sigma[4][3] = {
        {4e-3, 3e-3, 1e-5}, {4e-3, 1e-6, 1e-6}, {1e-3, 1e-3, 1e-3}, {0, 0, 0}};
    double cov[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    const double tilt[3] = {gauss(rng), gauss(rng), gauss(rng)};
    for (int j = 0; j < 16; ++j) {
      const double local[3] = {sigma[kind][0] * gauss(rng), sigma[kind][1] * gauss(rng),
                               sigma[kind][2] * gauss(rng)};
      const double p[3] = {local[0] + 0.3 * tilt[0] * local[2], local[1] + 0.4 * tilt[1] * local[0],
                           local[2] + 0.5 * tilt[2] * local[1]};
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) cov[3 * r + c] += p[r] * p[c];
      }
    }
    double jacobi[3], fast[3];
    SmallestEigenvector(cov, jacobi);
    PlaneNormal(cov, fast);
    SCOPED_TRACE("trial " + std::to_string(trial));
    EXPECT_NEAR(fast[0] * fast[0] + fast[1] * fast[1] + fast[2] * fast[2], 1.0, 1e-14);
    if (kind == 3) {
      EXPECT_EQ(std::vector<double>(fast, fast + 3), std::vector<double>(jacobi, jacobi + 3));
    } else {
      // 1 - |cos| < 1e-14: within 1.5e-7 rad, float resolution.
      const double cosine = jacobi[0] * fast[0] + jacobi[1] * fast[1] + jacobi[2] * fast[2];
      EXPECT_NEAR(std::fabs(cosine), 1.0, 1e-14);
    }
  }
}

TEST(NormalsTest, NoisyPlaneWithinTwoDegrees) {
  // Plane through the origin with normal (1, 2, 3)/|.|, 2 mm grid, 0.05 mm noise.
  const double normal[3] = {1 / std::sqrt(14.0), 2 / std::sqrt(14.0), 3 / std::sqrt(14.0)};
  const double u[3] = {2 / std::sqrt(5.0), -1 / std::sqrt(5.0), 0};
  const double v[3] = {normal[1] * u[2] - normal[2] * u[1], normal[2] * u[0] - normal[0] * u[2],
                       normal[0] * u[1] - normal[1] * u[0]};
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.00005);
  PointCloud cloud;
  cloud.origin = {654321.0, 5432100.0, 250.0};
  for (int i = 0; i < 100; ++i) {
    for (int j = 0; j < 100; ++j) {
      const double a = 0.002 * i, b = 0.002 * j, h = noise(rng);
      for (int axis = 0; axis < 3; ++axis) {
        cloud.positions.push_back(static_cast<float>(a * u[axis] + b * v[axis] + h * normal[axis]));
      }
    }
  }
  NormalReport report;
  ASSERT_TRUE(EstimateNormals(cloud, {.k = 16, .orientation = NormalOrientation::kPropagate}, &report).ok());
  EXPECT_EQ(report.points, 10000u);
  EXPECT_EQ(report.orientation_used, NormalOrientation::kPropagate);
  ASSERT_EQ(cloud.normals.size(), cloud.positions.size());
  // Propagation makes every normal agree with the first one's side.
  const double side = Dot(&cloud.normals[0], normal) > 0 ? 1.0 : -1.0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_GT(side * Dot(&cloud.normals[3 * i], normal), kCos2Deg) << "point " << i;
  }
}

TEST(NormalsTest, SpherePointsOutwardAfterPropagation) {
  PointCloud cloud;
  const double center[3] = {0.3, -0.2, 1.0};
  AddSphere(cloud, center, 0.5, 20000, 0.0002, 5);
  NormalReport report;
  ASSERT_TRUE(EstimateNormals(cloud, {}, &report).ok());  // auto -> propagate: no stations
  EXPECT_EQ(report.orientation_used, NormalOrientation::kPropagate);
  for (size_t i = 0; i < cloud.size(); ++i) {
    double radial[3];
    for (int a = 0; a < 3; ++a) radial[a] = cloud.positions[3 * i + a] - center[a];
    const double length = std::sqrt(radial[0] * radial[0] + radial[1] * radial[1] + radial[2] * radial[2]);
    ASSERT_GT(Dot(&cloud.normals[3 * i], radial) / length, std::cos(10.0 * std::numbers::pi / 180.0))
        << "point " << i;
  }
}

TEST(NormalsTest, TwoSeparateSpheresBothOutward) {
  PointCloud cloud;
  const double left[3] = {-2, 0, 0}, right[3] = {2, 0, 0};
  AddSphere(cloud, left, 0.3, 5000, 0.0, 1);
  AddSphere(cloud, right, 0.3, 5000, 0.0, 2);
  ASSERT_TRUE(EstimateNormals(cloud, {.orientation = NormalOrientation::kPropagate}).ok());
  for (size_t i = 0; i < cloud.size(); ++i) {
    const double* c = i < 5000 ? left : right;
    double radial[3];
    for (int a = 0; a < 3; ++a) radial[a] = cloud.positions[3 * i + a] - c[a];
    ASSERT_GT(Dot(&cloud.normals[3 * i], radial), 0) << "point " << i;
  }
}

// One scan exported without its station (the synthetic facade from one
// station, its stations dropped): the normals face where the scanner stood,
// found in the points, nearly all of them; propagation (find_station false,
// version 5) picks a side per part.
TEST(NormalsTest, AScanWithoutItsStationFacesWhereItStood) {
  testing::ScanWithoutStations scan = testing::FacadeWithoutStations(1, 60'000);
  ASSERT_EQ(scan.stations.size(), 1u);
  const std::array<double, 3> station = scan.stations[0];
  PointCloud cloud = std::move(scan.cloud);
  auto facing = [&](const PointCloud& oriented) {
    size_t toward = 0;
    for (size_t i = 0; i < oriented.size(); ++i) {
      double dot = 0;
      for (int a = 0; a < 3; ++a)
        dot += (station[a] - oriented.positions[3 * i + a]) * oriented.normals[3 * i + a];
      toward += dot > 0;
    }
    return double(toward) / double(oriented.size());
  };
  PointCloud propagated = cloud;
  NormalReport report, old_report;
  ASSERT_TRUE(EstimateNormals(cloud, {}, &report).ok());
  ASSERT_TRUE(EstimateNormals(propagated, {.find_station = false}, &old_report).ok());
  EXPECT_TRUE(report.station_searched);
  EXPECT_TRUE(report.station_found) << report.station_verdict;
  EXPECT_EQ(report.orientation_used, NormalOrientation::kStations);
  EXPECT_LT(std::hypot(report.station[0] - station[0], report.station[1] - station[1],
                       report.station[2] - station[2]),
            0.25);
  EXPECT_GT(facing(cloud), 0.99);
  EXPECT_FALSE(old_report.station_searched);
  EXPECT_EQ(old_report.orientation_used, NormalOrientation::kPropagate);
  EXPECT_LT(facing(propagated), 0.95) << "propagation alone no longer errs: the test shows nothing";
}

TEST(NormalsTest, StationOrientationFacesTheScanner) {
  // A horizontal plane seen from above (station 0) for x < 0.1 and from below
  // (station 1) otherwise; stations are absolute, positions relative to origin.
  PointCloud cloud;
  cloud.origin = {1000.0, 2000.0, 30.0};
  cloud.stations = {{1000.1, 2000.1, 32.0}, {1000.1, 2000.1, 28.0}};
  for (int i = 0; i < 100; ++i) {
    for (int j = 0; j < 100; ++j) {
      cloud.positions.insert(cloud.positions.end(), {0.002f * i, 0.002f * j, 0.0f});
      cloud.station_ids.push_back(i < 50 ? 0 : 1);
    }
  }
  NormalReport report;
  ASSERT_TRUE(EstimateNormals(cloud, {}, &report).ok());
  EXPECT_EQ(report.orientation_used, NormalOrientation::kStations);
  for (size_t i = 0; i < cloud.size(); ++i) {
    const float expected_z = cloud.station_ids[i] == 0 ? 1.0f : -1.0f;
    ASSERT_NEAR(cloud.normals[3 * i + 2], expected_z, 1e-6) << "point " << i;
  }
  // Exactly half the normals point away from their station before orienting.
  PointCloud unoriented = cloud;
  ASSERT_TRUE(EstimateNormals(unoriented, {.orientation = NormalOrientation::kNone}).ok());
  size_t wrong = 0;
  for (size_t i = 0; i < cloud.size(); ++i) wrong += unoriented.normals[3 * i + 2] != cloud.normals[3 * i + 2];
  EXPECT_EQ(report.flipped, wrong);
}

// A thin sheet (an ear, a drapery fold) sampled on both faces, 5 mm apart,
// with the normals the file came with: rough (each tilted up to 40 degrees)
// but on the right side. `auto` takes their sides: every PCA normal faces
// the way its input one did, top face up and bottom face down.
TEST(NormalsTest, InputNormalsGiveTheSides) {
  PointCloud cloud;
  for (int face = 0; face < 2; ++face) {
    for (int i = 0; i < 60; ++i) {
      for (int j = 0; j < 60; ++j) {
        cloud.positions.insert(cloud.positions.end(),
                               {0.002f * i, 0.002f * j, face == 0 ? 0.0f : -0.005f});
        const float tilt = 0.8f * std::sin(0.7f * float(i * 60 + j));  // up to ~40 degrees
        const float up = face == 0 ? 1.0f : -1.0f;
        cloud.normals.insert(cloud.normals.end(), {tilt, 0.0f, up});
      }
    }
  }
  PointCloud unoriented = cloud;
  NormalReport report;
  ASSERT_TRUE(EstimateNormals(cloud, {.k = 8}, &report).ok());
  EXPECT_EQ(report.orientation_used, NormalOrientation::kInput);
  ASSERT_TRUE(EstimateNormals(unoriented, {.k = 8, .orientation = NormalOrientation::kNone}).ok());
  size_t flipped = 0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    const float expected = i < 3600 ? 1.0f : -1.0f;
    ASSERT_GT(cloud.normals[3 * i + 2] * expected, 0.99f) << "point " << i;
    // The PCA normal itself, only its sign chosen.
    ASSERT_EQ(std::fabs(cloud.normals[3 * i + 2]), std::fabs(unoriented.normals[3 * i + 2]));
    flipped += cloud.normals[3 * i + 2] != unoriented.normals[3 * i + 2];
  }
  EXPECT_EQ(report.flipped, flipped);

  // One unusable input normal: `auto` propagates instead; `input` says which.
  PointCloud zero = cloud;
  zero.normals[3 * 17 + 0] = zero.normals[3 * 17 + 1] = zero.normals[3 * 17 + 2] = 0.0f;
  PointCloud zero_auto = zero;
  ASSERT_TRUE(EstimateNormals(zero_auto, {.k = 8}, &report).ok());
  EXPECT_EQ(report.orientation_used, NormalOrientation::kPropagate);
  EXPECT_THAT(EstimateNormals(zero, {.k = 8, .orientation = NormalOrientation::kInput}).message(),
              HasSubstr("orientation 'input': point 17 has a zero or non-finite normal"));
  PointCloud none;
  none.positions = cloud.positions;
  EXPECT_THAT(EstimateNormals(none, {.orientation = NormalOrientation::kInput}).message(),
              HasSubstr("orientation 'input' needs the cloud's own normals"));
}

// A file whose normals a tool computed without orienting them (random
// signs here): `auto` finds their sides disagree between neighbours and
// propagates instead of taking them; oriented ones it takes.
TEST(NormalsTest, AutoDoesNotTakeUnorientedFileNormals) {
  PointCloud cloud;
  const double center[3] = {0.3, -0.2, 1.0};
  AddSphere(cloud, center, 0.5, 20000, 0.0002, 5);
  std::mt19937 rng(9);
  for (size_t i = 0; i < cloud.size(); ++i) {
    const float sign = rng() % 2 ? 1.0f : -1.0f;
    for (int a = 0; a < 3; ++a) cloud.normals.push_back(sign * float(cloud.positions[3 * i + a] - center[a]));
  }
  PointCloud oriented = cloud;
  for (size_t i = 0; i < oriented.size(); ++i) {
    for (int a = 0; a < 3; ++a) oriented.normals[3 * i + a] = float(oriented.positions[3 * i + a] - center[a]);
  }
  NormalReport report;
  ASSERT_TRUE(EstimateNormals(cloud, {}, &report).ok());
  EXPECT_EQ(report.orientation_used, NormalOrientation::kPropagate);
  EXPECT_GT(report.input_sides_disagree, 0.4);
  for (size_t i = 0; i < cloud.size(); ++i) {
    double radial[3];
    for (int a = 0; a < 3; ++a) radial[a] = cloud.positions[3 * i + a] - center[a];
    ASSERT_GT(Dot(&cloud.normals[3 * i], radial), 0) << "point " << i;
  }
  ASSERT_TRUE(EstimateNormals(oriented, {}, &report).ok());
  EXPECT_EQ(report.orientation_used, NormalOrientation::kInput);
  EXPECT_LT(report.input_sides_disagree, 0.01);
  // `input` asked for takes them as they are.
  PointCloud asked = cloud;
  for (size_t i = 0; i < asked.size(); ++i) {
    for (int a = 0; a < 3; ++a) asked.normals[3 * i + a] = -asked.normals[3 * i + a];
  }
  ASSERT_TRUE(EstimateNormals(asked, {.orientation = NormalOrientation::kInput}, &report).ok());
  EXPECT_EQ(report.orientation_used, NormalOrientation::kInput);
  EXPECT_EQ(report.input_sides_disagree, 0.0);
}

TEST(NormalsTest, Errors) {
  PointCloud cloud;
  cloud.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  EXPECT_THAT(EstimateNormals(cloud, {.orientation = NormalOrientation::kStations}).message(),
              HasSubstr("orientation 'stations' needs per-point station ids"));
  EXPECT_THAT(EstimateNormals(cloud, {.k = 2}).message(), HasSubstr("k must be between 3 and 100, got 2"));
  cloud.station_ids = {0, 0, 3, 0};
  cloud.stations = {{0, 0, 1}};
  EXPECT_THAT(EstimateNormals(cloud, {}).message(),
              HasSubstr("point 2 names station 3 of 1"));
  PointCloud two;
  two.positions = {0, 0, 0, 1, 0, 0};
  EXPECT_THAT(EstimateNormals(two, {}).message(), HasSubstr("needs at least 3 points, the cloud has 2"));
  // Every implementation names a non-finite point (the other libraries'
  // are checked before their module is loaded).
  for (const NormalImplementation implementation :
       {NormalImplementation::kOwn, NormalImplementation::kPcl, NormalImplementation::kOpen3d}) {
    PointCloud bad;
    bad.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, std::nanf("")};
    NormalOptions options;
    options.implementation = implementation;
    options.orientation = NormalOrientation::kNone;
    EXPECT_THAT(EstimateNormals(bad, options).message(), HasSubstr("point 3"));
  }
}

TEST(NormalsTest, SameNormalsWithOneAndTwoThreads) {
  PointCloud cloud;
  const double center[3] = {0, 0, 0};
  AddSphere(cloud, center, 0.4, 30000, 0.001, 9);
  PointCloud one = cloud, two = cloud;
  NormalReport report_one, report_two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    ASSERT_TRUE(EstimateNormals(one, {}, &report_one).ok());
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    ASSERT_TRUE(EstimateNormals(two, {.threads = 2}, &report_two).ok());
  }
  EXPECT_EQ(one.normals, two.normals);
  EXPECT_EQ(report_one.flipped, report_two.flipped);
}

// A ceiling 1.7 m above a scanner, swept as a laser scanner sweeps it
// (AddZenithCeiling), 2 mm range noise along the ray. Near the zenith a
// point's 16 nearest lie on one short arc across the lines, the noise is as
// deep as the arc is long, and their plane stands on edge. Widened to a
// typical neighbourhood, it spans several lines.
TEST(NormalsTest, WhereScanLinesConvergeTheNeighbourhoodIsWidened) {
  PointCloud cloud;
  AddZenithCeiling(cloud, 1.7, 0.006, 0.4, 0.002, 11);
  // Off by more than 25 degrees from the ceiling's normal, within 0.2 m of
  // the zenith and beyond.
  auto tilted = [&](const PointCloud& c, bool near) {
    size_t count = 0;
    for (size_t i = 0; i < c.size(); ++i) {
      const float* p = &c.positions[3 * i];
      if ((std::hypot(p[0], p[1]) < 0.2) == near) count += std::fabs(c.normals[3 * i + 2]) < 0.9;
    }
    return count;
  };
  PointCloud narrow = cloud;
  NormalReport report;
  ASSERT_TRUE(EstimateNormals(narrow, {.widen_dense = false, .orientation = NormalOrientation::kNone}, &report).ok());
  EXPECT_EQ(report.widened, 0u);
  EXPECT_GT(tilted(narrow, true), 15000u);  // of the 19,912 within 0.2 m
  EXPECT_GT(tilted(narrow, false), 1000u);
  ASSERT_TRUE(EstimateNormals(cloud, {.orientation = NormalOrientation::kNone}, &report).ok());
  EXPECT_GT(report.widened, cloud.size() / 4);
  EXPECT_GT(report.widen_to_m, 0.005);
  // 19,877 and 1,396 tilted before; 213 and 5 (at the disc's rim) after.
  EXPECT_LT(tilted(cloud, true), 400u);
  EXPECT_LT(tilted(cloud, false), 20u);
}

// The share of the room's wall, floor and ceiling points whose normals face
// into the room (toward the box's center side of their face), and of the
// table's facing out of it.
struct RoomSides {
  double walls_inward = 0, table_outward = 0;
};
RoomSides SidesOf(const PointCloud& room, double width_m, double depth_m) {
  size_t walls = 0, walls_in = 0, table = 0, table_out = 0;
  const double table_center[3] = {0.3 * width_m + 0.6, 0.5 * depth_m + 0.4, 0.375};
  const double room_center[3] = {0.5 * width_m, 0.5 * depth_m, 1.5};
  for (size_t i = 0; i < room.size(); ++i) {
    const float* p = &room.positions[3 * i];
    const float* n = &room.normals[3 * i];
    const bool on_table = p[0] > 0.3 * width_m - 0.01 && p[0] < 0.3 * width_m + 1.21 &&
                          p[1] > 0.5 * depth_m - 0.01 && p[1] < 0.5 * depth_m + 0.81 &&
                          p[2] < 0.76 && p[2] > 0.01;
    const double* c = on_table ? table_center : room_center;
    const double toward[3] = {c[0] - p[0], c[1] - p[1], c[2] - p[2]};
    const bool faces_center = Dot(n, toward) > 0;
    if (on_table) {
      ++table, table_out += !faces_center;
    } else {
      ++walls, walls_in += faces_center;
    }
  }
  return {double(walls_in) / double(walls), double(table_out) / double(table)};
}

// A plinth on a ground, as a statue's file brings them (no stations, no
// normals): the box's four sides and top, the ground around it, one linked
// part. The seed, the ground's corner farthest from the centroid, has its
// normal across the way out and faced down, and propagation turned the box
// inside out through the ground (version 3: every side point faced in).
// Rays now find the box's outside (open ahead, its far side behind) and
// the propagation grows from the points they decide.
TEST(NormalsTest, RaysFaceAPlinthOutwardOnItsGround) {
  PointCloud cloud;
  const double lo[3] = {-0.3, -0.3, 0.0}, hi[3] = {0.3, 0.3, 1.0};
  // Noise half the spacing, as a laser scan's at a few metres.
  AddBoxFaces(cloud, lo, hi, 0.02, 0.01, 7, [](double, double, double z) { return z < 0.01; });
  const size_t box = cloud.size();
  std::mt19937 rng(8);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (double x = -1.5; x <= 1.5; x += 0.02) {
    for (double y = -1.5; y <= 1.5; y += 0.02) {
      if (std::fabs(x) < 0.3 && std::fabs(y) < 0.3) continue;
      cloud.positions.insert(cloud.positions.end(), {float(x), float(y), float(noise(rng))});
    }
  }
  NormalReport report;
  ASSERT_TRUE(EstimateNormals(cloud, {}, &report).ok());
  EXPECT_EQ(report.orientation_used, NormalOrientation::kPropagate);
  EXPECT_GT(report.facing_rays, 0u);
  size_t sides = 0, sides_out = 0, top = 0, top_up = 0, ground_up = 0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    const float* p = &cloud.positions[3 * i];
    const float* normal = &cloud.normals[3 * i];
    if (i >= box) {
      ground_up += normal[2] > 0;
    } else if (p[2] > 0.99f) {
      ++top;
      top_up += normal[2] > 0;
    } else if (p[2] > 0.05f && (std::fabs(p[0]) > 0.29f || std::fabs(p[1]) > 0.29f)) {
      ++sides;
      sides_out += p[0] * normal[0] + p[1] * normal[1] > 0;
    }
  }
  EXPECT_GT(double(sides_out) / double(sides), 0.99) << sides_out << " of " << sides;
  EXPECT_GT(double(top_up) / double(top), 0.99) << top_up << " of " << top;
  EXPECT_GT(double(ground_up) / double(cloud.size() - box), 0.99);

  // A ball alone, a cloud the seed already got right, stays outward.
  PointCloud ball;
  const double center[3] = {0, 0, 0};
  AddSphere(ball, center, 0.4, 20000, 0.0005, 3);
  ASSERT_TRUE(EstimateNormals(ball, {}, &report).ok());
  EXPECT_GT(report.facing_rays, 0u);
  for (size_t i = 0; i < ball.size(); ++i) {
    const float* p = &ball.positions[3 * i];
    ASSERT_GT(p[0] * ball.normals[3 * i] + p[1] * ball.normals[3 * i + 1] + p[2] * ball.normals[3 * i + 2], 0)
        << "point " << i;
  }
}

// A room merged into one cloud without its stations: propagation alone
// would face its walls outward (inside-out); the enclosed space turns them
// in. The table, an object in the room, faces out of itself, into the room.
TEST(NormalsTest, PropagationFacesARoomsInside) {
  PointCloud room = testing::RoomWithTable(6.0, 4.5, 1.0, 3);
  NormalReport report;
  ASSERT_TRUE(EstimateNormals(room, {}, &report).ok());  // auto -> propagate: no stations
  EXPECT_EQ(report.orientation_used, NormalOrientation::kPropagate);
  EXPECT_GT(report.enclosed_volume_m3, 8.0);
  EXPECT_GT(report.facing_enclosure, room.size() / 2);
  RoomSides sides = SidesOf(room, 6.0, 4.5);
  EXPECT_GT(sides.walls_inward, 0.99);
  EXPECT_GT(sides.table_outward, 0.95);

  // interior: no is version 2's rule: outward from the centroid.
  room = testing::RoomWithTable(6.0, 4.5, 1.0, 3);
  ASSERT_TRUE(EstimateNormals(room, {.interior = NormalInterior::kNo}, &report).ok());
  EXPECT_LT(SidesOf(room, 6.0, 4.5).walls_inward, 0.01);
}

// A room open on a side wider than the enclosure test closes (a 2.5 m
// doorway): no enclosed space, but from inside it most lines of sight meet
// the scan (enclosure.h, FindOpen), and auto faces it inward (version 7;
// version 6 faced it out). Open across a whole wall, it is a cup, as an
// object's inside is from its open underside: auto faces it outward, and
// interior: yes is for it.
TEST(NormalsTest, ARoomOpenOnASideFacesIn) {
  PointCloud room = testing::RoomWithTable(6.0, 4.5, 2.5, 3);
  NormalReport report;
  ASSERT_TRUE(EstimateNormals(room, {}, &report).ok());
  EXPECT_GT(report.enclosed_volume_m3, 8.0);
  EXPECT_TRUE(report.enclosure_open);
  EXPECT_GT(report.facing_enclosure, room.size() / 2);
  RoomSides sides = SidesOf(room, 6.0, 4.5);
  EXPECT_GT(sides.walls_inward, 0.99);
  EXPECT_GT(sides.table_outward, 0.95);

  room = testing::RoomWithTable(6.0, 4.5, 6.0, 3);  // no wall below the lintel
  ASSERT_TRUE(EstimateNormals(room, {}, &report).ok());
  EXPECT_EQ(report.enclosed_volume_m3, 0.0);
  EXPECT_FALSE(report.enclosure_open);
  EXPECT_EQ(report.facing_enclosure, 0u);
  EXPECT_LT(SidesOf(room, 6.0, 4.5).walls_inward, 0.01);
  room = testing::RoomWithTable(6.0, 4.5, 6.0, 3);
  ASSERT_TRUE(EstimateNormals(room, {.interior = NormalInterior::kYes}, &report).ok());
  EXPECT_GT(SidesOf(room, 6.0, 4.5).walls_inward, 0.99);
}

// A corridor open at both ends, merged without its stations: version 6
// faced its walls, floor and ceiling out (every line of sight from the wall's
// outside leaves the scan, and the propagation took that side).
TEST(NormalsTest, ACorridorOpenAtBothEndsFacesIn) {
  PointCloud corridor = testing::OpenCorridor();
  NormalReport report;
  ASSERT_TRUE(EstimateNormals(corridor, {}, &report).ok());
  EXPECT_TRUE(report.enclosure_open);
  size_t inward = 0;
  for (size_t i = 0; i < corridor.size(); ++i) {
    const float* p = &corridor.positions[3 * i];
    const float* n = &corridor.normals[3 * i];
    inward += (0.9 - p[1]) * n[1] + (1.3 - p[2]) * n[2] > 0;  // toward the corridor's axis
  }
  EXPECT_GT(double(inward) / double(corridor.size()), 0.99) << inward << " of " << corridor.size();
}

}  // namespace
}  // namespace pb
