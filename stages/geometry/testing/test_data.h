// For tests only: where the shared sample scans are, and a fixture with a
// private temporary folder.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "base/testing/temp_dir.h"

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

// A test with its own empty folder `dir_`, removed afterwards.
class TempDirTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = temp_.path(); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  // Writes `bytes` to dir_/name and returns the path.
  std::string Write(const std::string& name, const std::string& bytes) const {
    std::ofstream(Path(name), std::ios::binary) << bytes;
    return Path(name);
  }

  ::pb::testing::TempDir temp_;
  std::filesystem::path dir_;
};

}  // namespace pb::testing
