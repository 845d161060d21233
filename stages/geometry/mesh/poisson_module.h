// The call between ReconstructPoisson (poisson.cc, in pointbake) and the
// Open3D module (poisson_open3d.cc, pointbake-poisson-open3d.so) or the PCL
// module (pcl_module.cc, pointbake-pcl.so). Both are
// built from this tree by the same compiler, so C++ types cross; the ABI
// number in the symbol's name changes whenever this struct or the meaning of
// a field does.
#pragma once

#include <string>
#include <vector>

#include "stages/geometry/core/mesh.h"
#include "stages/geometry/core/point_cloud.h"
#include "stages/geometry/mesh/poisson.h"

namespace pb {

struct PoissonModuleCall {
  const PointCloud* cloud = nullptr;  // has normals; finite positions
  PoissonOptions options;             // validated
  // Out: positions relative to cloud->origin, normals, colors (when the cloud
  // has colors) and indices as Open3D wound them; densities per vertex.
  Mesh* mesh = nullptr;
  std::vector<float>* densities = nullptr;
  std::string* error = nullptr;  // set when the call returns false
};

}  // namespace pb

#define PB_POISSON_MODULE_SYMBOL "pb_poisson_open3d_run_v1"
extern "C" bool pb_poisson_open3d_run_v1(pb::PoissonModuleCall* call);

// The same call into PCL's pcl::Poisson (pointbake-pcl.so, pcl_module.cc):
// fills positions (relative to cloud->origin) and indices only, no normals,
// colors or densities.
#define PB_PCL_POISSON_SYMBOL "pb_pcl_poisson_v1"
extern "C" bool pb_pcl_poisson_v1(pb::PoissonModuleCall* call);
