// The three bakes against ground truth on a small synthetic room: the
// paper's claim in miniature. One low mesh (Poisson depth 7, decimated,
// unwrapped) is baked from its own vertex colors (LPM), from a high mesh
// (Poisson depth 8, Remeshing's bake) and from the points (the paper). Each
// covered texel's color is compared with the true albedo at the texel's 3-D
// position (SampleSurface); texels off the true surface by more than 1 cm
// (Poisson's surface across openings) or in openings are skipped.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "stages/geometry/bake/bake.h"
#include "stages/geometry/bake/from_mesh.h"
#include "stages/geometry/bake/from_points.h"
#include "stages/geometry/bake/truth.h"
#include "stages/geometry/mesh/clean.h"
#include "stages/geometry/mesh/decimate.h"
#include "stages/geometry/points/normals.h"
#include "stages/geometry/mesh/poisson.h"
#include "stages/geometry/synth/scanner.h"
#include "stages/geometry/synth/scene.h"
#include "stages/geometry/uv/atlas.h"

namespace pb {
namespace {

constexpr int kSize = 512;

struct Fixture {
  SynthScene scene;
  PointCloud cloud;  // with normals
  double spacing_m = 0;
  Mesh low;          // unwrapped
  Mesh high;
};

Fixture* fixture = nullptr;

Mesh Poisson(const PointCloud& cloud, int depth) {
  PoissonOptions options;
  options.depth = depth;
  auto out = ReconstructPoisson(cloud, options);
  EXPECT_TRUE(out.ok()) << out.status().message();
  if (!out.ok()) return Mesh();
  Mesh trimmed = TrimByDensity(std::move(out->mesh), out->densities, 0.01, nullptr);
  CleanReport report;
  auto clean = CleanMesh(trimmed, CleanOptions{}, &report);

  EXPECT_TRUE(clean.ok());
  return clean.ok() ? std::move(*clean) : Mesh();
}

class BakeCompareTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (fixture) return;
    fixture = new Fixture;
    auto scene = MakeSynthScene("room", 11, Vec3{2.4, 2.0, 2.2});
    ASSERT_TRUE(scene.ok());
    fixture->scene = *scene;
    SynthScanOptions scan;
    scan.target_points = 800000;
    scan.stations = 2;
    auto result = SimulateScan(fixture->scene, scan);
    ASSERT_TRUE(result.ok());
    fixture->cloud = std::move(result->cloud);
    fixture->spacing_m = result->median_spacing_m;
    ASSERT_TRUE(EstimateNormals(fixture->cloud, NormalOptions{}).ok());

    fixture->high = Poisson(fixture->cloud, 8);
    DecimateOptions decimate;
    decimate.target_faces = 6000;
    auto low = DecimateMesh(Poisson(fixture->cloud, 7), decimate, nullptr);
    ASSERT_TRUE(low.ok());
    UnwrapOptions unwrap;
    unwrap.size_texels = kSize;
    unwrap.gutter_texels = 2;
    auto unwrapped = UnwrapMesh(*low, unwrap, nullptr);
    ASSERT_TRUE(unwrapped.ok()) << unwrapped.status().message();
    fixture->low = std::move(*unwrapped);
  }

  static double ColorError(const BakeResult& result, size_t* compared = nullptr) {
    auto error = ColorErrorAgainstTruth(fixture->scene, result);
    EXPECT_TRUE(error.ok());
    if (!error.ok() || error->texels == 0) return 1e9;
    if (compared) *compared = error->texels;
    return error->mean_abs;
  }
};

TEST_F(BakeCompareTest, PointTransferBeatsVertexColorsAndMatchesTheHighMeshBake) {
  ASSERT_GT(fixture->low.face_count(), 0u);
  BakeOptions options;
  options.size = kSize;
  options.gutter = 2;

  auto vertex = BakeVertexColors(fixture->low, options);
  ASSERT_TRUE(vertex.ok()) << vertex.status().message();
  FromMeshOptions cage;
  cage.cage_m = 0.03;
  auto from_mesh = BakeFromMesh(fixture->low, fixture->high, options, cage);
  ASSERT_TRUE(from_mesh.ok()) << from_mesh.status().message();
  FromPointsOptions transfer;
  transfer.max_distance_m = 4 * fixture->spacing_m;
  transfer.max_angle_deg = 90;
  transfer.splat_sigma_m = fixture->spacing_m;
  PointCloud copy = fixture->cloud;
  FromPointsReport report;
  auto from_points = BakeFromPoints(fixture->low, std::move(copy), options, transfer, &report);
  ASSERT_TRUE(from_points.ok()) << from_points.status().message();
  // The same with the neighbours' points (bake.from_points' default).
  transfer.neighbors = true;
  copy = fixture->cloud;
  auto with_neighbors = BakeFromPoints(fixture->low, std::move(copy), options, transfer);
  ASSERT_TRUE(with_neighbors.ok()) << with_neighbors.status().message();

  size_t compared = 0;
  const double vertex_error = ColorError(*vertex, &compared);
  const double mesh_error = ColorError(*from_mesh);
  const double points_error = ColorError(*from_points);
  const double neighbors_error = ColorError(*with_neighbors);
  std::printf("spacing %.2f mm, low %zu faces, high %zu faces, %zu texels compared\n"
              "mean |baked - true albedo| (0..255): vertex colors %.2f, from mesh %.2f, "
              "from points %.2f, with neighbours %.2f; points assigned %zu of %zu\n",
              fixture->spacing_m * 1e3, fixture->low.face_count(), fixture->high.face_count(),
              compared, vertex_error, mesh_error, points_error, neighbors_error,
              report.assign.assigned, report.assign.points);
  RecordProperty("vertex_colors_error", std::to_string(vertex_error));
  RecordProperty("from_mesh_error", std::to_string(mesh_error));
  RecordProperty("from_points_error", std::to_string(points_error));
  RecordProperty("from_points_neighbors_error", std::to_string(neighbors_error));
  EXPECT_GT(compared, size_t(kSize * kSize / 4));
  // "Clearly lower" than the low mesh's own vertex colors...
  EXPECT_LT(points_error, 0.8 * vertex_error);
  // ...and no worse than baking from the high mesh.
  EXPECT_LE(points_error, mesh_error * 1.02);
  // The neighbours' points replace the corners' smooth colors at the edges
  // and corners of every face: closer to the truth than the paper's.
  EXPECT_LT(neighbors_error, points_error);
}

}  // namespace
}  // namespace pb
