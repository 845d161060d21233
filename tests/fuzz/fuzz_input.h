// The fuzzer's bytes as a file a reader can open: the scan readers take a
// path, so the input is written to a memfd (memory only, nothing left on
// disk) and named as /proc/self/fd/N. Linux only, like the fuzz build.
#pragma once

#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <string>

namespace pb::fuzz {

class FuzzInput {
 public:
  // `name` labels the memfd (seen in /proc/self/fd); it need not be unique.
  FuzzInput(const char* name, const uint8_t* data, size_t size)
      : fd_(::memfd_create(name, MFD_CLOEXEC)) {
    if (fd_ < 0) return;
    size_t written = 0;
    while (written < size) {
      const ssize_t n = ::write(fd_, data + written, size - written);
      if (n <= 0) break;
      written += static_cast<size_t>(n);
    }
    if (written == size) path_ = "/proc/self/fd/" + std::to_string(fd_);
  }
  ~FuzzInput() {
    if (fd_ >= 0) ::close(fd_);
  }
  FuzzInput(const FuzzInput&) = delete;
  FuzzInput& operator=(const FuzzInput&) = delete;

  // False when the memfd could not be made or filled; skip the input then.
  bool ok() const { return !path_.empty(); }
  const std::string& path() const { return path_; }

 private:
  int fd_;
  std::string path_;
};

}  // namespace pb::fuzz
