// ForEachIntersectingBoxPair and ChartFacesOverlap against brute force.
#include "stages/geometry/uv/charts.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <utility>
#include <vector>

namespace pb {
namespace {

TEST(UvChartsTest, BoxPairsAreEveryIntersectingPairOnce) {
  // Boxes of mixed sizes (a few large, many small, some points and
  // duplicates), by a fixed multiplicative hash.
  uint64_t state = 12345;
  auto random = [&]() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return double(state >> 11) / double(1ull << 53);
  };
  std::vector<Box2> boxes;
  for (int i = 0; i < 600; ++i) {
    const double x = 10 * random(), y = 5 * random();
    const double size = i % 50 == 0 ? 3 * random() : i % 7 == 0 ? 0.0 : 0.4 * random();
    boxes.push_back({x, y, x + size * random(), y + size * random()});
    if (i % 97 == 0) boxes.push_back(boxes.back());
  }
  std::set<std::pair<uint32_t, uint32_t>> expected;
  for (uint32_t i = 0; i < boxes.size(); ++i) {
    for (uint32_t j = i + 1; j < boxes.size(); ++j) {
      const Box2 &a = boxes[i], &b = boxes[j];
      if (!(a[0] > b[2] || b[0] > a[2] || a[1] > b[3] || b[1] > a[3])) expected.insert({i, j});
    }
  }
  std::set<std::pair<uint32_t, uint32_t>> visited;
  size_t visits = 0;
  ForEachIntersectingBoxPair(boxes, [&](uint32_t i, uint32_t j) {
    EXPECT_LT(i, j);
    visited.insert({i, j});
    ++visits;
    return true;
  });
  EXPECT_GT(expected.size(), 200u);
  EXPECT_EQ(visits, expected.size());
  EXPECT_EQ(visited, expected);
  // Stops when the visit says so.
  visits = 0;
  ForEachIntersectingBoxPair(boxes, [&](uint32_t, uint32_t) { return ++visits < 10; });
  EXPECT_EQ(visits, 10u);
}

// A chart of the given points (u, v) and faces, with the boxes
// ChartFacesOverlap takes; `brute` receives whether TrianglesOverlap finds
// any pair of faces overlapping.
FlatChart MakeChart(const std::vector<double>& uv, const std::vector<uint32_t>& corners,
                    double tolerance, std::vector<Box2>* boxes, bool* brute) {
  FlatChart chart;
  chart.uv_m = uv;
  chart.corners = corners;
  for (uint32_t f = 0; f < corners.size() / 3; ++f) chart.faces.push_back(f);
  for (uint32_t v = 0; v < uv.size() / 2; ++v) chart.vertices.push_back(v);
  std::vector<std::array<double, 6>> t(chart.faces.size());
  boxes->clear();
  for (size_t f = 0; f < t.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      t[f][2 * k] = uv[2 * corners[3 * f + k]];
      t[f][2 * k + 1] = uv[2 * corners[3 * f + k] + 1];
    }
    boxes->push_back({std::min({t[f][0], t[f][2], t[f][4]}), std::min({t[f][1], t[f][3], t[f][5]}),
                      std::max({t[f][0], t[f][2], t[f][4]}),
                      std::max({t[f][1], t[f][3], t[f][5]})});
  }
  *brute = false;
  for (size_t i = 0; i < t.size(); ++i) {
    for (size_t j = i + 1; j < t.size(); ++j) *brute |= TrianglesOverlap(t[i], t[j], tolerance);
  }
  return chart;
}

TEST(UvChartsTest, ChartFacesOverlapAgreesWithEveryPairTested) {
  constexpr double kTolerance = 1e-9;
  std::vector<Box2> boxes;
  bool brute = true;
  // A flat grid, diagonals alternating: faces meet along edges and at
  // corners (with collinear sides), none overlaps.
  std::vector<double> grid;
  std::vector<uint32_t> grid_faces;
  for (int j = 0; j <= 6; ++j) {
    for (int i = 0; i <= 6; ++i) grid.insert(grid.end(), {double(i), double(j)});
  }
  for (uint32_t j = 0; j < 6; ++j) {
    for (uint32_t i = 0; i < 6; ++i) {
      const uint32_t a = 7 * j + i, b = a + 1, c = a + 7, d = c + 1;
      if ((i + j) % 2 == 0) {
        grid_faces.insert(grid_faces.end(), {a, b, d, a, d, c});
      } else {
        grid_faces.insert(grid_faces.end(), {a, b, c, b, d, c});
      }
    }
  }
  FlatChart chart = MakeChart(grid, grid_faces, kTolerance, &boxes, &brute);
  EXPECT_FALSE(brute);
  EXPECT_FALSE(ChartFacesOverlap(chart, boxes, kTolerance));

  // A fan winding twice around its centre: twelve counter-clockwise faces
  // of 60 degrees, each overlapping the one half the fan away, which shares
  // only the centre with it.
  std::vector<double> fan = {0, 0};
  std::vector<uint32_t> fan_faces;
  for (uint32_t k = 0; k <= 12; ++k) {
    const double a = M_PI / 3 * k, r = 1 + 0.05 * k;
    fan.insert(fan.end(), {r * std::cos(a), r * std::sin(a)});
    if (k > 0) fan_faces.insert(fan_faces.end(), {0, k, k + 1});
  }
  chart = MakeChart(fan, fan_faces, kTolerance, &boxes, &brute);
  EXPECT_TRUE(brute);
  EXPECT_TRUE(ChartFacesOverlap(chart, boxes, kTolerance));
  // Its first six faces are one turn: no overlap.
  fan_faces.resize(18);
  chart = MakeChart(fan, fan_faces, kTolerance, &boxes, &brute);
  EXPECT_FALSE(brute);
  EXPECT_FALSE(ChartFacesOverlap(chart, boxes, kTolerance));

  // Two counter-clockwise faces on the same side of their shared edge
  // (which both run 0 -> 1: a fold), and the same two unfolded.
  const std::vector<double> fold = {0, 0, 2, 0, 1, 1, 1.2, 0.5, 1, -1};
  chart = MakeChart(fold, {0, 1, 2, 0, 1, 3}, kTolerance, &boxes, &brute);
  EXPECT_TRUE(brute);
  EXPECT_TRUE(ChartFacesOverlap(chart, boxes, kTolerance));
  chart = MakeChart(fold, {0, 1, 2, 1, 0, 4}, kTolerance, &boxes, &brute);
  EXPECT_FALSE(brute);
  EXPECT_FALSE(ChartFacesOverlap(chart, boxes, kTolerance));
}

}  // namespace
}  // namespace pb
