// seen_through_bench: the look through the stations (points/seen_through.h)
// on a site of many stations: ROWS x COLS rooms of 6 x 5 x 3 m, 0.25 m walls
// between them, a door (1 x 2.1 m) to the next room of the row and, from the
// first room of each row, one to the next row; two stations per room at 1.2
// and 1.5 m, each scanning on an equirectangular grid (latitudes -80 to 85
// degrees) whose step gives about POINTS points in all. A ray that leaves its
// room through a door goes on into the next room (up to three rooms). Each
// room also holds a person (a 0.3 x 0.3 x 1.7 m box of points) that only its
// first station recorded: its second station sees the wall behind it.
//
// Prints the cloud, then the wall and CPU seconds of SeenThroughPoints and
// what it found, for each way of choosing the points a station reads (all
// of them, or only those nearer than its farthest sample), on the same cloud
// in one run; the two must find the same points.
//
//   seen_through_bench [POINTS=10000000] [ROWS=6] [COLS=8]
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>
#include <vector>

#include "bench/bench_clock.h"
#include "stages/geometry/points/seen_through.h"

namespace {

constexpr double kRoomX = 6, kRoomY = 5, kRoomZ = 3, kWall = 0.25;
constexpr double kDoorLo = 2, kDoorHi = 3, kDoorZ = 2.1;  // door span along its wall, height

struct Site {
  int rows, columns;
  double x0(int c) const { return c * (kRoomX + kWall); }
  double y0(int r) const { return r * (kRoomY + kWall); }
};

// Where the ray from `from` (inside room r, c) along `u` ends: the exit
// point of the last room it enters through doors.
std::array<double, 3> Cast(const Site& site, int r, int c, std::array<double, 3> from, const std::array<double, 3>& u,
                           double* range) {
  double travelled = 0;
  for (int rooms = 0; rooms < 3; ++rooms) {
    const double lo[3] = {site.x0(c), site.y0(r), 0}, hi[3] = {site.x0(c) + kRoomX, site.y0(r) + kRoomY, kRoomZ};
    double t = 1e30;
    int axis = -1;
    for (int a = 0; a < 3; ++a) {
      if (u[size_t(a)] == 0) continue;
      const double bound = u[size_t(a)] > 0 ? hi[a] : lo[a];
      const double ta = (bound - from[size_t(a)]) / u[size_t(a)];
      if (ta < t) t = std::max(ta, 0.0), axis = a;
    }
    const std::array<double, 3> exit = {from[0] + t * u[0], from[1] + t * u[1], from[2] + t * u[2]};
    travelled += t;
    // A door: +x to the next room of the row, -x back; +y / -y between the
    // rows' first rooms.
    bool door = false;
    int nr = r, nc = c;
    if (axis == 0 && exit[2] < kDoorZ && exit[1] - lo[1] > kDoorLo && exit[1] - lo[1] < kDoorHi) {
      nc = u[0] > 0 ? c + 1 : c - 1;
      door = nc >= 0 && nc < site.columns;
    } else if (axis == 1 && c == 0 && exit[2] < kDoorZ && exit[0] - lo[0] > kDoorLo && exit[0] - lo[0] < kDoorHi) {
      nr = u[1] > 0 ? r + 1 : r - 1;
      door = nr >= 0 && nr < site.rows;
    }
    if (!door || rooms == 2) {
      *range = travelled;
      return exit;
    }
    // Through the wall's thickness into the next room; a ray that leaves
    // the opening on the way hits the jamb (taken as the point where it
    // meets the next room's wall face, which the next room's stations see).
    const double through = kWall / std::abs(u[size_t(axis)]);
    travelled += through;
    from = {exit[0] + through * u[0], exit[1] + through * u[1], exit[2] + through * u[2]};
    const int along = axis == 0 ? 1 : 0;
    const double lateral = from[size_t(along)] - (along == 1 ? lo[1] : lo[0]);
    if (from[2] >= kDoorZ || lateral <= kDoorLo || lateral >= kDoorHi) {
      *range = travelled;
      return from;
    }
    r = nr;
    c = nc;
  }
  *range = travelled;
  return from;
}

}  // namespace

int main(int argc, char** argv) {
  const double target = argc > 1 ? std::atof(argv[1]) : 1e7;
  const Site site{argc > 2 ? std::atoi(argv[2]) : 6, argc > 3 ? std::atoi(argv[3]) : 8};
  const int rooms = site.rows * site.columns, stations = 2 * rooms;
  constexpr double kPi = std::numbers::pi;
  const double lat_lo = -80 * kPi / 180, lat_hi = 85 * kPi / 180;
  // step^2 = (2 pi) (lat span) / (points per station)
  const double step = std::sqrt(2 * kPi * (lat_hi - lat_lo) / (target / stations));

  pb::PointCloud cloud;
  std::vector<float> spacing;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int r = 0; r < site.rows; ++r)
    for (int c = 0; c < site.columns; ++c)
      for (int k = 0; k < 2; ++k) {
        const std::array<double, 3> at = {site.x0(c) + (k ? 4.2 : 1.8), site.y0(r) + (k ? 2.0 : 2.5), k ? 1.2 : 1.5};
        const uint16_t id = uint16_t(cloud.stations.size());
        cloud.stations.push_back(at);
        for (double lat = lat_lo; lat < lat_hi; lat += step)
          for (double lon = 0; lon < 2 * kPi; lon += step) {
            const std::array<double, 3> u = {std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
            double range = 0;
            const std::array<double, 3> hit = Cast(site, r, c, at, u, &range);
            for (double v : hit) cloud.positions.push_back(float(v));
            cloud.station_ids.push_back(id);
            spacing.push_back(float(range * step));
          }
        if (k == 0) {  // the person only this station recorded
          const double px = site.x0(c) + 3.0, py = site.y0(r) + 4.0;
          for (int i = 0; i < 600; ++i) {
            cloud.positions.push_back(float(px + 0.3 * unit(rng)));
            cloud.positions.push_back(float(py + 0.3 * unit(rng)));
            cloud.positions.push_back(float(0.3 + 1.4 * unit(rng)));
            cloud.station_ids.push_back(id);
            spacing.push_back(0.01f);
          }
        }
      }
  std::printf("%zu points, %d stations in %d x %d rooms, angular step %.3f mrad, %d person points\n", cloud.size(),
              stations, site.rows, site.columns, step * 1e3, rooms * 600);
  std::fflush(stdout);

  std::vector<uint8_t> results[2];
  for (int reach = 0; reach < 2; ++reach) {
    pb::SeenThroughOptions options;
    options.within_reach_only = reach == 1;
    pb::SeenThroughReport report;
    const auto wall = pb::bench::Clock::now();
    const double cpu = pb::bench::CpuSeconds();
    pb::Expected<std::vector<uint8_t>> seen = pb::SeenThroughPoints(cloud, spacing, options, &report);
    if (!seen.ok()) {
      std::fprintf(stderr, "%s\n", seen.status().message().c_str());
      return 1;
    }
    std::printf("%-36s %6.2f s wall, %6.2f s CPU, %.3g cones read: %zu seen through, %zu decided\n",
                reach ? "points within each station's reach:" : "every point, every station:",
                pb::bench::Seconds(wall), pb::bench::CpuSeconds() - cpu, double(report.cones_read),
                report.seen_through, report.decided);
    std::fflush(stdout);
    results[reach] = std::move(seen).value();
  }
  if (results[0] != results[1]) {
    std::fprintf(stderr, "the two ways found different points\n");
    return 1;
  }
  std::printf("the same points either way\n");
  return 0;
}
