// The calls between the point algorithms (normals.cc, outliers.cc,
// smooth.cc) and the modules that hold other libraries' implementations of
// them: pointbake-pcl.so (stages/geometry/mesh/pcl_module.cc) and
// pointbake-poisson-open3d.so (stages/geometry/mesh/poisson_open3d.cc),
// loaded on first use (stages/geometry/core/module.h). Both sides are built
// from this tree by the same compiler, so C++ types cross; the ABI number in
// each symbol's name changes whenever its struct or the meaning of a field
// does. Every call returns false and sets *error on failure.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "stages/geometry/core/point_cloud.h"

namespace pb {

// Unoriented k-NN PCA normals: `normals` gets 3 floats per point, unit
// length (or 0, 0, 0 where the library could not fit a plane).
struct NormalsModuleCall {
  const PointCloud* cloud = nullptr;  // finite positions, >= 3 points
  int k = 16;                         // neighbours, the point included
  int threads = 1;                    // >= 1
  std::vector<float>* normals = nullptr;
  std::string* error = nullptr;
};

// Statistical outlier removal: `kept` gets the indices of the points kept,
// ascending.
struct OutliersModuleCall {
  const PointCloud* cloud = nullptr;  // finite positions, >= 2 points
  int k = 16;                         // neighbours, the point excluded
  double std_ratio = 2.0;
  std::vector<uint32_t>* kept = nullptr;
  std::string* error = nullptr;
};

// Moving-least-squares projection of every point: `positions` gets 3 floats
// per output point (relative to cloud->origin), `source` the input index of
// each output point, in any order.
struct SmoothModuleCall {
  const PointCloud* cloud = nullptr;  // finite positions, >= 3 points
  double radius_m = 0;                // > 0
  int polynomial_order = 2;           // 0..3
  int threads = 1;                    // >= 1
  std::vector<float>* positions = nullptr;
  std::vector<uint32_t>* source = nullptr;
  std::string* error = nullptr;
};

}  // namespace pb

#define PB_PCL_NORMALS_SYMBOL "pb_pcl_normals_v1"
extern "C" bool pb_pcl_normals_v1(pb::NormalsModuleCall* call);
#define PB_OPEN3D_NORMALS_SYMBOL "pb_open3d_normals_v1"
extern "C" bool pb_open3d_normals_v1(pb::NormalsModuleCall* call);
#define PB_PCL_OUTLIERS_SYMBOL "pb_pcl_outliers_v1"
extern "C" bool pb_pcl_outliers_v1(pb::OutliersModuleCall* call);
#define PB_PCL_SMOOTH_SYMBOL "pb_pcl_smooth_v1"
extern "C" bool pb_pcl_smooth_v1(pb::SmoothModuleCall* call);
