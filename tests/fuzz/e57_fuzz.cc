// libFuzzer target for the E57 reader (pb::ReadE57).
//
// Every E57 page carries a CRC-32C, so random mutations almost always stop at
// the first page check. Build pb_geometry's e57_binary.cc with
// -DPB_E57_FUZZ_SKIP_CRC for fuzzing (fuzz builds only, never a release) so
// inputs reach the header, XML and CompressedVector decoders. Seeds: the
// shared sample files bunny/bunnyDouble.e57 and pump_e57/*.e57 (run.sh).
//
// The input is handed over through a memfd, as /proc/self/fd/N, because the
// reader takes a path.
#include <cstddef>
#include <cstdint>

#include "stages/geometry/io/e57.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const pb::fuzz::FuzzInput input("e57_fuzz", data, size);
  if (!input.ok()) return 0;
  pb::ScanReadOptions options;
  options.drop_invalid_points = (size & 1) != 0;  // exercise both NaN paths
  auto result = pb::ReadE57(input.path(), options);
  if (result.ok()) {
    // Touch the output so sanitizers see any inconsistency.
    const pb::Status valid = pb::Validate(result->points);
    if (!valid.ok()) __builtin_trap();
  }
  return 0;
}
