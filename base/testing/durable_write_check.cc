#include "base/testing/durable_write_check.h"

#include <gtest/gtest.h>

#include <map>

#include "base/testing/fault_injecting_env.h"

namespace pb::testing {
namespace {

// name -> bytes of every file directly in `dir`.
std::map<std::string, std::string> Snapshot(const std::string& dir) {
  std::map<std::string, std::string> files;
  auto names = Env::Default()->ListDir(dir);
  EXPECT_TRUE(names.ok()) << names.status().message();
  if (!names.ok()) return files;
  for (const std::string& name : *names) {
    auto bytes = Env::Default()->ReadFile(JoinPath(dir, name));
    EXPECT_TRUE(bytes.ok()) << bytes.status().message();
    if (bytes.ok()) files[name] = *std::move(bytes);
  }
  return files;
}

bool IsTemporary(const std::string& name) { return name.find(".tmp.") != std::string::npos; }

}  // namespace

int ExpectFailedWritesKeepEarlierFiles(const std::string& dir,
                                       const std::function<Status(Env*)>& write) {
  const std::map<std::string, std::string> earlier = Snapshot(dir);
  EXPECT_FALSE(earlier.empty()) << dir << " holds no earlier result to protect";
  constexpr int kMaxWrites = 64;
  for (int fail_at = 1; fail_at <= kMaxWrites; ++fail_at) {
    FaultInjectingEnv env(fail_at);
    const Status status = write(&env);
    if (env.writes_seen() < fail_at) {  // nothing failed: the writer is done
      EXPECT_TRUE(status.ok()) << status.message();
      EXPECT_GT(fail_at - 1, 0) << "the writer made no durable write through the Env";
      EXPECT_NE(Snapshot(dir), earlier) << "a successful write changed no file";
      return fail_at - 1;
    }
    EXPECT_FALSE(status.ok()) << "write " << fail_at << " failed but the writer reported success";
    const std::map<std::string, std::string> after = Snapshot(dir);
    for (const auto& [name, bytes] : earlier) {
      auto it = after.find(name);
      EXPECT_TRUE(it != after.end() && it->second == bytes)
          << "write " << fail_at << " failed and " << name << " lost its earlier content";
    }
    for (const auto& [name, bytes] : after) {
      EXPECT_TRUE(earlier.count(name) > 0 || IsTemporary(name))
          << "write " << fail_at << " failed and left " << name << ", which looks complete";
      if (IsTemporary(name)) (void)Env::Default()->RemoveAll(JoinPath(dir, name));
    }
  }
  ADD_FAILURE() << "the writer made more than " << kMaxWrites << " durable writes";
  return kMaxWrites;
}

}  // namespace pb::testing
