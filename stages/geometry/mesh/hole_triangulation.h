// Triangulating one hole given as a closed polyline: CGAL's
// triangulate_hole_polyline (Liepa, "Filling holes in meshes", SGP 2003:
// minimum-weight triangulation, the weight being the worst dihedral angle,
// then the area; restricted to the 3-D Delaunay faces of the points when
// that succeeds). CGAL's compile flags (-frounding-math) stay in
// hole_triangulation.cc, the only file of its library pb_hole_triangulation.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace pb {

// `loop`: n >= 3 points (x, y, z per point, any frame), in order around the
// hole; the closing edge (n-1, 0) is implied. `third`: empty, or per edge
// (i, i+1) the opposite corner of the mesh face on that edge (3 per edge),
// so the dihedral angles with the surrounding surface count in the weight.
// Returns n - 2 triangles as indices into `loop`, each wound like the loop
// (an edge (i, i+1) of the loop appears as i -> i+1 in its triangle); empty
// if CGAL found no triangulation.
std::vector<std::array<uint32_t, 3>> TriangulateHoleLoop(std::span<const double> loop,
                                                          std::span<const double> third);

}  // namespace pb
