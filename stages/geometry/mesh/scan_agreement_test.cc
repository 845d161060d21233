// Mesh-versus-scan figures on hand-made meshes and clouds with known answers.
#include "stages/geometry/mesh/scan_agreement.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace pb {
namespace {

// The unit square [0, 1]^2 at z = 0 as n x n quads (2 n^2 faces), at `origin`.
Mesh GridMesh(int n, std::array<double, 3> origin) {
  Mesh mesh;
  mesh.origin = origin;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) mesh.positions.insert(mesh.positions.end(), {float(i) / n, float(j) / n, 0.0f});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, d, a, d, c});
    }
  return mesh;
}

TEST(ScanAgreementTest, BoundaryEdgesOfAnOpenGridAndAClosedTetrahedron) {
  EXPECT_EQ(CountBoundaryEdges(GridMesh(10, {0, 0, 0})), 40u);
  Mesh tetrahedron;
  tetrahedron.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  tetrahedron.indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  EXPECT_EQ(CountBoundaryEdges(tetrahedron), 0u);
  // A UV seam: the face 1-2-3 gets its own copies of its vertices, at the
  // same positions, as uv.unwrap makes them. Still closed.
  Mesh seamed = tetrahedron;
  seamed.positions.insert(seamed.positions.end(), {1, 0, 0, 0, 1, 0, 0, 0, 1});
  seamed.indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 4, 5, 6};
  EXPECT_EQ(CountBoundaryEdges(seamed), 0u);
}

TEST(ScanAgreementTest, InventedAreaMissingPointsAndBoundary) {
  // The mesh: the unit square, edges of 1 cm. The scan, 1 cm apart: the left
  // half of the square (x <= 0.5) 1 cm above it (within 3 spacings: seen), plus
  // 250 points 0.5 m above (not on the mesh: missing). Georeferenced origins
  // that differ by half a meter in x.
  const Mesh mesh = GridMesh(100, {1000.0, 2000.0, 10.0});
  PointCloud scan;
  scan.origin = {1000.5, 2000.0, 10.0};
  size_t on_surface = 0;
  for (int j = 0; j <= 100; ++j)
    for (int i = 0; i <= 50; ++i) {
      scan.positions.insert(scan.positions.end(), {float(i * 0.01 - 0.5), float(j * 0.01), 0.01f});
      ++on_surface;
    }
  for (int k = 0; k < 250; ++k)
    scan.positions.insert(scan.positions.end(), {float((k % 25) * 0.01 - 0.3), float((k / 25) * 0.01 + 0.2), 0.5f});
  const std::vector<float> spacing(scan.size(), 0.01f);
  ScanAgreementOptions options;
  options.samples = 100000;
  Expected<ScanAgreement> r = Status::Internal("not run");
  tbb::task_arena(2).execute([&] { r = MeasureScanAgreement(mesh, scan, spacing, options); });
  ASSERT_TRUE(r.ok()) << r.status().message();
  // Seen: x <= 0.5 + sqrt(0.03^2 - 0.01^2) = 0.528 (the points are 1 cm above).
  EXPECT_NEAR(r->invented_area_fraction, 1 - 0.528, 0.006);
  EXPECT_EQ(r->scan_points_measured, scan.size());
  EXPECT_DOUBLE_EQ(r->missing_fraction, 250.0 / double(on_surface + 250));
  EXPECT_EQ(r->boundary_edges, 400u);
  EXPECT_DOUBLE_EQ(r->boundary_edges_per_1000_faces, 400.0 / 20000 * 1000);
  EXPECT_NEAR(r->mean_edge_m, (0.01 + 0.01 + 0.01 * std::sqrt(2.0)) / 3, 1e-6);
  EXPECT_FLOAT_EQ(r->median_spacing_m, 0.01f);
  EXPECT_EQ(r->mesh_samples, 100000u);
  EXPECT_EQ(r->mesh_to_scan.samples, 100000u);
  EXPECT_NEAR(r->scan_to_mesh.max_m, 0.5, 1e-6);  // the points half a meter above
  EXPECT_NEAR(r->scan_to_mesh.p95_m, 0.01, 1e-6);  // 2.3 % of the points are up there

  // The same with one thread: the same figures.
  Expected<ScanAgreement> one = Status::Internal("not run");
  tbb::task_arena(1).execute([&] { one = MeasureScanAgreement(mesh, scan, spacing, options); });
  ASSERT_TRUE(one.ok());
  EXPECT_EQ(one->invented_area_fraction, r->invented_area_fraction);
  EXPECT_EQ(one->missing_fraction, r->missing_fraction);

  // The 250 points flagged as strays (points/strays.h): not missing, not
  // measured; the invented area stays.
  std::vector<uint8_t> strays(scan.size(), 0);
  std::fill(strays.begin() + std::ptrdiff_t(on_surface), strays.end(), uint8_t{1});
  options.strays = strays;
  Expected<ScanAgreement> flagged = Status::Internal("not run");
  tbb::task_arena(2).execute([&] { flagged = MeasureScanAgreement(mesh, scan, spacing, options); });
  ASSERT_TRUE(flagged.ok()) << flagged.status().message();
  EXPECT_EQ(flagged->missing_fraction, 0.0);
  EXPECT_EQ(flagged->scan_points_measured, on_surface);
  EXPECT_EQ(flagged->stray_points, 250u);
  EXPECT_EQ(flagged->invented_area_fraction, r->invented_area_fraction);
  strays.pop_back();
  options.strays = strays;
  EXPECT_FALSE(MeasureScanAgreement(mesh, scan, spacing, options).ok());  // one flag short
}

// The invented-area rule at the vertices: the scan covers x <= 0.5 of the
// unit square 1 cm above it, so vertices up to x = 0.52 are seen
// (sqrt(0.02^2 + 0.01^2) < 3 cm) and from x = 0.53 on invented.
TEST(ScanAgreementTest, PerVertexDistanceAndInventedFlag) {
  const Mesh mesh = GridMesh(100, {1000.0, 2000.0, 10.0});
  PointCloud scan;
  scan.origin = {1000.5, 2000.0, 10.0};
  for (int j = 0; j <= 100; ++j)
    for (int i = 0; i <= 50; ++i) scan.positions.insert(scan.positions.end(), {float(i * 0.01 - 0.5), float(j * 0.01), 0.01f});
  const std::vector<float> spacing(scan.size(), 0.01f);
  Expected<VertexScanAgreement> r = Status::Internal("not run");
  tbb::task_arena(2).execute([&] { r = MeasureVertexScanAgreement(mesh, scan, spacing); });
  ASSERT_TRUE(r.ok()) << r.status().message();
  ASSERT_EQ(r->distance_to_scan_m.size(), mesh.vertex_count());
  ASSERT_EQ(r->invented.size(), mesh.vertex_count());
  for (int j = 0; j <= 100; ++j)
    for (int i = 0; i <= 100; ++i) {
      const size_t v = size_t(j * 101 + i);
      const double dx = std::max(0.0, i * 0.01 - 0.5);
      EXPECT_NEAR(r->distance_to_scan_m[v], std::sqrt(dx * dx + 0.0001), 2e-5) << i << " " << j;
      EXPECT_EQ(r->invented[v], i >= 53 ? 1 : 0) << i << " " << j;
    }
  EXPECT_FALSE(MeasureVertexScanAgreement(mesh, scan, std::vector<float>(3, 0.01f)).ok());
}

TEST(ScanAgreementTest, ACoarseMeshIsNotInventionWithinItsOwnEdge) {
  // Two triangles (edges of 1 m) and a scan of the left half, 1 cm apart: the
  // threshold becomes the mean edge (1.14 m), so nothing counts as invented.
  const Mesh mesh = GridMesh(1, {0, 0, 0});
  PointCloud scan;
  for (int j = 0; j <= 100; ++j)
    for (int i = 0; i <= 50; ++i) scan.positions.insert(scan.positions.end(), {float(i * 0.01), float(j * 0.01), 0.0f});
  const std::vector<float> spacing(scan.size(), 0.01f);
  Expected<ScanAgreement> r = MeasureScanAgreement(mesh, scan, spacing);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->invented_area_fraction, 0.0);
  EXPECT_EQ(r->missing_fraction, 0.0);
  EXPECT_EQ(r->boundary_edges, 4u);
}

TEST(ScanAgreementTest, RejectsBadInput) {
  const Mesh mesh = GridMesh(2, {0, 0, 0});
  PointCloud scan;
  scan.positions = {0, 0, 0, 1, 1, 0};
  const std::vector<float> one(1, 0.01f), two(2, 0.01f);
  EXPECT_FALSE(MeasureScanAgreement(mesh, scan, one).ok());
  EXPECT_FALSE(MeasureScanAgreement(mesh, PointCloud{}, {}).ok());
  ScanAgreementOptions options;
  options.spacing_factor = 0;
  EXPECT_FALSE(MeasureScanAgreement(mesh, scan, two, options).ok());
  EXPECT_TRUE(MeasureScanAgreement(mesh, scan, two).ok());
}

TEST(ScanAgreementTest, TheCallersIndexGivesTheSameFiguresAndMustBeOfTheScan) {
  // A 1 m grid of 5 cm cells and a scan of its left 30 cm: the rest is invented.
  const Mesh mesh = GridMesh(20, {0, 0, 0});
  PointCloud scan;
  for (int j = 0; j <= 100; ++j)
    for (int i = 0; i <= 30; ++i) scan.positions.insert(scan.positions.end(), {float(i * 0.01), float(j * 0.01), 0.002f});
  const std::vector<float> spacing(scan.size(), 0.01f);
  Expected<KnnIndex> index = KnnIndex::Build(scan.positions);
  ASSERT_TRUE(index.ok());
  Expected<ScanAgreement> own = MeasureScanAgreement(mesh, scan, spacing);
  Expected<ScanAgreement> given = MeasureScanAgreement(mesh, scan, *index, spacing);
  ASSERT_TRUE(own.ok() && given.ok());
  EXPECT_EQ(own->invented_area_fraction, given->invented_area_fraction);
  EXPECT_GT(given->invented_area_fraction, 0.0);
  EXPECT_EQ(own->missing_fraction, given->missing_fraction);
  Expected<VertexScanAgreement> own_v = MeasureVertexScanAgreement(mesh, scan, spacing);
  Expected<VertexScanAgreement> given_v = MeasureVertexScanAgreement(mesh, scan, *index, spacing);
  ASSERT_TRUE(own_v.ok() && given_v.ok());
  EXPECT_EQ(own_v->invented, given_v->invented);
  EXPECT_EQ(own_v->distance_to_scan_m, given_v->distance_to_scan_m);

  Expected<KnnIndex> other = KnnIndex::Build(std::vector<float>{0, 0, 0, 1, 1, 0});
  ASSERT_TRUE(other.ok());
  EXPECT_FALSE(MeasureScanAgreement(mesh, scan, *other, spacing).ok());
  EXPECT_FALSE(MeasureVertexScanAgreement(mesh, scan, *other, spacing).ok());
}

}  // namespace
}  // namespace pb
