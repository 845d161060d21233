// Statistical outlier removal. Reference: R. B. Rusu, Z. C. Marton,
// N. Blodow, M. Dolha, M. Beetz, "Towards 3D point cloud based object maps for
// household environments", Robotics and Autonomous Systems 56(11), 2008,
// section 4 (sparse outlier removal); semantics follow PCL 1.x
// StatisticalOutlierRemoval (k neighbours excluding the point, sample
// standard deviation, keep when mean distance <= threshold). Departure: the
// global mean and deviation are summed sequentially in index order (two
// passes, double precision) so the result never depends on the thread count.
#include "stages/geometry/points/outliers.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "stages/geometry/core/module.h"
#include "stages/geometry/points/knn.h"
#include "stages/geometry/points/module_calls.h"

namespace pb {
namespace {

constexpr int kMaxK = 1000;
constexpr size_t kChunk = size_t{1} << 20;  // points per progress step

Expected<PointCloud> RemoveInArena(const PointCloud& cloud, const OutlierOptions& options,
                                   OutlierReport& report) {
  const size_t n = cloud.size();
  PB_ASSIGN_OR_RETURN(const KnnIndex index, KnnIndex::Build(cloud.positions));
  std::vector<double> mean_distance(n);
  const int k = options.k;
  for (size_t chunk = 0; chunk < n; chunk += kChunk) {
    const size_t chunk_end = std::min(n, chunk + kChunk);
    tbb::parallel_for(tbb::blocked_range<size_t>(chunk, chunk_end, 1024),
                      [&](const tbb::blocked_range<size_t>& range) {
      std::vector<Neighbor> neighbors(k);
      for (size_t slot = range.begin(); slot < range.end(); ++slot) {
        const uint32_t i = index.PointAtSlot(slot);
        const int count = index.QueryPoint(i, k, neighbors);
        double sum = 0;
        for (int j = 0; j < count; ++j) sum += std::sqrt(neighbors[j].squared_distance_m2);
        mean_distance[i] = sum / count;
      }
    });
    if (options.progress) options.progress(0.9 * static_cast<double>(chunk_end) / static_cast<double>(n));
  }
  double sum = 0;
  for (double d : mean_distance) sum += d;
  const double mean = sum / static_cast<double>(n);
  double squares = 0;
  for (double d : mean_distance) squares += (d - mean) * (d - mean);
  const double stddev = std::sqrt(squares / static_cast<double>(n - 1));
  const double threshold = mean + options.std_ratio * stddev;

  std::vector<uint32_t> kept;
  kept.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (mean_distance[i] <= threshold) kept.push_back(static_cast<uint32_t>(i));
  }
  PointCloud out = SelectPoints(cloud, kept);
  report.mean_distance_m = mean;
  report.stddev_m = stddev;
  report.threshold_m = threshold;
  report.points_out = out.size();
  report.removed = n - out.size();
  if (options.progress) options.progress(1.0);
  return out;
}

Expected<PointCloud> RemoveWithPcl(const PointCloud& cloud, const OutlierOptions& options,
                                   OutlierReport& report) {
  PB_ASSIGN_OR_RETURN(void* symbol,
                      ModuleSymbol(kPclModule, PB_PCL_OUTLIERS_SYMBOL,
                                   "statistical outlier removal (implementation 'pcl')"));
  PB_RETURN_IF_ERROR(CheckFinitePositions(cloud, "statistical outlier removal"));
  std::vector<uint32_t> kept;
  std::string error;
  OutliersModuleCall call;
  call.cloud = &cloud;
  call.k = options.k;
  call.std_ratio = options.std_ratio;
  call.kept = &kept;
  call.error = &error;
  if (!reinterpret_cast<bool (*)(OutliersModuleCall*)>(symbol)(&call)) {
    return Status::Internal("PCL StatisticalOutlierRemoval failed: " + error);
  }
  for (size_t j = 0; j < kept.size(); ++j) {
    if (kept[j] >= cloud.size() || (j > 0 && kept[j] <= kept[j - 1])) {
      return Status::Internal("PCL StatisticalOutlierRemoval returned an invalid index list");
    }
  }
  PointCloud out = SelectPoints(cloud, kept);
  report.points_out = out.size();
  report.removed = cloud.size() - out.size();
  if (options.progress) options.progress(1.0);
  return out;
}

}  // namespace

Expected<PointCloud> RemoveStatisticalOutliers(const PointCloud& cloud, const OutlierOptions& options,
                                               OutlierReport* report) {
  if (options.k < 1 || options.k > kMaxK) {
    return Status::Invalid("statistical outlier removal: k must be between 1 and " +
                           std::to_string(kMaxK) + ", got " + std::to_string(options.k));
  }
  if (!(options.std_ratio >= 0) || !std::isfinite(options.std_ratio)) {
    return Status::Invalid("statistical outlier removal: std_ratio must be a finite number >= 0, got " +
                           std::to_string(options.std_ratio));
  }
  PB_RETURN_IF_ERROR(Validate(cloud));
  OutlierReport local;
  local.points_in = local.points_out = cloud.size();
  if (cloud.size() < 2) {
    if (report) *report = local;
    return cloud;
  }
  if (options.implementation == OutlierImplementation::kPcl) {
    Expected<PointCloud> out = RemoveWithPcl(cloud, options, local);
    if (out.ok() && report) *report = local;
    return out;
  }
  auto run = [&] { return RemoveInArena(cloud, options, local); };
  Expected<PointCloud> out = Status::Internal("not run");
  if (options.threads > 0) {
    tbb::task_arena arena(options.threads);
    out = arena.execute(run);
  } else {
    out = run();
  }
  if (out.ok() && report) *report = local;
  return out;
}

}  // namespace pb
