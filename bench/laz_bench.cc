// LAZ decoding speed (docs/laz.md): synthetic airborne scans (point format
// 7, layered, and 3, pointwise; one scanner channel, 50 000-point chunks)
// compressed by the test encoder, then decoded by LazReader (every field)
// and read by ReadLas (the layers io.read_points uses, into a PointCloud),
// on 1 and on 2 threads; best of 3. Writes the .laz files and their .las
// twins to FOLDER so bench/laz_decode.sh can time the npm laz-perf decoder
// on the same files and check that it decodes the same points.
// Usage: laz_bench [FOLDER] [POINTS]   (default /tmp, 5000000); with
// PB_LAZ_BENCH_REUSE set, files already in FOLDER are decoded, not rewritten.
#include <pthread.h>
#include <tbb/task_arena.h>
#include <tbb/task_scheduler_observer.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <string>
#include <thread>

#include "bench/bench_clock.h"
#include "stages/geometry/io/las.h"
#include "stages/geometry/io/laz.h"
#include "stages/geometry/io/laz_test_encoder.h"

namespace {

using pb::bench::Clock;

template <typename T>
T Get(const std::string& bytes, size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;
}

// Decodes every record of `path` (all layers); returns the point count.
uint64_t DecodeAll(const std::string& path, const std::string& bytes) {
  pb::LazPointLayout layout;
  layout.point_offset = Get<uint32_t>(bytes, 96);
  layout.point_format = static_cast<uint8_t>(bytes[104]) & 0x3F;
  layout.record_bytes = Get<uint16_t>(bytes, 105);
  layout.point_count = bytes[25] == 4 ? Get<uint64_t>(bytes, 247) : Get<uint32_t>(bytes, 107);
  const size_t vlr = layout.point_offset - (34 + 6 * (layout.point_format >= 6 ? 2 : 3));
  pb::BufferedInput in;
  if (!in.Open(path, "a LAZ file", nullptr).ok()) std::abort();
  pb::LazOptions options;
  options.all_layers = true;
  auto reader = pb::LazReader::Open(
      &in, path, layout,
      {reinterpret_cast<const uint8_t*>(bytes.data()) + vlr, layout.point_offset - vlr}, vlr,
      options);
  if (!reader.ok()) {
    std::fprintf(stderr, "%s\n", reader.status().message().c_str());
    std::exit(1);
  }
  uint64_t points = 0;
  for (;;) {
    std::span<const uint8_t> records;
    const pb::Status status = (*reader)->Next(&records);
    if (!status.ok()) {
      std::fprintf(stderr, "%s\n", status.message().c_str());
      std::exit(1);
    }
    if (records.empty()) break;
    points += records.size() / layout.record_bytes;
  }
  return points;
}

struct Timing {
  double wall_s = 1e30;
  double cpu_s = 0;
  double busiest_thread_cpu_s = 0;  // CPU seconds of the thread that worked most
};

double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

// CPU seconds each thread spends in the arena: how the chunks spread over
// the threads, whatever else runs on the machine. With the work split
// evenly the busiest thread holds half of it, and on free cores the wall
// time would be that half.
class ThreadCpu : public tbb::task_scheduler_observer {
 public:
  explicit ThreadCpu(tbb::task_arena& arena) : tbb::task_scheduler_observer(arena) {
    observe(true);
  }
  ~ThreadCpu() override { observe(false); }
  void on_scheduler_entry(bool) override {
    std::lock_guard lock(mutex_);
    entered_[std::this_thread::get_id()] = ThreadCpuSeconds();
  }
  void on_scheduler_exit(bool) override {
    std::lock_guard lock(mutex_);
    const auto id = std::this_thread::get_id();
    used_[id] += ThreadCpuSeconds() - entered_[id];
  }
  double Busiest() {
    std::lock_guard lock(mutex_);
    double most = 0;
    for (const auto& [id, seconds] : used_) most = std::max(most, seconds);
    return most;
  }

 private:
  std::mutex mutex_;
  std::map<std::thread::id, double> entered_, used_;
};

template <typename F>
Timing Best(int threads, F run) {
  Timing best;
  for (int repeat = 0; repeat < 3; ++repeat) {
    tbb::task_arena arena(threads);
    arena.initialize();
    double busiest = 0;
    const double cpu = pb::bench::CpuSeconds();
    const auto start = Clock::now();
    {
      ThreadCpu per_thread(arena);
      arena.execute(run);
      busiest = per_thread.Busiest();
    }
    const double wall = pb::bench::Seconds(start);
    if (wall < best.wall_s) best = {wall, pb::bench::CpuSeconds() - cpu, busiest};
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string folder = argc > 1 ? argv[1] : "/tmp";
  const size_t points = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 5000000;
  std::printf(
      "| file | decoder | threads | wall s | CPU s | busiest thread CPU s | Mpoints/s | Mpoints/s "
      "per CPU-second |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (int format : {7, 3}) {
    const std::string name = format == 7 ? "layered_f7" : "pointwise_f3";
    const std::string path = folder + "/laz_bench_" + name + ".laz";
    std::string laz;
    if (std::getenv("PB_LAZ_BENCH_REUSE") && std::filesystem::exists(path)) {  // decoding only
      std::ifstream in(path, std::ios::binary);
      laz.assign(std::istreambuf_iterator<char>(in), {});
    } else {
      const std::string las = pb::laz::SyntheticAirborneLas(format, points, 0, 7, 1);
      laz = pb::laz::CompressLas(las, {});
      std::ofstream(path, std::ios::binary) << laz;
      // The uncompressed twin, for the oracle's comparison.
      std::ofstream(folder + "/laz_bench_" + name + ".las", std::ios::binary) << las;
    }

    for (int threads : {1, 2}) {
      uint64_t decoded = 0;
      const Timing all = Best(threads, [&] { decoded = DecodeAll(path, laz); });
      const Timing read = Best(threads, [&] {
        auto cloud = pb::ReadLas(path, {});
        if (!cloud.ok()) {
          std::fprintf(stderr, "%s\n", cloud.status().message().c_str());
          std::exit(1);
        }
        decoded = cloud->points.size();
      });
      for (const auto& [what, t] : {std::pair{"LazReader, every field", all},
                                    std::pair{"ReadLas (io.read_points)", read}}) {
        std::printf("| %s (%.1f MB) | %s | %d | %.3f | %.3f | %.3f | %.2f | %.2f |\n", name.c_str(),
                    laz.size() / 1e6, what, threads, t.wall_s, t.cpu_s, t.busiest_thread_cpu_s,
                    decoded / t.wall_s / 1e6, decoded / t.cpu_s / 1e6);
      }
    }
  }
  return 0;
}
