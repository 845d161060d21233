// pcd_memory_bench: the PCD reader's peak memory against the decoded cloud,
// for each DATA kind (binary_compressed, binary, ascii) of a 5·10^6-point
// file with x y z rgb normal_x normal_y normal_z (all 4 bytes). Writes each
// file into FOLDER (up to ~300 MB), reads it, prints the peak RSS added by
// the read over the decoded cloud's bytes (docs/points.md), removes it.
// Linux only (/proc/self/status, /proc/self/clear_refs).
//
//   pcd_memory_bench [FOLDER=/tmp] [POINTS=5000000]
#include <malloc.h>

#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "bench/bench_clock.h"
#include "stages/geometry/io/pcd.h"

namespace {

template <typename T>
void AppendBytes(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // PCD binary is little-endian, as this host
  out->append(bytes, sizeof(T));
}

// Field `field` of point i: a 1000 x 1000 grid, hashed heights and colors.
float Value(int i, int field) {
  const uint32_t hash = static_cast<uint32_t>(i) * 2654435761u;
  switch (field) {
    case 0: return 0.01f * static_cast<float>(i % 1000);
    case 1: return 0.01f * static_cast<float>(i / 1000 % 1000);
    case 2: return 0.001f * static_cast<float>(hash >> 22);
    case 3: return std::bit_cast<float>(hash >> 8);  // packed 0x00RRGGBB
    case 4: return 0.6f;
    case 5: return (hash & 1) ? 0.8f : -0.8f;
    default: return 0;
  }
}

// binary_compressed: the fields one after the other (structure of arrays),
// as an LZF stream of literal runs only (32 bytes each, a valid stream that
// does not compress).
std::string CompressedBody(int n) {
  std::string soa;
  soa.reserve(size_t{28} * n);
  for (int field = 0; field < 7; ++field) {
    for (int i = 0; i < n; ++i) AppendBytes(&soa, Value(i, field));
  }
  std::string lzf;
  lzf.reserve(soa.size() + soa.size() / 32 + 1);
  for (size_t k = 0; k < soa.size(); k += 32) {
    const size_t run = std::min<size_t>(32, soa.size() - k);
    lzf.push_back(static_cast<char>(run - 1));
    lzf.append(soa, k, run);
  }
  std::string body;
  AppendBytes(&body, static_cast<uint32_t>(lzf.size()));
  AppendBytes(&body, static_cast<uint32_t>(soa.size()));
  return body + lzf;
}

void WriteCloud(const std::string& path, const std::string& data, int n) {
  std::ofstream out(path, std::ios::binary);
  out << "FIELDS x y z rgb normal_x normal_y normal_z\nSIZE 4 4 4 4 4 4 4\n"
         "TYPE F F F U F F F\nWIDTH "
      << n << "\nHEIGHT 1\nPOINTS " << n << "\nDATA " << data << "\n";
  if (data == "binary_compressed") {
    out << CompressedBody(n);
    return;
  }
  std::string chunk;
  for (int i = 0; i < n; ++i) {
    if (data == "binary") {
      for (int field = 0; field < 7; ++field) AppendBytes(&chunk, Value(i, field));
    } else {
      char line[160];
      std::snprintf(line, sizeof line, "%.9g %.9g %.9g %u %.9g %.9g %.9g\n", Value(i, 0),
                    Value(i, 1), Value(i, 2), std::bit_cast<uint32_t>(Value(i, 3)), Value(i, 4),
                    Value(i, 5), Value(i, 6));
      chunk += line;
    }
    if (chunk.size() > (1 << 20)) {
      out << chunk;
      chunk.clear();
    }
  }
  out << chunk;
}

}  // namespace

int main(int argc, char** argv) {
  using pb::bench::StatusBytes;
  const std::string folder = argc > 1 ? argv[1] : "/tmp";
  const int n = argc > 2 ? std::atoi(argv[2]) : 5'000'000;
  for (const std::string data : {"binary_compressed", "binary", "ascii"}) {
    const std::string path = folder + "/pb_pcd_memory_bench_" + data + ".pcd";
    WriteCloud(path, data, n);
    // Return freed heap pages (so the read cannot reuse resident memory
    // unseen), then reset the peak to the current RSS.
    ::malloc_trim(0);
    pb::bench::ResetPeakRss();
    const double before = StatusBytes("VmRSS:");
    if (before <= 0 || StatusBytes("VmHWM:") > before + (1 << 20)) {
      std::fprintf(stderr, "cannot reset the peak RSS (/proc/self/clear_refs)\n");
      return 1;
    }
    const auto read = pb::ReadPcd(path, {});
    const double peak = StatusBytes("VmHWM:");
    std::filesystem::remove(path);
    if (!read.ok()) {
      std::fprintf(stderr, "%s\n", read.status().message().c_str());
      return 1;
    }
    const double cloud_bytes = 4.0 * read->points.positions.size() +
                               4.0 * read->points.normals.size() + read->points.colors.size();
    std::printf("pcd %s, %zu points: decoded cloud %.1f MB; peak RSS %.1f MB = %.1f MB before "
                "the read + %.1f MB: ratio %.3f (whole process %.3f)\n",
                data.c_str(), read->points.size(), cloud_bytes / 1e6, peak / 1e6, before / 1e6,
                (peak - before) / 1e6, (peak - before) / cloud_bytes, peak / cloud_bytes);
  }
  return 0;
}
