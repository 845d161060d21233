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

// A horizontal ceiling `height_m` above a scanner at the origin, swept as a
// laser scanner sweeps it: vertical lines through the zenith every `step`
// rad of azimuth, a sample every `step` rad along each out to `max_zenith`
// rad from the zenith, Gaussian range noise of `noise_m` along the ray,
// appended to `cloud`. Near the zenith the lines lie a fraction of a
// millimetre apart and their samples a centimetre apart along them (at
// step 6 mrad, 1.7 m up): a point's 16 nearest lie on one arc across them.
inline void AddZenithCeiling(PointCloud& cloud, double height_m, double step, double max_zenith,
                             double noise_m, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_m > 0 ? noise_m : 1.0);
  for (double azimuth = 0; azimuth < 2 * std::numbers::pi; azimuth += step) {
    for (double zenith = step; zenith < max_zenith; zenith += step) {
      const double d[3] = {std::sin(zenith) * std::cos(azimuth), std::sin(zenith) * std::sin(azimuth),
                           std::cos(zenith)};
      const double range = height_m / d[2] + (noise_m > 0 ? noise(rng) : 0.0);
      cloud.positions.insert(cloud.positions.end(), {static_cast<float>(range * d[0]),
                                                     static_cast<float>(range * d[1]),
                                                     static_cast<float>(range * d[2])});
    }
  }
}

// The six faces of the box [lo, hi] sampled every `spacing_m` (a jittered
// grid, Gaussian noise of `noise_m` across each face), without the points
// for which `skip(x, y, z)` holds (a door, a window), appended to `cloud`.
template <typename Skip>
void AddBoxFaces(PointCloud& cloud, const double lo[3], const double hi[3], double spacing_m,
                 double noise_m, uint32_t seed, Skip skip) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.3 * spacing_m, 0.3 * spacing_m);
  std::normal_distribution<double> noise(0.0, noise_m > 0 ? noise_m : 1.0);
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const int nu = int((hi[u] - lo[u]) / spacing_m), nv = int((hi[v] - lo[v]) / spacing_m);
    for (const double plane : {lo[axis], hi[axis]}) {
      for (int i = 0; i < nu; ++i) {
        for (int j = 0; j < nv; ++j) {
          double p[3];
          p[axis] = plane + (noise_m > 0 ? noise(rng) : 0.0);
          p[u] = lo[u] + (i + 0.5) * spacing_m + jitter(rng);
          p[v] = lo[v] + (j + 0.5) * spacing_m + jitter(rng);
          if (skip(p[0], p[1], p[2])) continue;
          cloud.positions.insert(cloud.positions.end(), {static_cast<float>(p[0]),
                                                         static_cast<float>(p[1]),
                                                         static_cast<float>(p[2])});
        }
      }
    }
  }
}

// A room seen from inside, as one merged cloud without stations: the box
// [0, width] x [0, depth] x [0, 3 m] every 5 cm with a door `door_m` wide
// and 2.1 m high in the wall y = 0 (none when 0), and a table (a
// 1.2 x 0.8 x 0.75 m box, its top and sides) standing in it.
inline PointCloud RoomWithTable(double width_m, double depth_m, double door_m, uint32_t seed) {
  PointCloud cloud;
  const double lo[3] = {0, 0, 0}, hi[3] = {width_m, depth_m, 3.0};
  const double door_left = 0.5 * width_m - 0.5 * door_m;
  AddBoxFaces(cloud, lo, hi, 0.05, 0.002, seed, [&](double x, double y, double z) {
    return door_m > 0 && y < 0.01 && z < 2.1 && x > door_left && x < door_left + door_m;
  });
  const double table_lo[3] = {0.3 * width_m, 0.5 * depth_m, 0.0};
  const double table_hi[3] = {0.3 * width_m + 1.2, 0.5 * depth_m + 0.8, 0.75};
  // No bottom face: the scanner does not see it, and it would lie on the floor.
  AddBoxFaces(cloud, table_lo, table_hi, 0.05, 0.002, seed + 1,
              [](double, double, double z) { return z < 0.01; });
  return cloud;
}

// A corridor 10 x 1.8 x 2.6 m ([0, 10] x [0, 1.8] x [0, 2.6]) seen from
// inside, merged without stations, open at both ends (no end walls: the
// scan stops there), its walls, floor and ceiling every 4 cm.
inline PointCloud OpenCorridor() {
  PointCloud corridor;
  const double lo[3] = {0, 0, 0}, hi[3] = {10.0, 1.8, 2.6};
  AddBoxFaces(corridor, lo, hi, 0.04, 0.002, 11, [](double x, double, double) { return x < 0.01 || x > 9.99; });
  return corridor;
}

}  // namespace pb::testing
