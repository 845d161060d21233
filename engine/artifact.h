// Artifacts as the cache stores them: a type, named files stored by content
// digest, and metadata. The artifact digest covers all three, so an output
// whose bytes and metadata did not change keeps its digest (early cutoff).
#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "base/hash.h"
#include "base/status.h"

namespace pb {

struct StoredFile {
  Digest digest;
  uint64_t size_bytes = 0;
};

struct Artifact {
  std::string type;
  std::map<std::string, StoredFile> files;  // file name -> content
  nlohmann::json meta = nlohmann::json::object();

  Digest ComputeDigest() const;
  uint64_t TotalBytes() const;
  nlohmann::json ToJson() const;
  static Expected<Artifact> FromJson(const nlohmann::json& j);
};

}  // namespace pb
