// Point clouds for tests (test-only: no production code includes
// stages/geometry/testing/), generated, no files.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

#include "stages/geometry/core/point_cloud.h"

namespace pb::testing {

// `points` points on a sphere (Fibonacci lattice: even spacing) with
// Gaussian radial noise of `noise_m` (none when 0), appended to `cloud`.
inline void AddSphere(PointCloud& cloud, const double center[3], double radius_m, int points,
                      double noise_m, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_m > 0 ? noise_m : 1.0);
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < points; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / points;
    const double r = std::sqrt(1.0 - z * z);
    const double r_m = radius_m + (noise_m > 0 ? noise(rng) : 0.0);
    cloud.positions.insert(cloud.positions.end(),
                           {static_cast<float>(center[0] + r_m * r * std::cos(golden * i)),
                            static_cast<float>(center[1] + r_m * r * std::sin(golden * i)),
                            static_cast<float>(center[2] + r_m * z)});
  }
}

}  // namespace pb::testing
