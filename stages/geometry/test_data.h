// For tests only: where the shared sample scans are.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>

namespace pb::testing {

// `$PB_SOURCE_DIR/../shared/data` (set by ctest), else /work/shared/data;
// empty when neither exists, so a test can GTEST_SKIP.
inline std::string SharedDataDir() {
  if (const char* source = std::getenv("PB_SOURCE_DIR")) {
    const auto candidate = std::filesystem::path(source) / ".." / "shared" / "data";
    if (std::filesystem::exists(candidate)) return candidate.lexically_normal().string();
  }
  if (std::filesystem::exists("/work/shared/data")) return "/work/shared/data";
  return "";
}

}  // namespace pb::testing
