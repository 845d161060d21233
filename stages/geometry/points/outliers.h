// Statistical outlier removal, as PCL's StatisticalOutlierRemoval: for every
// point the mean distance to its k nearest other points; points whose mean
// exceeds  global_mean + std_ratio * global_stddev  are removed.
//
// Distances are meters in the cloud's frame; the standard deviation is the
// sample one (n - 1), as PCL. Kept points keep every attribute (normals,
// colors, intensities, station ids) and their order; origin and stations are
// copied unchanged. Output is identical whatever the thread count. Memory:
// the kNN index (~21 bytes per point, see knn.h) plus 8 bytes per point.
#pragma once

#include <cstddef>
#include <functional>

#include "base/status.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

// Whose code runs: ours (below) or PCL 1.13's StatisticalOutlierRemoval
// (pointbake-pcl.so, loaded on first use; single-threaded, float distances,
// so a point right at the threshold may go the other way). With kPcl the
// report's mean_distance_m, stddev_m and threshold_m stay 0: PCL does not
// expose them.
enum class OutlierImplementation { kOwn, kPcl };

struct OutlierOptions {
  OutlierImplementation implementation = OutlierImplementation::kOwn;
  int k = 16;              // neighbours per point, the point excluded; 1..1000
  double std_ratio = 2.0;  // threshold in standard deviations above the mean, >= 0
  int threads = 0;         // worker threads; 0 = TBB's default (all cores)
  // Called from the calling thread with the fraction done, in [0, 1].
  std::function<void(double fraction)> progress;
};

struct OutlierReport {
  size_t points_in = 0;
  size_t points_out = 0;
  size_t removed = 0;
  double mean_distance_m = 0;    // mean over points of their mean kNN distance
  double stddev_m = 0;           // sample standard deviation of the same
  double threshold_m = 0;        // mean_distance_m + std_ratio * stddev_m
};

// Status::Invalid for k outside 1..1000, a negative or non-finite std_ratio,
// inconsistent attribute arrays or a non-finite coordinate (naming the point).
// A cloud with fewer than 2 points is returned unchanged. Status::Unsupported
// when kPcl is asked for and this build has no pointbake-pcl.so.
Expected<PointCloud> RemoveStatisticalOutliers(const PointCloud& cloud, const OutlierOptions& options,
                                               OutlierReport* report = nullptr);

}  // namespace pb
