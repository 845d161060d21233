// LscmFlatten (complex sparse solve) against an independent dense reference.
#include "stages/geometry/uv/conformal.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

namespace pb {
namespace {

// A curved, irregular patch: a jittered (n+1) x (n+1) grid on a saddle with a
// bump, cut into triangles along alternating diagonals, counter-clockwise
// seen from +z.
void MakeCurvedPatch(int n, std::vector<double>* positions, std::vector<uint32_t>* corners) {
  positions->clear();
  corners->clear();
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const double x = i + 0.3 * std::sin(1.7 * i + 2.3 * j);
      const double y = j + 0.3 * std::cos(2.9 * i - 1.1 * j);
      const double z = 0.08 * (x * x - y * y) + 3.0 * std::exp(-0.15 * ((x - 3) * (x - 3) + y * y));
      positions->insert(positions->end(), {x, y, z});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      if ((i + j) % 2 == 0) {
        corners->insert(corners->end(), {a, b, d, a, d, c});
      } else {
        corners->insert(corners->end(), {a, b, c, b, d, c});
      }
    }
  }
}

// The LSCM energy's minimizer by dense least squares on the real
// Cauchy-Riemann residuals (u_x - v_y, u_y + v_x, each face weighed by the
// square root of its area, in a frame of its own unlike LscmFlatten's),
// with `pin_a` at (0, 0) and `pin_b` at (pin_u, 0); QR, no normal equations.
std::vector<double> DenseLscm(const std::vector<double>& p, const std::vector<uint32_t>& corners,
                              uint32_t pin_a, uint32_t pin_b, double pin_u) {
  const int n = int(p.size() / 3), faces = int(corners.size() / 3);
  std::vector<int> column(n, -1);
  int unknowns = 0;
  for (int v = 0; v < n; ++v) {
    if (v != int(pin_a) && v != int(pin_b)) column[v] = unknowns++;
  }
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * faces, 2 * unknowns);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(2 * faces);
  for (int f = 0; f < faces; ++f) {
    const uint32_t* c = &corners[3 * f];
    Eigen::Vector3d q[3];
    for (int k = 0; k < 3; ++k) q[k] = Eigen::Vector3d(p[3 * c[k]], p[3 * c[k] + 1], p[3 * c[k] + 2]);
    const Eigen::Vector3d normal = (q[1] - q[0]).cross(q[2] - q[0]);
    const double area = 0.5 * normal.norm();
    // Frame: x along the edge 2 -> 0, y = normal x x (right-handed).
    const Eigen::Vector3d ex = (q[0] - q[2]).normalized();
    const Eigen::Vector3d ey = normal.normalized().cross(ex);
    double x[3], y[3];
    for (int k = 0; k < 3; ++k) {
      x[k] = (q[k] - q[2]).dot(ex);
      y[k] = (q[k] - q[2]).dot(ey);
    }
    const double w = std::sqrt(area);
    for (int k = 0; k < 3; ++k) {
      // Gradient of the hat function of corner k: the opposite edge turned
      // 90 degrees, over twice the area.
      const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
      const double gx = -(y[k2] - y[k1]) / (2 * area), gy = (x[k2] - x[k1]) / (2 * area);
      // Row 2f: u_x - v_y; row 2f + 1: u_y + v_x.
      const double ru[2] = {w * gx, w * gy}, rv[2] = {-w * gy, w * gx};
      const uint32_t v = c[k];
      if (column[v] < 0) {
        const double pu = v == pin_b ? pin_u : 0.0;
        for (int r = 0; r < 2; ++r) b[2 * f + r] -= ru[r] * pu;
      } else {
        for (int r = 0; r < 2; ++r) {
          a(2 * f + r, 2 * column[v]) += ru[r];
          a(2 * f + r, 2 * column[v] + 1) += rv[r];
        }
      }
    }
  }
  const Eigen::VectorXd x = a.colPivHouseholderQr().solve(b);
  std::vector<double> uv(2 * n, 0.0);
  uv[2 * pin_b] = pin_u;
  for (int v = 0; v < n; ++v) {
    if (column[v] < 0) continue;
    uv[2 * v] = x[2 * column[v]];
    uv[2 * v + 1] = x[2 * column[v] + 1];
  }
  return uv;
}

TEST(UvConformalTest, LscmMatchesADenseReferenceOnACurvedPatch) {
  std::vector<double> positions;
  std::vector<uint32_t> corners;
  MakeCurvedPatch(9, &positions, &corners);
  std::vector<double> uv;
  ASSERT_TRUE(LscmFlatten(positions, corners, &uv));
  // The pins LscmFlatten chose: the vertex at exactly (0, 0) and the one at
  // exactly (its 3-D distance from the first, 0).
  const int n = int(positions.size() / 3);
  int pin_a = -1, pin_b = -1;
  for (int v = 0; v < n; ++v) {
    if (uv[2 * v] == 0 && uv[2 * v + 1] == 0) pin_a = v;
  }
  ASSERT_GE(pin_a, 0);
  for (int v = 0; v < n; ++v) {
    double d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += std::pow(positions[3 * v + k] - positions[3 * pin_a + k], 2);
    if (v != pin_a && uv[2 * v + 1] == 0 && uv[2 * v] == std::sqrt(d2)) pin_b = v;
  }
  ASSERT_GE(pin_b, 0);
  const double pin_u = uv[2 * pin_b];
  // Far apart: the pins span most of the 9 x 9 patch.
  EXPECT_GT(pin_u, 9.0);
  const std::vector<double> reference = DenseLscm(positions, corners, pin_a, pin_b, pin_u);
  // LscmFlatten adds a ridge of 1e-12 x the mean diagonal to its normal
  // equations; here it moves the solution by about 4e-9 of the pin
  // distance (without it the two agree to 2e-14).
  double worst = 0;
  for (size_t i = 0; i < uv.size(); ++i) worst = std::max(worst, std::abs(uv[i] - reference[i]));
  EXPECT_LT(worst, 1e-7 * pin_u);
  // Curved: the map is no isometry (a real test of the solve, not of
  // unrolling), yet every face stays counter-clockwise.
  double most_off = 0;
  for (size_t f = 0; f < corners.size() / 3; ++f) {
    const double* a = &uv[2 * corners[3 * f]];
    const double* b = &uv[2 * corners[3 * f + 1]];
    const double* c = &uv[2 * corners[3 * f + 2]];
    EXPECT_GT((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]), 0) << f;
    for (auto [s, t] : {std::pair{0, 1}, {1, 2}, {2, 0}}) {
      const uint32_t vs = corners[3 * f + s], vt = corners[3 * f + t];
      double d2 = 0;
      for (int k = 0; k < 3; ++k) d2 += std::pow(positions[3 * vs + k] - positions[3 * vt + k], 2);
      const double flat = std::hypot(uv[2 * vs] - uv[2 * vt], uv[2 * vs + 1] - uv[2 * vt + 1]);
      most_off = std::max(most_off, std::abs(flat / std::sqrt(d2) - 1));
    }
  }
  EXPECT_GT(most_off, 0.05);
}

}  // namespace
}  // namespace pb
