#include "stages/geometry/mesh/holes.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "stages/geometry/mesh/clean.h"
#include "stages/geometry/mesh/trim.h"

namespace pb {
namespace {

// An n x n quad grid over [0, 1]^2 at z = 0 without the quads for which
// `hole(i, j)` is true.
template <typename Hole>
Mesh GridWithHoles(int n, Hole hole) {
  Mesh mesh;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      mesh.positions.insert(mesh.positions.end(),
                            {static_cast<float>(i) / n, static_cast<float>(j) / n, 0.0f});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      if (hole(i, j)) continue;
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
    }
  }
  return mesh;
}

// +1 when every face's normal points up (+z), -1 when all point down.
int Winding(const Mesh& mesh) {
  int up = 0, down = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const float* p[3];
    for (int k = 0; k < 3; ++k) p[k] = &mesh.positions[3 * mesh.indices[3 * f + k]];
    const double z = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
    (z > 0 ? up : down)++;
  }
  return down == 0 ? 1 : up == 0 ? -1 : 0;
}

TEST(HolesTest, FindsTheOuterBorderAndEachHoleOnce) {
  const Mesh mesh = GridWithHoles(10, [](int i, int j) {
    return (i == 2 && j == 2) || (i >= 5 && i <= 7 && j >= 5 && j <= 7);
  });
  std::vector<std::vector<uint32_t>> loops = BoundaryLoops(mesh);
  ASSERT_EQ(loops.size(), 3u);
  std::vector<size_t> sizes;
  for (const auto& loop : loops) sizes.push_back(loop.size());
  std::sort(sizes.begin(), sizes.end());
  EXPECT_EQ(sizes, (std::vector<size_t>{4, 12, 40}));
}

TEST(HolesTest, FillsSmallHolesAndKeepsLargeOnesAndTheBorder) {
  // Holes of 1 quad (4 edges of 0.1 m) and of 3 x 3 quads (12 edges, 1.2 m).
  Mesh mesh = GridWithHoles(10, [](int i, int j) {
    return (i == 2 && j == 2) || (i >= 5 && i <= 7 && j >= 5 && j <= 7);
  });
  const size_t faces = mesh.face_count();
  HoleFillReport report;
  ASSERT_TRUE(FillSmallHoles(mesh, {.max_edges = 8, .max_perimeter_m = 0}, &report).ok());
  EXPECT_EQ(report.loops, 3u);
  EXPECT_EQ(report.holes_filled, 1u);
  EXPECT_EQ(report.faces_added, 2u);
  EXPECT_EQ(mesh.face_count(), faces + 2);
  EXPECT_EQ(BoundaryLoops(mesh).size(), 2u);  // the big hole and the border
  EXPECT_EQ(CountBoundaryEdges(mesh), 40u + 12u);
  EXPECT_EQ(Winding(mesh), 1);  // the patch is wound like its surroundings
  EXPECT_TRUE(CheckManifold(mesh).ok());

  // By perimeter: 1.2 m fills the big hole too, never the 4 m border.
  ASSERT_TRUE(FillSmallHoles(mesh, {.max_edges = 0, .max_perimeter_m = 1.5}, &report).ok());
  EXPECT_EQ(report.holes_filled, 1u);
  EXPECT_EQ(CountBoundaryEdges(mesh), 40u);
  EXPECT_EQ(Winding(mesh), 1);
  EXPECT_TRUE(CheckManifold(mesh).ok());
}

TEST(HolesTest, TheReachKeepsWideHolesOpenAndFillsLongNarrowOnes) {
  // A slit of 1 x 8 quads (18 edges, 1.8 m; its patch within 0.05 m of the
  // rim) and a hole of 3 x 3 quads (12 edges, 1.2 m; its middle 0.15 m from
  // the rim), both within the perimeter.
  Mesh mesh = GridWithHoles(10, [](int i, int j) {
    return (j == 2 && i >= 1 && i <= 8) || (i >= 5 && i <= 7 && j >= 6 && j <= 8);
  });
  HoleFillReport report;
  ASSERT_TRUE(
      FillSmallHoles(mesh, {.max_edges = 0, .max_perimeter_m = 2.0, .max_reach_m = 0.1}, &report)
          .ok());
  EXPECT_EQ(report.loops, 3u);
  EXPECT_EQ(report.holes_filled, 1u);
  EXPECT_EQ(report.holes_too_wide, 1u);
  EXPECT_EQ(CountBoundaryEdges(mesh), 40u + 12u);  // the border and the square hole
  EXPECT_EQ(Winding(mesh), 1);
  EXPECT_TRUE(CheckManifold(mesh).ok());
  // A reach just below the slit's half width keeps it open too.
  Mesh again = GridWithHoles(10, [](int i, int j) { return j == 2 && i >= 1 && i <= 8; });
  ASSERT_TRUE(
      FillSmallHoles(again, {.max_edges = 0, .max_perimeter_m = 2.0, .max_reach_m = 0.045}, &report)
          .ok());
  EXPECT_EQ(report.holes_filled, 0u);
  EXPECT_EQ(report.holes_too_wide, 1u);
}

TEST(HolesTest, TheOutlineOfAnOpenSheetIsNoHole) {
  // A ridge of 6 x 2 quads alone, its middle row raised 0.05 m: its outline
  // (16 edges, 1.6 m, within 0.1 m of itself) passes the size and reach
  // tests, but its patch would span the ridge underneath, about as large as
  // the sheet, closing it into a shell.
  Mesh strip = GridWithHoles(10, [](int i, int j) { return !(j < 2 && i < 6); });
  for (int i = 0; i <= 6; ++i) strip.positions[3 * (11 + i) + 2] = 0.05f;
  const HoleFillOptions options = {
      .max_edges = 0, .max_perimeter_m = 2.0, .max_reach_m = 0.15, .max_component_fraction = 0.25};
  Mesh kept = strip;
  HoleFillReport report;
  ASSERT_TRUE(FillSmallHoles(kept, options, &report).ok());
  EXPECT_EQ(report.loops, 1u);
  EXPECT_EQ(report.holes_filled, 0u);
  EXPECT_EQ(report.outlines_kept, 1u);
  EXPECT_EQ(kept.indices, strip.indices);
  Mesh closed = strip;
  HoleFillOptions no_outline_test = options;
  no_outline_test.max_component_fraction = 0;
  ASSERT_TRUE(FillSmallHoles(closed, no_outline_test, &report).ok());
  EXPECT_EQ(report.holes_filled, 1u);
  EXPECT_EQ(CountBoundaryEdges(closed), 0u);
}

TEST(HolesTest, CleanFillsHolesBeforeDecimationCanGrowThem) {
  Mesh mesh = GridWithHoles(20, [](int i, int j) { return (i == 4 && j == 4) || (i == 12 && j == 9); });
  CleanOptions options;
  options.min_component_faces = 0;
  options.hole_max_edges = 8;
  CleanReport report;
  auto cleaned = CleanMesh(mesh, options, &report);
  ASSERT_TRUE(cleaned.ok()) << cleaned.status().message();
  EXPECT_EQ(report.boundary_loops, 3u);
  EXPECT_EQ(report.holes_filled, 2u);
  EXPECT_EQ(report.hole_faces, 4u);
  EXPECT_EQ(CountBoundaryEdges(*cleaned), 80u);
  // Off by default in the library.
  auto unfilled = CleanMesh(mesh, CleanOptions(), &report);
  ASSERT_TRUE(unfilled.ok());
  EXPECT_EQ(report.holes_filled, 0u);
  EXPECT_EQ(CountBoundaryEdges(*unfilled), 80u + 8u);
}

TEST(HolesTest, RejectsNegativeLimits) {
  Mesh mesh = GridWithHoles(2, [](int, int) { return false; });
  const Status status = FillSmallHoles(mesh, {.max_edges = -1, .max_perimeter_m = 0}, nullptr);
  EXPECT_FALSE(status.ok());
  EXPECT_FALSE(
      FillSmallHoles(mesh, {.max_edges = 1, .max_perimeter_m = 0, .max_reach_m = -1}, nullptr).ok());
}

}  // namespace
}  // namespace pb
