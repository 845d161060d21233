#include "base/hash.h"

#include <fcntl.h>
#include <unistd.h>
#include <xxhash.h>

#include <cerrno>
#include <cstdio>
#include <vector>

namespace pb {

std::string Digest::Hex() const {
  char buf[33];
  std::snprintf(buf, sizeof buf, "%016llx%016llx", static_cast<unsigned long long>(high),
                static_cast<unsigned long long>(low));
  return buf;
}

Expected<Digest> Digest::FromHex(std::string_view hex) {
  if (hex.size() != 32) return Status::Invalid("digest '" + std::string(hex) + "' is not 32 hex digits");
  Digest d;
  for (size_t i = 0; i < 32; ++i) {
    const char c = hex[i];
    int v;
    if (c >= '0' && c <= '9') v = c - '0';
    else if (c >= 'a' && c <= 'f') v = c - 'a' + 10;
    else return Status::Invalid("digest '" + std::string(hex) + "' has a non-hex character");
    uint64_t& word = i < 16 ? d.high : d.low;
    word = (word << 4) | static_cast<uint64_t>(v);
  }
  return d;
}

Digest HashBytes(std::string_view bytes) {
  XXH128_hash_t h = XXH3_128bits(bytes.data(), bytes.size());
  return Digest{h.high64, h.low64};
}

Expected<Digest> HashFile(const std::string& path, uint64_t* size_bytes) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status::Errno(path, "open");
  ::posix_fadvise(fd, 0, 0, POSIX_FADV_SEQUENTIAL);
  XXH3_state_t* state = XXH3_createState();
  XXH3_128bits_reset(state);
  std::vector<char> buf(1 << 20);
  uint64_t total = 0;
  for (;;) {
    ssize_t n = ::read(fd, buf.data(), buf.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      Status st = Status::Errno(path, "read");
      XXH3_freeState(state);
      ::close(fd);
      return st;
    }
    if (n == 0) break;
    XXH3_128bits_update(state, buf.data(), static_cast<size_t>(n));
    total += static_cast<uint64_t>(n);
  }
  ::close(fd);
  XXH128_hash_t h = XXH3_128bits_digest(state);
  XXH3_freeState(state);
  if (size_bytes) *size_bytes = total;
  return Digest{h.high64, h.low64};
}

Hasher::Hasher() : state_(XXH3_createState()) {
  XXH3_128bits_reset(static_cast<XXH3_state_t*>(state_));
}

Hasher::~Hasher() { XXH3_freeState(static_cast<XXH3_state_t*>(state_)); }

Hasher& Hasher::Add(std::string_view field) {
  auto* s = static_cast<XXH3_state_t*>(state_);
  const uint64_t len = field.size();
  XXH3_128bits_update(s, &len, sizeof len);
  XXH3_128bits_update(s, field.data(), field.size());
  return *this;
}

Digest Hasher::Finish() {
  XXH128_hash_t h = XXH3_128bits_digest(static_cast<XXH3_state_t*>(state_));
  return Digest{h.high64, h.low64};
}

}  // namespace pb
