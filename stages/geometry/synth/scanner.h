// A simulated terrestrial laser scanner (TLS) in a SynthScene.
//
// Each station sits on a tripod ~1.5 m above the floor and sweeps a regular
// spherical grid: azimuth over the full turn, elevation from -60° (below that
// the tripod hides the floor) to +90°, the same angular step in both. A ray
// returns the first surface it meets (Intersect in synth_scene.h; rays
// through doors and windows return nothing) with Gaussian range noise of
// sigma `noise_m` along the ray and the surface's albedo plus Gaussian sensor
// noise of sigma `color_noise` per channel (in [0, 1] units) as its color.
//
// Point budget: the angular step is chosen so that the valid returns of all
// stations total about `target_points` (a coarse pilot sweep measures the
// fraction of rays that hit something); the castle scans of the paper have
// ~2 mm spacing at a few meters, reached here at ~10^7 points per room.
//
// Determinism: every random number is a hash of (seed, ray index, stream)
// (splitmix64), never a shared sequential generator, and every ray writes
// its own output slot, so the cloud is byte-identical for any thread count.
// Memory: the output arrays (allocated once per run from exact per-column
// counts of a first, intersection-only pass) and one counter per column.
//
// Output order: station by station, azimuth column by column, elevation
// upward within a column (the order a real scanner records).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/point_cloud.h"
#include "stages/geometry/synth/scene.h"

namespace pb {

struct SynthScanOptions {
  uint64_t target_points = 2'000'000;  // total valid returns to aim for (>= 1000)
  uint64_t seed = 1;                   // noise; station placement is fixed
  int stations = 3;                    // 1..16
  double noise_m = 0.002;              // range noise sigma along the ray, meters
  double color_noise = 0.02;           // color noise sigma, [0, 1] units
  double min_elevation_deg = -60;      // lowest elevation the scanner records
  // Fraction done in [0, 1], called about once per station and phase.
  std::function<void(double)> progress;
};

struct SynthScanResult {
  PointCloud cloud;               // positions, colors, station_ids, stations; origin 0
  double angular_step_rad = 0;    // azimuth and elevation step
  uint64_t rays = 0;              // rays shot (all stations)
  double median_spacing_m = 0;    // see EstimateMedianSpacing
};

// Station positions (meters, absolute): a sunflower pattern over the inner
// 60% of the floor plan, heights 1.45..1.55 m; open scenes: their ring
// (objects.h; empty if count exceeds its room). Deterministic.
std::vector<Vec3> SynthStations(const SynthScene& scene, int count);

// Scans the scene. Status::Invalid for out-of-range options.
Expected<SynthScanResult> SimulateScan(const SynthScene& scene, const SynthScanOptions& options);

// Median nearest-neighbor distance measured in the surface's tangent plane
// (so range noise does not inflate it), over ~2000 evenly spread points of
// `cloud`; neighbors are searched among all points of the cloud within a few
// expected spacings. 0 for fewer than 2 points.
double EstimateMedianSpacing(const SynthScene& scene, const PointCloud& cloud);

}  // namespace pb
