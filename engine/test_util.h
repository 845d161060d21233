// Test helpers shared by the engine's unit tests: a temporary folder and a
// registry of tiny in-process stage types.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "engine/registry.h"

namespace pb::testing {

class TempDir {
 public:
  TempDir() {
    char tmpl[] = "/tmp/pbtest.XXXXXX";
    path_ = ::mkdtemp(tmpl);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  const std::string& path() const { return path_; }
  std::string Write(const std::string& name, const std::string& text) const {
    const std::string p = path_ + "/" + name;
    std::filesystem::create_directories(std::filesystem::path(p).parent_path());
    std::ofstream(p) << text;
    return p;
  }

 private:
  std::string path_;
};

// "t.text" writes params.text; "t.upper" upper-cases input `in`;
// "t.len" writes the length of input `in`; "t.pair" joins `a` and `b`;
// "t.file" reads params.path (x-path) and writes its content.
void RegisterTestStages(Registry& registry);

}  // namespace pb::testing
