// Simulated terrestrial laser scanner (synth_scanner.h).
//
// Models a phase-based TLS of the kind used for the paper's castle scans
// (regular azimuth x elevation sweep, ~2 mm spacing at a few meters, mm-level
// range noise, colors from a co-registered camera). Departures: no beam
// divergence / mixed pixels at edges, no intensity falloff, no max range
// (rooms are small), colors are the albedo (uniform white light).
#include "stages/geometry/synth/scanner.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <unordered_set>

#include "stages/geometry/synth/objects.h"

namespace pb {
namespace {

constexpr double kPi = std::numbers::pi;

uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Uniform in (0, 1]: never 0, so log() in Box-Muller is finite.
double UnitOpen(uint64_t h) { return (static_cast<double>(h >> 11) + 1.0) * 0x1.0p-53; }

// Two independent standard normals for (seed, ray, stream): Box-Muller on
// two counter-based uniforms.
void Normals(uint64_t seed, uint64_t ray, uint64_t stream, double* a, double* b) {
  const uint64_t key = SplitMix64(SplitMix64(seed) ^ ray) ^ (stream * 0xD1B54A32D192ED03ull);
  const double u1 = UnitOpen(SplitMix64(key)), u2 = UnitOpen(SplitMix64(key ^ 0xA5A5A5A5A5A5A5A5ull));
  const double r = std::sqrt(-2 * std::log(u1));
  *a = r * std::cos(2 * kPi * u2);
  *b = r * std::sin(2 * kPi * u2);
}

// The sweep of every station: n_az columns of n_el rays each.
struct Sweep {
  int n_az = 0, n_el = 0;
  double min_elevation_rad = 0, el_step = 0, az_step = 0;

  Vec3 Direction(int station, int stations, int col, int row) const {
    // Stations' azimuth grids are staggered so that overlaps do not align.
    const double az = (col + static_cast<double>(station) / stations) * az_step;
    const double el = min_elevation_rad + (row + 0.5) * el_step;
    return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  }
};

Sweep MakeSweep(double min_elevation_rad, double rays_per_station) {
  Sweep sweep;
  sweep.min_elevation_rad = min_elevation_rad;
  const double span = kPi / 2 - min_elevation_rad;
  const double step = std::sqrt(2 * kPi * span / std::max(rays_per_station, 32.0));
  sweep.n_el = std::max(4, static_cast<int>(std::lround(span / step)));
  // n_az from the exact ray budget, so rounding n_el does not skew the total.
  sweep.n_az = std::max(8, static_cast<int>(std::lround(rays_per_station / sweep.n_el)));
  sweep.el_step = span / sweep.n_el;
  sweep.az_step = 2 * kPi / sweep.n_az;
  return sweep;
}

// Valid returns per (station, column), in station-major order.
std::vector<uint32_t> CountReturns(const SynthScene& scene, const std::vector<Vec3>& stations,
                                   const Sweep& sweep) {
  const int n = static_cast<int>(stations.size());
  std::vector<uint32_t> counts(static_cast<size_t>(n) * sweep.n_az);
  tbb::parallel_for(size_t{0}, counts.size(), [&](size_t column) {
    const int station = static_cast<int>(column / sweep.n_az), col = static_cast<int>(column % sweep.n_az);
    uint32_t count = 0;
    for (int row = 0; row < sweep.n_el; ++row) {
      if (Intersect(scene, stations[station], sweep.Direction(station, n, col, row))) ++count;
    }
    counts[column] = count;
  });
  return counts;
}

uint64_t Sum(const std::vector<uint32_t>& counts) {
  uint64_t total = 0;
  for (uint32_t c : counts) total += c;
  return total;
}

double SurfaceArea(const SynthScene& s) {
  if (s.objects) return ObjectsArea(*s.objects);
  const double w = s.width_m, d = s.depth_m, h = s.height_m;
  switch (s.shape) {
    case SynthShape::kTower:
      return kPi * w * h + 2 * kPi * w * w / 4;
    case SynthShape::kVault: {
      const double spring = h - d / 2;
      return 2 * w * spring + 2 * (d * spring + kPi * d * d / 8) + w * d + kPi * d / 2 * w;
    }
    case SynthShape::kBox:
    case SynthShape::kObjects:
      break;
  }
  return 2 * (w + d) * h + 2 * w * d;
}

}  // namespace

std::vector<Vec3> SynthStations(const SynthScene& scene, int count) {
  if (scene.objects) {
    Expected<std::vector<Vec3>> ring = ObjectsStations(*scene.objects, count);
    return ring.ok() ? std::move(ring).value() : std::vector<Vec3>();
  }
  std::vector<Vec3> stations;
  const double golden_angle = kPi * (3 - std::sqrt(5.0));
  const double half_x = 0.6 * scene.width_m / 2, half_y = 0.6 * scene.depth_m / 2;
  for (int k = 0; k < count; ++k) {
    const double r = count == 1 ? 0.0 : std::sqrt((k + 0.5) / count);
    const double theta = 0.4 + k * golden_angle;
    double x = half_x * r * std::cos(theta), y = half_y * r * std::sin(theta);
    if (scene.shape == SynthShape::kTower) {
      // The sunflower over a disk of 60% of the radius.
      x = half_x * r * std::cos(theta), y = half_x * r * std::sin(theta);
    }
    stations.push_back({x, y, 1.5 + 0.05 * ((k % 3) - 1)});
  }
  return stations;
}

Expected<SynthScanResult> SimulateScan(const SynthScene& scene, const SynthScanOptions& options) {
  if (options.target_points < 1000) {
    return Status::Invalid("points: must be >= 1000, got " + std::to_string(options.target_points));
  }
  if (options.stations < 1 || options.stations > 16) {
    return Status::Invalid("stations: must be 1..16, got " + std::to_string(options.stations));
  }
  if (!(options.noise_m >= 0) || !(options.color_noise >= 0 && options.color_noise <= 1)) {
    return Status::Invalid("noise_mm must be >= 0 and color_noise in [0, 1]");
  }
  if (!(options.min_elevation_deg > -90 && options.min_elevation_deg < 80)) {
    return Status::Invalid("min_elevation_deg: must be in (-90, 80)");
  }
  if (scene.objects) PB_RETURN_IF_ERROR(ObjectsStations(*scene.objects, options.stations).status());
  const std::vector<Vec3> stations = SynthStations(scene, options.stations);
  const int n = options.stations;
  const double min_el = options.min_elevation_deg * kPi / 180;
  auto progress = [&options](double f) {
    if (options.progress) options.progress(f);
  };

  // Pilot: the fraction of rays that return, on a coarse sweep.
  const Sweep pilot = MakeSweep(min_el, 20000);
  const double pilot_rays = static_cast<double>(n) * pilot.n_az * pilot.n_el;
  const double valid_fraction =
      std::max(0.05, static_cast<double>(Sum(CountReturns(scene, stations, pilot))) / pilot_rays);
  const double target = static_cast<double>(options.target_points);
  Sweep sweep = MakeSweep(min_el, target / valid_fraction / n);
  std::vector<uint32_t> counts = CountReturns(scene, stations, sweep);
  uint64_t total = Sum(counts);
  // One correction if the pilot misjudged (openings seen at grazing angles).
  if (std::abs(static_cast<double>(total) - target) > 0.03 * target && total > 0) {
    const double rays = static_cast<double>(sweep.n_az) * sweep.n_el * target / static_cast<double>(total);
    sweep = MakeSweep(min_el, rays);
    counts = CountReturns(scene, stations, sweep);
    total = Sum(counts);
  }
  progress(0.1);

  std::vector<uint64_t> offsets(counts.size() + 1, 0);
  for (size_t c = 0; c < counts.size(); ++c) offsets[c + 1] = offsets[c] + counts[c];
  SynthScanResult result;
  PointCloud& cloud = result.cloud;
  cloud.positions.resize(3 * total);
  cloud.colors.resize(3 * total);
  cloud.station_ids.resize(total);
  cloud.stations = stations;
  result.angular_step_rad = sweep.az_step;
  result.rays = static_cast<uint64_t>(n) * sweep.n_az * sweep.n_el;

  constexpr int kChunksPerStation = 4;
  for (int station = 0; station < n; ++station) {
    for (int chunk = 0; chunk < kChunksPerStation; ++chunk) {
      const int col_begin = sweep.n_az * chunk / kChunksPerStation;
      const int col_end = sweep.n_az * (chunk + 1) / kChunksPerStation;
      tbb::parallel_for(col_begin, col_end, [&](int col) {
        const size_t column = static_cast<size_t>(station) * sweep.n_az + col;
        uint64_t out = offsets[column];
        for (int row = 0; row < sweep.n_el; ++row) {
          const Vec3 dir = sweep.Direction(station, n, col, row);
          const std::optional<SynthHit> hit = Intersect(scene, stations[station], dir);
          if (!hit) continue;
          const uint64_t ray = column * sweep.n_el + row;
          double range_noise, red_noise, green_noise, blue_noise;
          Normals(options.seed, ray, 0, &range_noise, &red_noise);
          Normals(options.seed, ray, 1, &green_noise, &blue_noise);
          const std::array<double, 3> albedo = HitAlbedo(scene, *hit);
          const double color_noise[3] = {red_noise, green_noise, blue_noise};
          for (int c = 0; c < 3; ++c) {
            cloud.positions[3 * out + c] = static_cast<float>(hit->point[c] + options.noise_m * range_noise * dir[c]);
            const double value = albedo[c] + options.color_noise * color_noise[c];
            cloud.colors[3 * out + c] = static_cast<uint8_t>(std::lround(std::clamp(value, 0.0, 1.0) * 255));
          }
          cloud.station_ids[out] = static_cast<uint16_t>(station);
          ++out;
        }
      });
      progress(0.1 + 0.8 * (station * kChunksPerStation + chunk + 1) / (n * kChunksPerStation));
    }
  }
  result.median_spacing_m = EstimateMedianSpacing(scene, cloud);
  progress(1.0);
  return result;
}

double EstimateMedianSpacing(const SynthScene& scene, const PointCloud& cloud) {
  const size_t n = cloud.size();
  if (n < 2) return 0;
  const double guess = std::sqrt(SurfaceArea(scene) / static_cast<double>(n));
  const double cell = std::max(0.01, 4 * guess);
  auto cell_of = [cell](const float* p, int axis) {
    return static_cast<int64_t>(std::floor(p[axis] / cell)) + (int64_t{1} << 20);
  };
  auto key_of = [](int64_t x, int64_t y, int64_t z) {
    return (static_cast<uint64_t>(x) << 42) | (static_cast<uint64_t>(y) << 21) | static_cast<uint64_t>(z);
  };
  const size_t samples = std::min<size_t>(2000, n);
  std::vector<size_t> sample_index(samples);
  std::unordered_set<uint64_t> wanted;
  for (size_t k = 0; k < samples; ++k) {
    sample_index[k] = k * n / samples + n / (2 * samples);
    const float* p = &cloud.positions[3 * sample_index[k]];
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz)
          wanted.insert(key_of(cell_of(p, 0) + dx, cell_of(p, 1) + dy, cell_of(p, 2) + dz));
  }
  // Points in the wanted cells, collected per block and merged in block
  // order (deterministic), then sorted by cell.
  constexpr size_t kBlock = 1 << 16;
  const size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::vector<std::pair<uint64_t, uint32_t>>> found(blocks);
  tbb::parallel_for(size_t{0}, blocks, [&](size_t b) {
    for (size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
      const float* p = &cloud.positions[3 * i];
      const uint64_t key = key_of(cell_of(p, 0), cell_of(p, 1), cell_of(p, 2));
      if (wanted.count(key)) found[b].push_back({key, static_cast<uint32_t>(i)});
    }
  });
  std::vector<std::pair<uint64_t, uint32_t>> points;
  for (auto& block : found) points.insert(points.end(), block.begin(), block.end());
  std::sort(points.begin(), points.end());

  std::vector<double> nearest(samples, -1);
  tbb::parallel_for(size_t{0}, samples, [&](size_t k) {
    const float* p = &cloud.positions[3 * sample_index[k]];
    const Vec3 normal = SampleSurface(scene, {p[0], p[1], p[2]}).normal;
    double best = -1;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const uint64_t key = key_of(cell_of(p, 0) + dx, cell_of(p, 1) + dy, cell_of(p, 2) + dz);
          auto it = std::lower_bound(points.begin(), points.end(), std::make_pair(key, uint32_t{0}));
          for (; it != points.end() && it->first == key; ++it) {
            if (it->second == sample_index[k]) continue;
            const float* q = &cloud.positions[3 * size_t{it->second}];
            const Vec3 diff = {double(q[0]) - p[0], double(q[1]) - p[1], double(q[2]) - p[2]};
            const double along = diff[0] * normal[0] + diff[1] * normal[1] + diff[2] * normal[2];
            if (std::abs(along) > cell / 2) continue;  // another surface (a corner)
            const double tangential =
                std::sqrt(std::max(0.0, diff[0] * diff[0] + diff[1] * diff[1] + diff[2] * diff[2] - along * along));
            if (best < 0 || tangential < best) best = tangential;
          }
        }
    nearest[k] = best;
  });
  std::vector<double> found_distances;
  for (double d : nearest) {
    if (d >= 0) found_distances.push_back(d);
  }
  if (found_distances.empty()) return cell;
  auto mid = found_distances.begin() + found_distances.size() / 2;
  std::nth_element(found_distances.begin(), mid, found_distances.end());
  return *mid;
}

}  // namespace pb
