// pointbake-poisson-open3d.so: Open3D 0.16's screened Poisson behind the
// call in poisson_module.h, and its normal estimation behind the call in
// stages/geometry/points/module_calls.h. The only file that includes Open3D.
#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/utility/Logging.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <memory>
#include <tuple>

#include "stages/geometry/core/module_guard.h"
#include "stages/geometry/mesh/poisson_module.h"
#include "stages/geometry/points/module_calls.h"

namespace {

// Open3D's copy of the cloud's positions (relative to its origin). Also
// quiets Open3D, which prints its progress at Info level to stdout; errors
// reach the caller as exceptions.
open3d::geometry::PointCloud Open3dPoints(const pb::PointCloud& cloud) {
  open3d::utility::SetVerbosityLevel(open3d::utility::VerbosityLevel::Error);
  open3d::geometry::PointCloud input;
  input.points_.resize(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    const float* p = &cloud.positions[3 * i];
    input.points_[i] = Eigen::Vector3d(p[0], p[1], p[2]);
  }
  return input;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) bool pb_poisson_open3d_run_v1(
    pb::PoissonModuleCall* call) {
  return pb::GuardModuleCall(call, [call] {
    const pb::PointCloud& cloud = *call->cloud;
    const size_t n = cloud.size();
    open3d::geometry::PointCloud input = Open3dPoints(cloud);
    input.normals_.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const float* q = &cloud.normals[3 * i];
      input.normals_[i] = Eigen::Vector3d(q[0], q[1], q[2]);
    }
    const bool colors = cloud.has_colors();
    if (colors) {
      input.colors_.resize(n);
      for (size_t i = 0; i < n; ++i) {
        const uint8_t* c = &cloud.colors[3 * i];
        input.colors_[i] = Eigen::Vector3d(c[0], c[1], c[2]) / 255.0;
      }
    }

    auto [result, densities] = open3d::geometry::TriangleMesh::CreateFromPointCloudPoisson(
        input, static_cast<size_t>(call->options.depth), 0.0f,
        static_cast<float>(call->options.scale), call->options.linear_fit,
        call->options.threads > 0 ? call->options.threads : -1);
    // The input copy is not needed any more; free it before building ours.
    input = open3d::geometry::PointCloud();

    pb::Mesh& mesh = *call->mesh;
    mesh = pb::Mesh();
    mesh.origin = cloud.origin;
    const size_t nv = result->vertices_.size();
    mesh.positions.resize(3 * nv);
    mesh.normals.resize(3 * nv);
    for (size_t i = 0; i < nv; ++i) {
      const Eigen::Vector3d& v = result->vertices_[i];
      Eigen::Vector3d nrm =
          i < result->vertex_normals_.size() ? result->vertex_normals_[i] : Eigen::Vector3d::Zero();
      const double len = nrm.norm();
      nrm = len > 0 && std::isfinite(len) ? Eigen::Vector3d(nrm / len) : Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) {
        mesh.positions[3 * i + k] = static_cast<float>(v[k]);
        mesh.normals[3 * i + k] = static_cast<float>(nrm[k]);
      }
    }
    if (colors && result->vertex_colors_.size() == nv) {
      mesh.colors.resize(3 * nv);
      for (size_t i = 0; i < nv; ++i) {
        for (int k = 0; k < 3; ++k) {
          const double c = std::clamp(result->vertex_colors_[i][k], 0.0, 1.0);
          mesh.colors[3 * i + k] = static_cast<uint8_t>(std::lround(c * 255.0));
        }
      }
    }
    mesh.indices.resize(3 * result->triangles_.size());
    for (size_t t = 0; t < result->triangles_.size(); ++t) {
      for (int k = 0; k < 3; ++k) {
        mesh.indices[3 * t + k] = static_cast<uint32_t>(result->triangles_[t][k]);
      }
    }
    call->densities->assign(densities.begin(), densities.end());
  });
}

extern "C" __attribute__((visibility("default"))) bool pb_open3d_normals_v1(
    pb::NormalsModuleCall* call) {
  return pb::GuardModuleCall(call, [call] {
    const size_t n = call->cloud->size();
    open3d::geometry::PointCloud input = Open3dPoints(*call->cloud);
    // Without normals on input, Open3D leaves each sign as its solver found
    // it; the caller orients. Open3D parallelizes with OpenMP: as many
    // threads as the stage was given.
    omp_set_num_threads(call->threads);
    input.EstimateNormals(open3d::geometry::KDTreeSearchParamKNN(call->k),
                          /*fast_normal_computation=*/true);
    call->normals->resize(3 * n);
    for (size_t i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) {
        (*call->normals)[3 * i + k] = static_cast<float>(input.normals_[i][k]);
      }
    }
  });
}
