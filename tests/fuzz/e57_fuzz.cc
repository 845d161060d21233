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
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "stages/geometry/e57.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const int fd = ::memfd_create("e57_fuzz", MFD_CLOEXEC);
  if (fd < 0) return 0;
  size_t written = 0;
  while (written < size) {
    const ssize_t n = ::write(fd, data + written, size - written);
    if (n <= 0) break;
    written += static_cast<size_t>(n);
  }
  if (written == size) {
    pb::ScanReadOptions options;
    options.drop_invalid_points = (size & 1) != 0;  // exercise both NaN paths
    auto result = pb::ReadE57("/proc/self/fd/" + std::to_string(fd), options);
    if (result.ok()) {
      // Touch the output so sanitizers see any inconsistency.
      const pb::Status valid = pb::Validate(result->points);
      if (!valid.ok()) __builtin_trap();
    }
  }
  ::close(fd);
  return 0;
}
