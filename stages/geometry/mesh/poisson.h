// Screened Poisson surface reconstruction (Kazhdan & Hoppe 2013) and what
// the mesh.poisson stage does around it.
//
// The solver is Open3D 0.16's (Kazhdan's PoissonRecon inside), chosen over
// PCL's pcl::Poisson with the evidence in docs/poisson.md: 1.2-3.2x faster,
// per-vertex colors and densities, 57 Debian packages instead of 432.
// libOpen3D pulls ~100 shared libraries that take ~40 ms to load, so it is
// not linked into pointbake: poisson_open3d.cc builds the module
// `pointbake-poisson-open3d.so`, which ReconstructPoisson loads with dlopen
// the first time it runs (every other stage process starts without it).
//
// Open3D 0.16 fixes the screening weight at 2 (PoissonRecon's "point
// weight", times the degree-1 B-spline) and the samples per node at 1.5;
// its C++ API does not take them, so neither does ReconstructPoisson.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/mesh.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

// Which solver runs: Open3D 0.16's (the default) or PCL 1.13's pcl::Poisson
// (an older PoissonRecon, run with its point weight 4 and samples per node
// 1.5), each from its module (pointbake-poisson-open3d.so, pointbake-pcl.so).
// PCL's returns no densities (PoissonOutput::densities are then all 0, so
// TrimByDensity keeps everything) and no per-vertex attributes: normals and
// colors are the inverse-distance-weighted mean of the 4 nearest points'.
enum class PoissonImplementation { kOpen3d, kPcl };

struct PoissonOptions {
  PoissonImplementation implementation = PoissonImplementation::kOpen3d;
  int depth = 8;            // octree depth: the grid is at most 2^depth cells per side
  double scale = 1.1;       // reconstruction cube / the points' bounding cube
  bool linear_fit = false;  // place iso-vertices by linear interpolation
  int threads = 0;          // 0: all cores
};

struct PoissonOutput {
  // Positions relative to the cloud's origin (same origin), unit normals
  // interpolated from the points' normals, colors interpolated from the
  // points' colors when the cloud has colors. Triangles wind counter-
  // clockwise seen from the side the point normals face. Vertices sorted by
  // position, faces by their corners: the order does not depend on threads.
  Mesh mesh;
  // Per vertex: PoissonRecon's density estimate, the octree depth at which
  // the samples around the vertex support it; low where Poisson invented
  // surface far from any point (holes it closed, the outside of openings).
  std::vector<float> densities;
  // Open3D winds the triangles one way throughout; when most faces disagree
  // with the interpolated normals, every face was re-wound.
  bool rewound = false;
};

// Status::Invalid if the cloud has no normals, fewer than 3 points, a
// non-finite coordinate or depth outside [kPoissonMinDepth,
// kPoissonMaxDepth]; Status::Unsupported if the implementation's module
// cannot be loaded (the message says where it looked and how to get it).
inline constexpr int kPoissonMinDepth = 3;
inline constexpr int kPoissonMaxDepth = 14;
Expected<PoissonOutput> ReconstructPoisson(const PointCloud& cloud, const PoissonOptions& options);

// The paths tried for the module, in order: $PB_POISSON_MODULE, beside the
// running executable, the build directory this library was compiled for.
std::vector<std::string> PoissonModuleCandidates();

// Density-quantile trimming: drops every vertex whose density is below the
// `quantile` of all densities (0 keeps everything), the faces that use
// one, and vertices left unreferenced. Takes the mesh by value so that a
// caller done with it can move it in (quantile 0 then costs nothing).
struct TrimReport {
  double threshold = 0;
  uint64_t faces_removed = 0;
  uint64_t vertices_removed = 0;
};
Mesh TrimByDensity(Mesh mesh, const std::vector<float>& densities, double quantile,
                   TrimReport* report);

// Depth for a face budget. Poisson's face count grows ~4x per octree level
// while the points are dense enough to refine the tree, and slower after.
// `faces_at_probe` faces were produced at `probe_depth`; `occupied[d]` is the
// number of cells of the depth-d grid (over the same reconstruction cube)
// holding at least one point, for d in [0, occupied.size()). Predicts
// faces(d) = faces_at_probe * occupied[d] / occupied[probe_depth] and
// returns the depth in [kPoissonMinDepth, kPoissonMaxDepth] whose prediction
// is nearest `target_faces` in ratio (|log(predicted / target)|).
struct DepthChoice {
  int depth = 0;
  double predicted_faces = 0;
};
DepthChoice ChooseDepthForFaces(uint64_t target_faces, int probe_depth, uint64_t faces_at_probe,
                                const std::vector<uint64_t>& occupied);

// Occupied cells of the depth-d grids, d = 0..max_depth, over the cube that
// Open3D reconstructs in (the points' bounding cube scaled by `scale` about
// its center).
std::vector<uint64_t> OccupiedCellsPerDepth(const PointCloud& cloud, double scale, int max_depth);

}  // namespace pb
