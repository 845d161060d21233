// Least-squares conformal maps for UV charts (the `conformal` method of
// atlas.h; used by surface_charts.cc).
//
// Lévy, Petitjean, Ray, Maillot, "Least squares conformal maps for automatic
// texture atlas generation", SIGGRAPH 2002: per triangle, in its own
// orthonormal 2-D frame, the map's d/dz-bar (the non-holomorphic part) is
// zero for a similarity; the sum over triangles of area x |dU/dz-bar|^2 is
// minimized with two vertices pinned (the pair found by two farthest-point
// sweeps), by the normal equations in complex form (U = u + i v: one
// unknown per vertex, a Hermitian matrix) and a sparse LDLᴴ factorization
// (Eigen's SimplicialLDLT). Departure: the paper's free boundary is kept but
// no global (multi-chart) solve is done: each chart is solved alone, so the
// atlas is a set of independent problems (parallel, deterministic).
//
// Eigen's templates stay in conformal.cc (library pb_uv_param), so that a
// change elsewhere in the atlas does not recompile them.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace pb {

// Flattens one edge-connected chart. `positions`: 3 per vertex (meters,
// any origin); `corners`: 3 vertex indices per face, counter-clockwise seen
// from the front. Faces with no area are left out of the energy (their
// vertices follow their neighbours'). Writes 2 coordinates per vertex to
// `uv` (meters up to one similarity; orientation preserved: front faces stay
// counter-clockwise wherever the map does not fold). Returns false when the
// system cannot be solved (fewer than two distinct vertices, or a
// factorization failure); the caller then splits the chart.
bool LscmFlatten(std::span<const double> positions, std::span<const uint32_t> corners,
                 std::vector<double>* uv);

}  // namespace pb
