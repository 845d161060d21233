// libFuzzer target for the PCD reader (pb::ReadPcd).
//
// Seeds: the shared files livingroom_fragment/fragment.pcd (binary) and
// office_kinect/office1.pcd (binary_compressed) (run.sh). The input is handed
// over through a memfd, as /proc/self/fd/N, because the reader takes a path.
// Besides sanitizer findings, an accepted file must give a consistent cloud:
// attribute arrays of the right length, intensities in [0, 1], station ids
// inside `stations`.
#include <cstddef>
#include <cstdint>

#include "stages/geometry/io/pcd.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const pb::fuzz::FuzzInput input("pcd_fuzz", data, size);
  if (!input.ok()) return 0;
  pb::ScanReadOptions options;
  options.drop_invalid_points = (size & 1) != 0;  // exercise both NaN paths
  auto result = pb::ReadPcd(input.path(), options);
  if (result.ok()) {
    const pb::PointCloud& cloud = result->points;
    if (!pb::Validate(cloud).ok()) __builtin_trap();
    for (float intensity : cloud.intensities) {
      if (!(intensity >= 0 && intensity <= 1)) __builtin_trap();
    }
    if (cloud.has_stations() && cloud.station_ids.size() != cloud.size()) __builtin_trap();
    for (uint16_t id : cloud.station_ids) {
      if (id >= cloud.stations.size()) __builtin_trap();
    }
  }
  return 0;
}
