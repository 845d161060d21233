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
namespace {

// Solves the 6 x 6 symmetric positive definite system m x = r in place
// (Cholesky); false if a pivot is not positive (singular: points on a line).
bool SolveSymmetric6(double m[36], double r[6]) {
  for (int j = 0; j < 6; ++j) {
    double d = m[j * 6 + j];
    for (int k = 0; k < j; ++k) d -= m[j * 6 + k] * m[j * 6 + k];
    if (!(d > 1e-12)) return false;
    d = std::sqrt(d);
    m[j * 6 + j] = d;
    for (int i = j + 1; i < 6; ++i) {
      double v = m[i * 6 + j];
      for (int k = 0; k < j; ++k) v -= m[i * 6 + k] * m[j * 6 + k];
      m[i * 6 + j] = v / d;
    }
  }
  for (int i = 0; i < 6; ++i) {
    double v = r[i];
    for (int k = 0; k < i; ++k) v -= m[i * 6 + k] * r[k];
    r[i] = v / m[i * 6 + i];
  }
  for (int i = 5; i >= 0; --i) {
    double v = r[i];
    for (int k = i + 1; k < 6; ++k) v -= m[k * 6 + i] * r[k];
    r[i] = v / m[i * 6 + i];
  }
  return true;
}

}  // namespace

Expected<Surfels> EstimateSurfels(const PointCloud& cloud, const SurfelOptions& options, const KnnIndex* given) {
  PB_RETURN_IF_ERROR(Validate(cloud));
  if (options.k < 3 || options.k > 64)
    return Status::Invalid("surfels: k must be in [3, 64], got " + std::to_string(options.k));
  if (!(options.border_shift > 0) || !std::isfinite(options.border_shift))
    return Status::Invalid("surfels: border_shift must be finite and > 0");
  const size_t n = cloud.size();
  if (n <= size_t(options.k))
    return Status::Invalid("surfels: needs more than k = " + std::to_string(options.k) + " points, the cloud has " +
                           std::to_string(n));
  if (given && given->size() != n)
    return Status::Invalid("surfels: the given index holds " + std::to_string(given->size()) +
                           " points, the cloud " + std::to_string(n));
  KnnIndex built;
  if (!given) {
    PB_ASSIGN_OR_RETURN(built, KnnIndex::Build(cloud.positions));
  }
  const KnnIndex& index = given ? *given : built;
  Surfels surfels;
  surfels.normal.assign(n * 3, 0.0f);
  surfels.outward.assign(n * 3, 0.0f);
  surfels.variation.assign(n, 0.0f);
  if (options.project) surfels.on_surface = cloud.positions;
  std::atomic<size_t> border{0}, widened{0};
  const int k = options.k;
  // The point and its k nearest others: Query's k + 1.
  if (options.widen_dense) surfels.widen_to_m = MedianNeighborhoodRadius(index, k + 1);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<Neighbor> neighbors(static_cast<size_t>(options.widen_dense ? kWidenedNeighbors * k : k));
    size_t border_here = 0, widened_here = 0;
    for (size_t slot = range.begin(); slot < range.end(); ++slot) {
      const uint32_t i = index.PointAtSlot(slot);
      int found = index.QueryPoint(i, k, neighbors);
      if (surfels.widen_to_m > 0) {
        const int nearest = found;
        found = WidenNeighborhood([&](int want, std::span<Neighbor> out) { return index.QueryPoint(i, want, out); },
                                  k, found, surfels.widen_to_m, neighbors);
        widened_here += found != nearest;
      }
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
      if (options.project && r_k > 0) {
        // The quadric over the plane (origin: the centroid; unit r_k).
        const int axis = std::abs(normal[0]) < std::abs(normal[1])
                             ? (std::abs(normal[0]) < std::abs(normal[2]) ? 0 : 2)
                             : (std::abs(normal[1]) < std::abs(normal[2]) ? 1 : 2);
        double t1[3] = {0, 0, 0};
        t1[axis] = 1;
        const double dot = normal[axis];
        for (int c = 0; c < 3; ++c) t1[c] -= dot * normal[c];
        const double t1_length = std::sqrt(t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]);
        for (int c = 0; c < 3; ++c) t1[c] /= t1_length;
        const double t2[3] = {normal[1] * t1[2] - normal[2] * t1[1], normal[2] * t1[0] - normal[0] * t1[2],
                              normal[0] * t1[1] - normal[1] * t1[0]};
        double m[36] = {}, r[6] = {};
        const auto local = [&](const double d[3], double& x, double& y, double& z) {
          const double e[3] = {(d[0] - centroid[0]) / r_k, (d[1] - centroid[1]) / r_k, (d[2] - centroid[2]) / r_k};
          x = e[0] * t1[0] + e[1] * t1[1] + e[2] * t1[2];
          y = e[0] * t2[0] + e[1] * t2[1] + e[2] * t2[2];
          z = e[0] * normal[0] + e[1] * normal[1] + e[2] * normal[2];
        };
        const auto add = [&](const double d[3]) {
          double x, y, z;
          local(d, x, y, z);
          const double row[6] = {x * x, x * y, y * y, x, y, 1};
          for (int a = 0; a < 6; ++a) {
            r[a] += row[a] * z;
            for (int b = 0; b <= a; ++b) m[a * 6 + b] += row[a] * row[b];
          }
        };
        add(self);
        for (int j = 0; j < found; ++j) {
          const float* q = &cloud.positions[size_t(neighbors[size_t(j)].index) * 3];
          const double d[3] = {double(q[0]) - p[0], double(q[1]) - p[1], double(q[2]) - p[2]};
          add(d);
        }
        for (int a = 0; a < 6; ++a)
          for (int b = a + 1; b < 6; ++b) m[a * 6 + b] = m[b * 6 + a];
        double x, y, z;
        local(self, x, y, z);
        double height = 0;  // the plane, when the quadric is undetermined
        if (SolveSymmetric6(m, r)) height = r[0] * x * x + r[1] * x * y + r[2] * y * y + r[3] * x + r[4] * y + r[5];
        if (!std::isfinite(height)) height = 0;
        const double move = height - z;  // along the normal, in r_k
        if (std::abs(move) <= 1.0) {
          for (int c = 0; c < 3; ++c)
            surfels.on_surface[size_t(i) * 3 + c] = float(double(p[c]) + move * r_k * normal[c]);
        }
      }
    }
    border += border_here;
    widened += widened_here;
  });
  surfels.border_points = border.load();
  surfels.widened = widened.load();
  return surfels;
}

}  // namespace pb
