// Content digests: XXH3-128, printed as 32 lowercase hex digits.
//
// Used for cache keys, artifact digests and input-file digests. XXH3-128 is
// not cryptographic; the cache trusts its own directory, not adversaries.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "base/status.h"

namespace pb {

struct Digest {
  uint64_t high = 0;
  uint64_t low = 0;
  std::string Hex() const;
  static Expected<Digest> FromHex(std::string_view hex);
  bool operator==(const Digest&) const = default;
};

Digest HashBytes(std::string_view bytes);

// Streams a file through XXH3-128 (1 MiB reads). Reports the byte count.
Expected<Digest> HashFile(const std::string& path, uint64_t* size_bytes = nullptr);

// Incremental hashing of several fields; each field is length-prefixed so
// ("ab","c") and ("a","bc") differ.
class Hasher {
 public:
  Hasher();
  ~Hasher();
  Hasher(const Hasher&) = delete;
  Hasher& operator=(const Hasher&) = delete;
  Hasher& Add(std::string_view field);
  Digest Finish();

 private:
  void* state_;
};

}  // namespace pb
