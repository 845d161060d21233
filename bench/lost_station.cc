// lost_station: how well FindLostStation (points/lost_station.h) finds a
// station that the file lost, on scans whose stations are known.
//
// For each SCAN (any format ReadScan reads): when the file has stations,
// each station's points alone with the station taken away (one scan
// exported without its position), then all its points together (a cloud
// merged from them, which no single station explains); when it has none,
// the cloud as it is. Prints what was found, how far from the station the
// file had, and the seconds it took.
//
//   lost_station [--units U] [--up x,y,z] SCAN...
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "base/units.h"
#include "stages/geometry/io/scan_read.h"
#include "stages/geometry/points/lost_station.h"

namespace {

using pb::LostStation;
using pb::PointCloud;

void Report(const std::string& what, const PointCloud& cloud, const pb::LostStationOptions& options,
            const std::array<double, 3>* truth) {
  const auto start = std::chrono::steady_clock::now();
  const pb::Expected<LostStation> lost = pb::FindLostStation(cloud, options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!lost.ok()) {
    std::printf("%s: %zu points: error: %s\n", what.c_str(), cloud.size(), lost.status().message().c_str());
    return;
  }
  std::string off;
  if (lost->found && truth != nullptr) {
    double d2 = 0;
    for (int a = 0; a < 3; ++a) d2 += (lost->position[a] - (*truth)[a]) * (lost->position[a] - (*truth)[a]);
    char buf[64];
    std::snprintf(buf, sizeof buf, ", %.3f m from the file's station", std::sqrt(d2));
    off = buf;
  }
  std::printf("%s: %zu points, %.1f s: %s: %s (%s)", what.c_str(), cloud.size(), seconds,
              lost->found ? "FOUND" : "none", lost->verdict.c_str(), lost->figures.c_str());
  if (lost->found)
    std::printf(" at %.3f, %.3f, %.3f m%s", lost->position[0], lost->position[1], lost->position[2], off.c_str());
  std::printf("\n");
}

// The points of `cloud` seen from station `s`, without stations.
PointCloud StationAlone(const PointCloud& cloud, size_t s) {
  PointCloud one;
  one.origin = cloud.origin;
  for (size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.station_ids[i] != s) continue;
    one.positions.insert(one.positions.end(), &cloud.positions[3 * i], &cloud.positions[3 * i + 3]);
  }
  return one;
}

}  // namespace

int main(int argc, char** argv) {
  pb::LostStationOptions options;
  double unit_m = 1;
  std::vector<std::string> scans;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--units" && i + 1 < argc) {
      const auto unit = pb::MetersPerUnit(argv[++i]);
      if (!unit) return std::fprintf(stderr, "lost_station: unknown unit %s\n", argv[i]), 2;
      unit_m = *unit;
    } else if (arg == "--up" && i + 1 < argc) {
      if (std::sscanf(argv[++i], "%lf,%lf,%lf", &options.up[0], &options.up[1], &options.up[2]) != 3)
        return std::fprintf(stderr, "lost_station: --up x,y,z\n"), 2;
    } else {
      scans.push_back(arg);
    }
  }
  if (scans.empty()) return std::fprintf(stderr, "usage: lost_station [--units U] [--up x,y,z] SCAN...\n"), 2;
  for (const std::string& path : scans) {
    pb::ScanReadOptions read_options;
    read_options.drop_invalid_points = true;
    pb::Expected<pb::ScanReadResult> read = pb::ReadScan(path, "auto", read_options);
    if (!read.ok()) return std::fprintf(stderr, "%s\n", read.status().message().c_str()), 1;
    PointCloud& cloud = read->points;
    pb::ConvertToMeters(unit_m, &cloud);
    if (!cloud.has_stations()) {
      Report(path, cloud, options, nullptr);
      continue;
    }
    for (size_t s = 0; s < cloud.stations.size(); ++s) {
      const PointCloud one = StationAlone(cloud, s);
      if (one.size() < 1000) continue;
      Report(path + " station " + std::to_string(s) + " alone", one, options, &cloud.stations[s]);
    }
    if (cloud.stations.size() > 1) {
      PointCloud merged = cloud;
      merged.station_ids.clear();
      merged.stations.clear();
      Report(path + " merged", merged, options, nullptr);
    }
  }
  return 0;
}
