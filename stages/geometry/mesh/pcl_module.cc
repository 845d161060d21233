// pointbake-pcl.so: PCL 1.13's implementations behind the calls of
// stages/geometry/points/module_calls.h (MLS smoothing, statistical outlier
// removal, normals) and poisson_module.h (screened Poisson). The only file
// that includes PCL: its headers are heavy to compile, and the module keeps
// PCL's shared libraries out of every process that does not use them. PCL
// was built with its common point types precompiled, so this file
// instantiates no PCL template itself.
#include <pcl/features/normal_3d_omp.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/mls.h>
#include <pcl/surface/poisson.h>

#include <exception>
#include <memory>

#include "stages/geometry/core/module_guard.h"
#include "stages/geometry/mesh/poisson_module.h"
#include "stages/geometry/points/module_calls.h"

namespace {

pcl::PointCloud<pcl::PointXYZ>::Ptr ToPcl(const pb::PointCloud& cloud) {
  auto out = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  out->resize(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    (*out)[i] = pcl::PointXYZ(cloud.positions[3 * i], cloud.positions[3 * i + 1],
                              cloud.positions[3 * i + 2]);
  }
  return out;
}

}  // namespace

#define PB_EXPORT extern "C" __attribute__((visibility("default")))

PB_EXPORT bool pb_pcl_normals_v1(pb::NormalsModuleCall* call) {
  return pb::GuardModuleCall(call, [call] {
    pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> estimation(
        static_cast<unsigned int>(call->threads));
    estimation.setInputCloud(ToPcl(*call->cloud));
    estimation.setSearchMethod(std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>());
    estimation.setKSearch(call->k);
    pcl::PointCloud<pcl::Normal> normals;
    estimation.compute(normals);
    if (normals.size() != call->cloud->size()) {
      throw std::runtime_error("NormalEstimationOMP returned " + std::to_string(normals.size()) +
                               " normals");
    }
    call->normals->resize(3 * normals.size());
    for (size_t i = 0; i < normals.size(); ++i) {
      (*call->normals)[3 * i] = normals[i].normal_x;
      (*call->normals)[3 * i + 1] = normals[i].normal_y;
      (*call->normals)[3 * i + 2] = normals[i].normal_z;
    }
  });
}

PB_EXPORT bool pb_pcl_outliers_v1(pb::OutliersModuleCall* call) {
  return pb::GuardModuleCall(call, [call] {
    pcl::StatisticalOutlierRemoval<pcl::PointXYZ> filter;
    filter.setInputCloud(ToPcl(*call->cloud));
    filter.setMeanK(call->k);
    filter.setStddevMulThresh(call->std_ratio);
    pcl::Indices kept;
    filter.filter(kept);
    call->kept->assign(kept.begin(), kept.end());
  });
}

PB_EXPORT bool pb_pcl_smooth_v1(pb::SmoothModuleCall* call) {
  return pb::GuardModuleCall(call, [call] {
    pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointXYZ> mls;
    mls.setInputCloud(ToPcl(*call->cloud));
    mls.setSearchMethod(std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>());
    mls.setSearchRadius(call->radius_m);
    mls.setPolynomialOrder(call->polynomial_order);
    mls.setComputeNormals(false);
    mls.setNumberOfThreads(static_cast<unsigned int>(call->threads));
    pcl::PointCloud<pcl::PointXYZ> smoothed;
    mls.process(smoothed);
    const pcl::PointIndicesPtr source = mls.getCorrespondingIndices();
    if (!source || source->indices.size() != smoothed.size()) {
      throw std::runtime_error("MovingLeastSquares returned no input index per output point");
    }
    call->positions->resize(3 * smoothed.size());
    for (size_t i = 0; i < smoothed.size(); ++i) {
      (*call->positions)[3 * i] = smoothed[i].x;
      (*call->positions)[3 * i + 1] = smoothed[i].y;
      (*call->positions)[3 * i + 2] = smoothed[i].z;
    }
    call->source->assign(source->indices.begin(), source->indices.end());
  });
}

PB_EXPORT bool pb_pcl_poisson_v1(pb::PoissonModuleCall* call) {
  return pb::GuardModuleCall(call, [call] {
    const pb::PointCloud& cloud = *call->cloud;
    auto input = std::make_shared<pcl::PointCloud<pcl::PointNormal>>();
    input->resize(cloud.size());
    for (size_t i = 0; i < cloud.size(); ++i) {
      pcl::PointNormal& p = (*input)[i];
      p.x = cloud.positions[3 * i];
      p.y = cloud.positions[3 * i + 1];
      p.z = cloud.positions[3 * i + 2];
      p.normal_x = cloud.normals[3 * i];
      p.normal_y = cloud.normals[3 * i + 1];
      p.normal_z = cloud.normals[3 * i + 2];
    }
    // PCL's defaults (point weight 4, degree 2) and samples per node 1.5,
    // as Open3D and docs/poisson.md's comparison.
    pcl::Poisson<pcl::PointNormal> poisson;
    poisson.setDepth(call->options.depth);
    poisson.setScale(static_cast<float>(call->options.scale));
    poisson.setThreads(call->options.threads > 0 ? call->options.threads : 1);
    poisson.setSamplesPerNode(1.5f);
    poisson.setManifold(true);
    poisson.setInputCloud(input);
    pcl::PointCloud<pcl::PointNormal> vertices;
    std::vector<pcl::Vertices> polygons;
    poisson.reconstruct(vertices, polygons);
    pb::Mesh& mesh = *call->mesh;
    mesh = pb::Mesh();
    mesh.origin = cloud.origin;
    mesh.positions.reserve(3 * vertices.size());
    for (const pcl::PointNormal& v : vertices) {
      mesh.positions.insert(mesh.positions.end(), {v.x, v.y, v.z});
    }
    for (const pcl::Vertices& polygon : polygons) {
      for (size_t k = 1; k + 1 < polygon.vertices.size(); ++k) {
        for (const size_t corner : {size_t{0}, k, k + 1}) {
          mesh.indices.push_back(static_cast<uint32_t>(polygon.vertices[corner]));
        }
      }
    }
    call->densities->clear();
  });
}
