#include "stages/geometry/points/smooth.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "stages/geometry/core/module.h"
#include "stages/geometry/points/module_calls.h"

namespace pb {

Expected<PointCloud> SmoothMovingLeastSquares(const PointCloud& cloud, const SmoothOptions& options,
                                              SmoothReport* report) {
  if (!(options.radius_m > 0) || !std::isfinite(options.radius_m)) {
    return Status::Invalid("MLS smoothing: radius must be a positive number of meters, got " +
                           std::to_string(options.radius_m));
  }
  if (options.polynomial_order < 0 || options.polynomial_order > 3) {
    return Status::Invalid("MLS smoothing: polynomial order must be 0..3, got " +
                           std::to_string(options.polynomial_order));
  }
  PB_RETURN_IF_ERROR(Validate(cloud));
  const size_t n = cloud.size();
  if (n < 3) {
    return Status::Invalid("MLS smoothing: needs at least 3 points, the cloud has " +
                           std::to_string(n));
  }
  PB_RETURN_IF_ERROR(CheckFinitePositions(cloud, "MLS smoothing"));
  PB_ASSIGN_OR_RETURN(void* symbol, ModuleSymbol(kPclModule, PB_PCL_SMOOTH_SYMBOL,
                                                 "MLS smoothing (points.smooth)"));
  std::vector<float> positions;
  std::vector<uint32_t> source;
  std::string error;
  SmoothModuleCall call;
  call.cloud = &cloud;
  call.radius_m = options.radius_m;
  call.polynomial_order = options.polynomial_order;
  call.threads = options.threads > 0
                     ? options.threads
                     : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  call.positions = &positions;
  call.source = &source;
  call.error = &error;
  if (!reinterpret_cast<bool (*)(SmoothModuleCall*)>(symbol)(&call)) {
    return Status::Internal("PCL MovingLeastSquares failed: " + error);
  }
  if (positions.size() != 3 * source.size()) {
    return Status::Internal("PCL MovingLeastSquares returned " + std::to_string(positions.size()) +
                            " coordinates for " + std::to_string(source.size()) + " points");
  }
  // Threads append their points in the order they finish; put every point
  // back at its input index (PCL emits one per input point without
  // upsampling; one missing keeps its input position).
  PointCloud out = cloud;
  out.normals.clear();
  std::vector<bool> seen(n, false);
  for (size_t j = 0; j < source.size(); ++j) {
    const uint32_t i = source[j];
    if (i >= n || seen[i]) {
      return Status::Internal("PCL MovingLeastSquares returned point index " + std::to_string(i) +
                              (i >= n ? " out of range" : " twice"));
    }
    seen[i] = true;
    bool finite = true;
    for (int a = 0; a < 3; ++a) finite = finite && std::isfinite(positions[3 * j + a]);
    if (finite) std::copy_n(&positions[3 * j], 3, &out.positions[3 * i]);
  }
  SmoothReport local;
  local.points = n;
  double total = 0;
  for (size_t i = 0; i < n; ++i) {
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
      const double d = double{out.positions[3 * i + a]} - cloud.positions[3 * i + a];
      d2 += d * d;
    }
    const double d = std::sqrt(d2);
    total += d;
    local.max_shift_m = std::max(local.max_shift_m, d);
  }
  local.mean_shift_m = total / static_cast<double>(n);
  if (report) *report = local;
  return out;
}

}  // namespace pb
