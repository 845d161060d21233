// libFuzzer target for the PTX reader (pb::ReadPtx).
//
// Seeds: the shared PDAL sample files ptx/*.ptx (run.sh). The input is handed
// over through a memfd, as /proc/self/fd/N, because the reader takes a path.
// Besides sanitizer findings, an accepted file must give a consistent cloud:
// attribute arrays of the right length and station ids inside `stations`.
#include <cstddef>
#include <cstdint>

#include "stages/geometry/io/ptx.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const pb::fuzz::FuzzInput input("ptx_fuzz", data, size);
  if (!input.ok()) return 0;
  pb::ScanReadOptions options;
  options.drop_invalid_points = (size & 1) != 0;  // exercise both NaN paths
  auto result = pb::ReadPtx(input.path(), options);
  if (result.ok()) {
    const pb::PointCloud& cloud = result->points;
    if (!pb::Validate(cloud).ok()) __builtin_trap();
    if (cloud.station_ids.size() != cloud.size()) __builtin_trap();
    for (uint16_t id : cloud.station_ids) {
      if (id >= cloud.stations.size()) __builtin_trap();
    }
  }
  return 0;
}
