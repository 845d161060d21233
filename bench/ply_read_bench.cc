// ply_read_bench: throughput of the PLY reader's binary fast path on the
// pointbake points layout (float xyz + uchar rgb + ushort station, 17 bytes
// a point). Writes a 10^7-point file (~170 MB) into FOLDER once, then reads
// it three times and prints the best time in MB/s (10^6 bytes per second).
// Given PLY files instead, reads each of them the same way, in turn, so
// their times are comparable as ratios within one run (e.g. a structured
// scan with its row/col grid, which is tested for the scanner's place, and
// the same file with those properties renamed).
//
//   ply_read_bench [FOLDER=/tmp] [POINTS=10000000]
//   ply_read_bench FILE.ply...
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "bench/bench_clock.h"
#include "stages/geometry/io/ply.h"

namespace {

// Best of three reads of `path`, in seconds; < 0 if a read failed.
double BestRead(const std::string& path, size_t expected_points) {
  double best = 1e30;
  for (int run = 0; run < 3; ++run) {
    const auto start = pb::bench::Clock::now();
    auto read = pb::ReadPlyPoints(path);
    const double seconds = pb::bench::Seconds(start);
    if (!read.ok() || (expected_points != 0 && read->points.size() != expected_points)) {
      std::fprintf(stderr, "%s: read failed: %s\n", path.c_str(),
                   read.ok() ? "wrong point count" : read.status().message().c_str());
      return -1;
    }
    best = std::min(best, seconds);
  }
  return best;
}

bool IsPly(const char* arg) {
  const std::string name = arg;
  return name.size() > 4 && name.substr(name.size() - 4) == ".ply" && std::filesystem::exists(name);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pb;
  if (argc > 1 && IsPly(argv[1])) {
    for (int i = 1; i < argc; ++i) {
      const double bytes = static_cast<double>(std::filesystem::file_size(argv[i]));
      const double best = BestRead(argv[i], 0);
      if (best < 0) return 1;
      std::printf("ReadPlyPoints %s, %.0f MB: best %.3f s = %.0f MB/s\n", argv[i], bytes / 1e6,
                  best, bytes / 1e6 / best);
    }
    return 0;
  }
  const std::string folder = argc > 1 ? argv[1] : "/tmp";
  const size_t n = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 10'000'000;
  const std::string path = folder + "/pb_ply_read_bench_" + std::to_string(n) + ".ply";
  if (!std::filesystem::exists(path)) {
    PointCloud cloud;
    cloud.positions.resize(3 * n);
    cloud.colors.resize(3 * n);
    cloud.station_ids.resize(n);
    cloud.stations = {{0, 0, 0}, {1, 2, 3}};
    for (size_t i = 0; i < 3 * n; ++i) {
      cloud.positions[i] = static_cast<float>(i % 1000) * 0.01f;
      cloud.colors[i] = static_cast<uint8_t>(i);
    }
    for (size_t i = 0; i < n; ++i) cloud.station_ids[i] = static_cast<uint16_t>(i % 2);
    const Status written = WritePlyPoints(path, cloud);
    if (!written.ok()) {
      std::fprintf(stderr, "%s\n", written.message().c_str());
      return 1;
    }
  }
  const double bytes = static_cast<double>(std::filesystem::file_size(path));
  const double best = BestRead(path, n);
  if (best < 0) return 1;
  std::printf("ReadPlyPoints %zu points, %.0f MB: best %.3f s = %.0f MB/s (file %s kept)\n", n,
              bytes / 1e6, best, bytes / 1e6 / best, path.c_str());
  return 0;
}
