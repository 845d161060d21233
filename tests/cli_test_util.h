// Helpers for end-to-end tests of the `pointbake` binary: temporary folders,
// running the binary as a child process, writing workflows, reading records.
#pragma once

#include <sys/types.h>

#include <nlohmann/json.hpp>
#include <string>

#include "base/testing/temp_dir.h"
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace pbtest {

using Json = nlohmann::json;
using EnvExtras = std::vector<std::pair<std::string, std::string>>;

// Absolute paths from compile definitions.
const char* Binary();        // PB_BINARY
const char* TestPlugin();    // PB_TEST_PLUGIN
const char* HelloPlugin();   // PB_HELLO_PLUGIN
std::string SourceDir();     // PB_SOURCE_DIR_STR

struct RunResult {
  int exit_code = -1;   // exit status, or 128 + signal
  bool signaled = false;
  std::string out;
  std::string err;
  // For failure messages: the command, exit code, stdout and stderr.
  std::string Describe() const;
  std::string command;
};

// The tests' one temporary folder (base/testing/temp_dir.h), with `dir / "rel"`.
class TempDir : public ::pb::testing::TempDir {
 public:
  std::string operator/(const std::string& rel) const { return path() + "/" + rel; }
};

// Runs `pointbake ARGS...` (PB_BINARY) with `cwd` as working directory (empty:
// inherit), extra environment variables, stdin from /dev/null; waits for it.
RunResult Run(const std::vector<std::string>& args, const EnvExtras& env = {},
              const std::string& cwd = "");

// Starts `pointbake ARGS...` in its own process group (pgid == pid), stdout
// and stderr to the given files (empty: /dev/null). Returns the pid.
pid_t Spawn(const std::vector<std::string>& args, const std::string& out_file = "",
            const std::string& err_file = "", const EnvExtras& env = {});
// Waits for `pid`; returns the exit code, or 128 + signal.
int Wait(pid_t pid);
// Waits at most `seconds`; on timeout kills the process group and returns -2.
int WaitWithTimeout(pid_t pid, double seconds);

// Files.
std::string ReadFile(const std::string& path);
void WriteFile(const std::string& path, const std::string& text);
bool Exists(const std::string& path);
Json ReadJson(const std::string& path);
std::vector<Json> ReadJsonLines(const std::string& path);
// Regular files below `dir` (recursive), as paths relative to `dir`, sorted.
std::vector<std::string> ListFiles(const std::string& dir);
void RemoveAll(const std::string& path);

// Writes a workflow file: every "$PLUGIN" in `yaml` becomes the quoted
// absolute path of the test stages plugin, "$HELLO" that of the example
// plugin. Creates parent folders. Returns `path`.
std::string WriteWorkflow(const std::string& path, const std::string& yaml);

// Number of entry files (entries/*/*.json) in a cache folder.
int CountEntries(const std::string& cache_dir);

// run.json helpers: stage id -> its record.
Json StageRecord(const Json& run_json, const std::string& stage);
std::string StageStatus(const Json& run_json, const std::string& stage);
// "a=ran b=hit ..." in the record's order, for messages.
std::string Statuses(const Json& run_json);

// A test fixture owning a temporary folder.
class CliTest : public ::testing::Test {
 protected:
  std::string P(const std::string& rel) const { return tmp_ / rel; }
  TempDir tmp_;
};

}  // namespace pbtest
