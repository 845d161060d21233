// Surfels (surfels.h): one k-NN query per point, a plane fit, the centroid
// shift of the half-disc border criterion.
#include "stages/geometry/points/surfels.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

#include "stages/geometry/points/knn.h"
#include "stages/geometry/points/normals.h"

namespace pb {

Expected<Surfels> EstimateSurfels(const PointCloud& cloud, const SurfelOptions& options) {
  PB_RETURN_IF_ERROR(Validate(cloud));
  if (options.k < 3 || options.k > 64)
    return Status::Invalid("surfels: k must be in [3, 64], got " + std::to_string(options.k));
  if (!(options.border_shift > 0) || !std::isfinite(options.border_shift))
    return Status::Invalid("surfels: border_shift must be finite and > 0");
  const size_t n = cloud.size();
  if (n <= size_t(options.k))
    return Status::Invalid("surfels: needs more than k = " + std::to_string(options.k) + " points, the cloud has " +
                           std::to_string(n));
  PB_ASSIGN_OR_RETURN(const KnnIndex index, KnnIndex::Build(cloud.positions));
  Surfels surfels;
  surfels.normal.assign(n * 3, 0.0f);
  surfels.outward.assign(n * 3, 0.0f);
  surfels.variation.assign(n, 0.0f);
  std::atomic<size_t> border{0};
  const int k = options.k;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<Neighbor> neighbors(static_cast<size_t>(k));
    size_t border_here = 0;
    for (size_t slot = range.begin(); slot < range.end(); ++slot) {
      const uint32_t i = index.PointAtSlot(slot);
      const int found = index.QueryPoint(i, k, neighbors);
      const float* p = &cloud.positions[size_t(i) * 3];
      // Offsets from the point, so the covariance does not lose digits far
      // from the origin.
      double mean[3] = {0, 0, 0}, cov[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
      for (int j = 0; j < found; ++j) {
        const float* q = &cloud.positions[size_t(neighbors[size_t(j)].index) * 3];
        for (int c = 0; c < 3; ++c) mean[c] += double(q[c]) - double(p[c]);
      }
      const double count = found + 1;  // the point itself at offset 0
      double centroid[3];
      for (int c = 0; c < 3; ++c) centroid[c] = mean[c] / count;
      const auto accumulate = [&](const double d[3]) {
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) cov[a * 3 + b] += (d[a] - centroid[a]) * (d[b] - centroid[b]);
      };
      const double self[3] = {0, 0, 0};
      accumulate(self);
      for (int j = 0; j < found; ++j) {
        const float* q = &cloud.positions[size_t(neighbors[size_t(j)].index) * 3];
        const double d[3] = {double(q[0]) - p[0], double(q[1]) - p[1], double(q[2]) - p[2]};
        accumulate(d);
      }
      double normal[3];
      PlaneNormal(cov, normal);
      for (int c = 0; c < 3; ++c) surfels.normal[size_t(i) * 3 + c] = float(normal[c]);
      // The smallest eigenvalue is n^T C n for its unit eigenvector n.
      double smallest = 0;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) smallest += normal[a] * cov[a * 3 + b] * normal[b];
      const double trace = cov[0] + cov[4] + cov[8];
      surfels.variation[i] = trace > 0 ? float(std::clamp(smallest / trace, 0.0, 1.0 / 3)) : 0.0f;
      // The neighbours' centroid (the point left out), in the tangent plane.
      double shift[3];
      for (int c = 0; c < 3; ++c) shift[c] = mean[c] / found;
      const double along = shift[0] * normal[0] + shift[1] * normal[1] + shift[2] * normal[2];
      for (int c = 0; c < 3; ++c) shift[c] -= along * normal[c];
      const double length = std::sqrt(shift[0] * shift[0] + shift[1] * shift[1] + shift[2] * shift[2]);
      const double r_k = std::sqrt(neighbors[size_t(found - 1)].squared_distance_m2);
      if (r_k > 0 && length > options.border_shift * r_k) {
        for (int c = 0; c < 3; ++c) surfels.outward[size_t(i) * 3 + c] = float(-shift[c] / length);
        ++border_here;
      }
    }
    border += border_here;
  });
  surfels.border_points = border.load();
  return surfels;
}

}  // namespace pb
