// Wall and CPU clocks shared by the benchmark programs in bench/.
#pragma once

#include <sys/resource.h>

#include <chrono>

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

}  // namespace pb::bench
