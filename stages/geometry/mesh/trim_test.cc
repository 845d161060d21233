#include "stages/geometry/mesh/trim.h"

#include <gtest/gtest.h>

#include <cmath>

#include "stages/geometry/mesh/clean.h"

namespace pb {
namespace {

// An n x n quad grid (2 n^2 faces) over [0, size]^2 at z = 0.
Mesh Grid(int n, double size) {
  Mesh mesh;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      mesh.positions.insert(mesh.positions.end(), {static_cast<float>(size * i / n),
                                                   static_cast<float>(size * j / n), 0.0f});
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

// Points every `step` meters over [0, size]^2 at z = 0, except where
// `skip(x, y)` is true.
template <typename Skip>
PointCloud PlanePoints(double size, double step, Skip skip) {
  PointCloud cloud;
  const int n = static_cast<int>(std::round(size / step));
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const double x = i * step, y = j * step;
      if (skip(x, y)) continue;
      cloud.positions.insert(cloud.positions.end(),
                             {static_cast<float>(x), static_cast<float>(y), 0.0f});
    }
  }
  return cloud;
}

// Faces whose centroid lies in x in [x0, x1].
int FacesWithCentroidIn(const Mesh& mesh, double x0, double x1) {
  int count = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    double x = 0;
    for (int k = 0; k < 3; ++k) x += mesh.positions[3 * mesh.indices[3 * f + k]] / 3.0;
    count += x >= x0 && x <= x1;
  }
  return count;
}

TEST(TrimTest, RemovesAMembraneAcrossAnUnscannedGap) {
  // Points every 1 cm on a 1 m square, none in the band 0.4 < x < 0.6: the
  // mesh (2 cm faces) spans the gap as a membrane 20 spacings wide.
  const PointCloud points = PlanePoints(1.0, 0.01, [](double x, double) { return x > 0.4 && x < 0.6; });
  const Mesh mesh = Grid(50, 1.0);
  SupportTrimReport report;
  auto trimmed = TrimUnsupported(mesh, points, TrimOptions(), &report);
  ASSERT_TRUE(trimmed.ok()) << trimmed.status().message();
  // The gap's middle (farther than 3 spacings from any point) is gone...
  EXPECT_EQ(FacesWithCentroidIn(*trimmed, 0.44, 0.56), 0);
  // ...the scanned surface stays whole.
  EXPECT_EQ(FacesWithCentroidIn(*trimmed, 0.0, 0.38), FacesWithCentroidIn(mesh, 0.0, 0.38));
  EXPECT_EQ(FacesWithCentroidIn(*trimmed, 0.62, 1.0), FacesWithCentroidIn(mesh, 0.62, 1.0));
  EXPECT_EQ(report.regions_removed, 1u);
  EXPECT_GT(report.faces_removed, 0u);
  EXPECT_NEAR(report.median_spacing_m, 0.01, 0.002);
  // The support measure agrees: nothing invented after, a fifth or so before.
  auto before = MeasureSupport(mesh, points, SupportOptions());
  auto after = MeasureSupport(*trimmed, points, SupportOptions());
  ASSERT_TRUE(before.ok() && after.ok());
  EXPECT_GT(before->invented_fraction, 0.1);
  EXPECT_LT(after->invented_fraction, 0.01);
}

TEST(TrimTest, ASparsePatchInWellSampledSurfaceOpensNoHole) {
  // A few missing points (a dark spot without returns, a low-density
  // vertex for Poisson) inside a well-sampled plane: the faces there are
  // weakly supported at most, and no face goes.
  const PointCloud points = PlanePoints(1.0, 0.01, [](double x, double y) {
    return std::abs(x - 0.5) < 0.021 && std::abs(y - 0.5) < 0.021;
  });
  const Mesh mesh = Grid(100, 1.0);  // 1 cm faces
  SupportTrimReport report;
  auto trimmed = TrimUnsupported(mesh, points, TrimOptions(), &report);
  ASSERT_TRUE(trimmed.ok()) << trimmed.status().message();
  EXPECT_EQ(report.core_faces, 0u);
  EXPECT_EQ(trimmed->face_count(), mesh.face_count());
  EXPECT_EQ(CountBoundaryEdges(*trimmed), CountBoundaryEdges(mesh));
}

TEST(TrimTest, AnUnsupportedRegionSmallerThanTheMinimumStays) {
  const PointCloud points = PlanePoints(1.0, 0.01, [](double x, double) { return x > 0.4 && x < 0.6; });
  const Mesh mesh = Grid(50, 1.0);
  TrimOptions options;
  options.min_region_faces = 100000;
  auto trimmed = TrimUnsupported(mesh, points, options, nullptr);
  ASSERT_TRUE(trimmed.ok());
  EXPECT_EQ(trimmed->face_count(), mesh.face_count());
}

TEST(TrimTest, SameBytesForOneAndTwoThreads) {
  const PointCloud points = PlanePoints(1.0, 0.01, [](double x, double y) {
    return (x > 0.3 && x < 0.55) || (y > 0.7 && x > 0.6);
  });
  Mesh mesh = Grid(60, 1.0);
  mesh.origin = {100.0, 200.0, 0.0};  // the points' origin differs
  PointCloud shifted = points;
  shifted.origin = {99.0, 199.5, 0.0};
  for (size_t i = 0; i < shifted.size(); ++i) {
    shifted.positions[3 * i] += 1.0f;
    shifted.positions[3 * i + 1] += 0.5f;
  }
  TrimOptions one, two;
  one.threads = 1;
  two.threads = 2;
  auto a = TrimUnsupported(mesh, shifted, one, nullptr);
  auto b = TrimUnsupported(mesh, shifted, two, nullptr);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_LT(a->face_count(), mesh.face_count());
  EXPECT_EQ(a->indices, b->indices);
  EXPECT_EQ(a->positions, b->positions);
  EXPECT_EQ(FacesWithCentroidIn(*a, 0.36, 0.49), 0);  // origins were applied
}

TEST(TrimTest, RejectsBadOptions) {
  const PointCloud points = PlanePoints(1.0, 0.1, [](double, double) { return false; });
  TrimOptions options;
  options.grow_fraction = 0;
  auto trimmed = TrimUnsupported(Grid(4, 1.0), points, options, nullptr);
  ASSERT_FALSE(trimmed.ok());
  EXPECT_NE(trimmed.status().message().find("grow_fraction"), std::string::npos);
  options = TrimOptions();
  options.spacing_neighbors = 1000;  // more than the 121 points
  trimmed = TrimUnsupported(Grid(4, 1.0), points, options, nullptr);
  ASSERT_FALSE(trimmed.ok());
  EXPECT_NE(trimmed.status().message().find("needs more than 1000 points"), std::string::npos);
}

TEST(TrimTest, CountsBoundaryEdges) {
  EXPECT_EQ(CountBoundaryEdges(Grid(3, 1.0)), 12u);
  EXPECT_NEAR(MeanEdgeLength(Grid(1, 1.0)), (4 + 2 * std::sqrt(2.0)) / 6, 1e-6);
}

}  // namespace
}  // namespace pb
