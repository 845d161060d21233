// The only file of pb_hole_triangulation, and the only mesh file that
// includes CGAL (see hole_triangulation.h).
#include "stages/geometry/mesh/hole_triangulation.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>

#include <algorithm>
#include <iterator>

namespace pb {

std::vector<std::array<uint32_t, 3>> TriangulateHoleLoop(std::span<const double> loop,
                                                          std::span<const double> third) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Point = Kernel::Point_3;
  std::vector<std::array<uint32_t, 3>> triangles;
  const size_t n = loop.size() / 3;
  if (n < 3) return triangles;
  std::vector<Point> points, third_points;
  points.reserve(n);
  for (size_t i = 0; i < n; ++i) points.emplace_back(loop[3 * i], loop[3 * i + 1], loop[3 * i + 2]);
  if (third.size() == loop.size()) {
    for (size_t i = 0; i < n; ++i) {
      third_points.emplace_back(third[3 * i], third[3 * i + 1], third[3 * i + 2]);
    }
  }
  std::vector<CGAL::Triple<int, int, int>> patch;
  CGAL::Polygon_mesh_processing::triangulate_hole_polyline(points, third_points,
                                                           std::back_inserter(patch));
  for (const auto& t : patch) {
    // The dynamic program over the polyline emits (i, m, k) with i < m < k,
    // which runs the loop's edges forward; sort to be sure of it.
    std::array<int, 3> corner{t.first, t.second, t.third};
    std::sort(corner.begin(), corner.end());
    if (corner[0] < 0 || corner[2] >= static_cast<int>(n)) return {};
    triangles.push_back({static_cast<uint32_t>(corner[0]), static_cast<uint32_t>(corner[1]),
                         static_cast<uint32_t>(corner[2])});
  }
  return triangles;
}

}  // namespace pb
