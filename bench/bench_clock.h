// Wall and CPU clocks and memory gauges shared by the benchmark programs in
// bench/.
#pragma once

#include <sys/resource.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <string>

namespace pb::bench {

using Clock = std::chrono::steady_clock;

// Wall seconds since `since`.
inline double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// CPU seconds (user + system) of the process so far: on a shared machine
// wall time depends on the load, CPU time much less.
inline double CpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// A field of /proc/self/status ("VmRSS:", "VmHWM:") in bytes; 0 if absent.
inline double StatusBytes(const char* field) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(field, 0) == 0) return std::atof(line.c_str() + std::string(field).size()) * 1024;
  return 0;
}

// Resets the peak RSS (VmHWM) to the current RSS (Linux >= 4.0).
inline void ResetPeakRss() { std::ofstream("/proc/self/clear_refs") << "5"; }

}  // namespace pb::bench
