// The other libraries' implementations (pointbake-pcl.so, and Open3D's
// normals in pointbake-poisson-open3d.so) give the same kind of result as
// ours on synthetic cases with a known answer: normals against analytic
// normals, outlier removal against planted outliers, MLS smoothing against a
// noisy plane's truth, PCL's Poisson against a sphere. Built only when both
// modules are.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "stages/geometry/core/module.h"
#include "stages/geometry/mesh/clean.h"
#include "stages/geometry/mesh/poisson.h"
#include "stages/geometry/points/normals.h"
#include "stages/geometry/points/module_calls.h"
#include "stages/geometry/points/outliers.h"
#include "stages/geometry/points/smooth.h"
#include "stages/geometry/testing/clouds.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

constexpr double kCenter[3] = {0.3, -0.2, 1.0};
constexpr double kRadius = 0.5;

// Fibonacci-lattice sphere with Gaussian radial noise.
PointCloud Sphere(int points, double noise_m, uint32_t seed) {
  PointCloud cloud;
  testing::AddSphere(cloud, kCenter, kRadius, points, noise_m, seed);
  return cloud;
}

// A 1 m x 1 m plane z = 0 sampled on a 1 cm jittered grid, with Gaussian
// noise along z (range noise of a scanner looking down), and colors.
PointCloud NoisyPlane(double noise_m, uint32_t seed) {
  PointCloud cloud;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_m);
  std::uniform_real_distribution<double> jitter(-0.002, 0.002);
  for (int y = 0; y < 100; ++y) {
    for (int x = 0; x < 100; ++x) {
      cloud.positions.insert(cloud.positions.end(),
                             {static_cast<float>(0.01 * x + jitter(rng)),
                              static_cast<float>(0.01 * y + jitter(rng)),
                              static_cast<float>(noise(rng))});
      cloud.colors.insert(cloud.colors.end(), {static_cast<uint8_t>(x), static_cast<uint8_t>(y), 7});
    }
  }
  return cloud;
}

double RadialCosine(const PointCloud& cloud, size_t i) {
  double radial[3], dot = 0, length = 0;
  for (int a = 0; a < 3; ++a) {
    radial[a] = cloud.positions[3 * i + a] - kCenter[a];
    dot += radial[a] * cloud.normals[3 * i + a];
    length += radial[a] * radial[a];
  }
  return dot / std::sqrt(length);
}

class NormalsImplementationTest : public ::testing::TestWithParam<NormalImplementation> {};

TEST_P(NormalsImplementationTest, SphereNormalsAreRadialAndOutward) {
  PointCloud cloud = Sphere(20000, 0.0002, 5);
  NormalOptions options;
  options.implementation = GetParam();
  options.threads = 2;
  NormalReport report;
  const Status status = EstimateNormals(cloud, options, &report);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(report.orientation_used, NormalOrientation::kPropagate);
  ASSERT_EQ(cloud.normals.size(), cloud.positions.size());
  const double cos5 = std::cos(5.0 * std::numbers::pi / 180.0);
  for (size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_GT(RadialCosine(cloud, i), cos5) << "point " << i;
  }
}

TEST_P(NormalsImplementationTest, AgreesWithOwnOnANoisyPlane) {
  PointCloud own = NoisyPlane(0.0005, 3);
  PointCloud other = own;
  NormalOptions options;
  options.orientation = NormalOrientation::kNone;
  options.widen_dense = false;  // the libraries take the k nearest everywhere
  ASSERT_TRUE(EstimateNormals(own, options).ok());
  options.implementation = GetParam();
  const Status status = EstimateNormals(other, options);
  ASSERT_TRUE(status.ok()) << status.message();
  // The same k points: the same plane up to float rounding (sign free).
  for (size_t i = 0; i < own.size(); ++i) {
    double dot = 0;
    for (int a = 0; a < 3; ++a) dot += own.normals[3 * i + a] * other.normals[3 * i + a];
    ASSERT_GT(std::abs(dot), 0.9999) << "point " << i;
  }
}

INSTANTIATE_TEST_SUITE_P(All, NormalsImplementationTest,
                         ::testing::Values(NormalImplementation::kOwn, NormalImplementation::kPcl,
                                           NormalImplementation::kOpen3d));

class OutliersImplementationTest : public ::testing::TestWithParam<OutlierImplementation> {};

TEST_P(OutliersImplementationTest, RemovesPlantedOutliersOnly) {
  PointCloud cloud = NoisyPlane(0.0005, 4);
  const size_t surface = cloud.size();
  // 50 points 5-30 cm off the plane, scattered.
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> xy(0.0, 1.0), z(0.05, 0.3);
  for (int i = 0; i < 50; ++i) {
    cloud.positions.insert(cloud.positions.end(), {static_cast<float>(xy(rng)),
                                                   static_cast<float>(xy(rng)),
                                                   static_cast<float>(z(rng))});
    cloud.colors.insert(cloud.colors.end(), {255, 0, 0});
  }
  OutlierOptions options;
  options.k = 16;
  options.std_ratio = 2.0;
  options.implementation = GetParam();
  OutlierReport report;
  auto out = RemoveStatisticalOutliers(cloud, options, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  size_t planted_left = 0;
  for (size_t i = 0; i < out->size(); ++i) planted_left += out->positions[3 * i + 2] > 0.02f;
  EXPECT_EQ(planted_left, 0u);
  EXPECT_GE(out->size(), surface * 99 / 100);  // the surface stays
  EXPECT_EQ(report.removed, cloud.size() - out->size());
  ASSERT_EQ(out->colors.size(), 3 * out->size());  // attributes follow their points
  for (size_t i = 0; i < out->size(); ++i) ASSERT_NE(out->colors[3 * i], 255);
}

INSTANTIATE_TEST_SUITE_P(All, OutliersImplementationTest,
                         ::testing::Values(OutlierImplementation::kOwn, OutlierImplementation::kPcl));

TEST(OutliersImplementationTest, PclKeepsTheSamePointsAsOwn) {
  PointCloud cloud = Sphere(5000, 0.002, 11);
  OutlierOptions options;
  options.std_ratio = 1.0;
  auto own = RemoveStatisticalOutliers(cloud, options);
  options.implementation = OutlierImplementation::kPcl;
  auto pcl = RemoveStatisticalOutliers(cloud, options);
  ASSERT_TRUE(own.ok() && pcl.ok());
  ASSERT_GT(own->size(), 0u);
  // The same rule; float rounding may move a point right at the threshold.
  EXPECT_NEAR(static_cast<double>(pcl->size()), static_cast<double>(own->size()), 2.0);
  EXPECT_LT(own->size(), cloud.size());
}

double RmsZ(const PointCloud& cloud) {
  double sum = 0;
  for (size_t i = 0; i < cloud.size(); ++i) sum += double{cloud.positions[3 * i + 2]} * cloud.positions[3 * i + 2];
  return std::sqrt(sum / static_cast<double>(cloud.size()));
}

TEST(SmoothTest, ReducesRangeNoiseOnAPlane) {
  const PointCloud noisy = NoisyPlane(0.002, 1);  // 2 mm range noise, 1 cm spacing
  SmoothOptions options;
  options.radius_m = 0.04;
  options.threads = 2;
  SmoothReport report;
  auto smoothed = SmoothMovingLeastSquares(noisy, options, &report);
  ASSERT_TRUE(smoothed.ok()) << smoothed.status().message();
  ASSERT_EQ(smoothed->size(), noisy.size());
  const double before = RmsZ(noisy), after = RmsZ(*smoothed);
  EXPECT_NEAR(before, 0.002, 0.0002);
  EXPECT_LT(after, before / 3) << "rms " << before << " -> " << after;
  EXPECT_GT(report.mean_shift_m, 0.0005);
  EXPECT_EQ(smoothed->colors, noisy.colors);  // same points, same order
  EXPECT_FALSE(smoothed->has_normals());
  // Points move along the normal (z), not across the surface.
  double across = 0;
  for (size_t i = 0; i < noisy.size(); ++i) {
    for (int a = 0; a < 2; ++a) {
      across = std::max(across, std::abs(double{smoothed->positions[3 * i + a]} - noisy.positions[3 * i + a]));
    }
  }
  EXPECT_LT(across, 0.002);
}

TEST(SmoothTest, KeepsASphereRoundAndIsThreadIndependent) {
  const PointCloud noisy = Sphere(20000, 0.002, 2);
  SmoothOptions options;
  options.radius_m = 0.03;
  options.threads = 1;
  auto one = SmoothMovingLeastSquares(noisy, options);
  options.threads = 2;
  auto two = SmoothMovingLeastSquares(noisy, options);
  ASSERT_TRUE(one.ok() && two.ok());
  EXPECT_EQ(one->positions, two->positions);
  double before = 0, after = 0;
  for (size_t i = 0; i < noisy.size(); ++i) {
    double rb = 0, ra = 0;
    for (int a = 0; a < 3; ++a) {
      rb += std::pow(noisy.positions[3 * i + a] - kCenter[a], 2);
      ra += std::pow(one->positions[3 * i + a] - kCenter[a], 2);
    }
    before += std::pow(std::sqrt(rb) - kRadius, 2);
    after += std::pow(std::sqrt(ra) - kRadius, 2);
  }
  EXPECT_LT(std::sqrt(after / noisy.size()), std::sqrt(before / noisy.size()) / 2);
}

TEST(SmoothTest, Errors) {
  const PointCloud plane = NoisyPlane(0.001, 1);
  SmoothOptions options;
  EXPECT_THAT(SmoothMovingLeastSquares(plane, options).status().message(), HasSubstr("radius"));
  options.radius_m = 0.03;
  options.polynomial_order = 4;
  EXPECT_THAT(SmoothMovingLeastSquares(plane, options).status().message(),
              HasSubstr("polynomial order"));
  options.polynomial_order = 2;
  PointCloud bad = plane;
  bad.positions[3 * 17 + 1] = std::nanf("");
  EXPECT_THAT(SmoothMovingLeastSquares(bad, options).status().message(), HasSubstr("point 17"));
}

TEST(PclPoissonTest, ClosedMeshNearASphere) {
  PointCloud cloud = Sphere(30000, 0.0, 3);
  ASSERT_TRUE(EstimateNormals(cloud, {}).ok());
  cloud.colors.assign(3 * cloud.size(), 200);
  PoissonOptions options;
  options.implementation = PoissonImplementation::kPcl;
  options.depth = 6;
  options.threads = 1;
  auto out = ReconstructPoisson(cloud, options);
  ASSERT_TRUE(out.ok()) << out.status().message();
  const Mesh& mesh = out->mesh;
  ASSERT_GT(mesh.face_count(), 1000u);
  EXPECT_TRUE(CheckManifold(mesh).ok()) << CheckManifold(mesh).message();
  // Closed: every edge is used by exactly two faces.
  std::multiset<std::pair<uint32_t, uint32_t>> edges;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = mesh.indices[3 * f + k], b = mesh.indices[3 * f + (k + 1) % 3];
      edges.emplace(std::min(a, b), std::max(a, b));
    }
  }
  for (const auto& edge : edges) ASSERT_EQ(edges.count(edge), 2u);
  // Near the sphere: depth 6 over a 1.1 m cube is a 17 mm cell.
  double worst = 0;
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    double r2 = 0;
    for (int a = 0; a < 3; ++a) r2 += std::pow(mesh.positions[3 * v + a] - kCenter[a], 2);
    worst = std::max(worst, std::abs(std::sqrt(r2) - kRadius));
  }
  EXPECT_LT(worst, 0.01);
  // Normals from the points (outward), colors from the points, the same
  // winding as Open3D's: counter-clockwise seen from outside.
  ASSERT_TRUE(mesh.has_normals());
  ASSERT_EQ(mesh.colors.size(), 3 * mesh.vertex_count());
  EXPECT_EQ(mesh.colors[0], 200);
  double signed_volume = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const float* p[3];
    for (int k = 0; k < 3; ++k) p[k] = &mesh.positions[3 * mesh.indices[3 * f + k]];
    signed_volume += (p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) -
                      p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0]) +
                      p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0])) / 6.0;
  }
  EXPECT_NEAR(signed_volume, 4.0 / 3.0 * std::numbers::pi * std::pow(kRadius, 3), 0.01);
  EXPECT_EQ(out->densities.size(), mesh.vertex_count());

  options.linear_fit = true;
  EXPECT_THAT(ReconstructPoisson(cloud, options).status().message(), HasSubstr("linear_fit"));
}

TEST(ModuleTest, MissingModuleSaysWhatToInstall) {
  const ModuleSpec missing{"pointbake-no-such-module.so", "PB_NO_SUCH_MODULE",
                           "install libno-such-dev and rebuild"};
  auto symbol = ModuleSymbol(missing, "pb_nothing_v1", "implementation 'none'");
  ASSERT_FALSE(symbol.ok());
  EXPECT_EQ(symbol.status().code(), Status::Code::kUnsupported);
  EXPECT_THAT(symbol.status().message(),
              HasSubstr("implementation 'none' needs pointbake-no-such-module.so, which this build "
                        "lacks: install libno-such-dev and rebuild"));
  EXPECT_THAT(symbol.status().message(), HasSubstr("not there"));
  // A module that loads but lacks the symbol is named as such.
  auto wrong = ModuleSymbol(kPclModule, "pb_pcl_nothing_v1", "x");
  ASSERT_FALSE(wrong.ok());
  EXPECT_THAT(wrong.status().message(), HasSubstr("pb_pcl_nothing_v1"));
  EXPECT_TRUE(ModuleSymbol(kPclModule, PB_PCL_SMOOTH_SYMBOL, "x").ok());
}

}  // namespace
}  // namespace pb
