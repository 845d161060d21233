// Crash safety: `pointbake run` killed (SIGKILL, whole process group) at
// random moments, 50 times, must leave a cache that verifies and a next run
// that produces exactly what an uninterrupted run produces.
#include <signal.h>

#include <chrono>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "tests/cli_test_util.h"

namespace pbtest {
namespace {

constexpr const char* kWorkflow = R"(name: crashy
plugins: [$PLUGIN]
stages:
  s1: { uses: test.source, with: { text: "alpha-", repeat: 600, sleep_ms: 120 } }
  s2: { uses: test.source, with: { text: "beta--", repeat: 900, sleep_ms: 150 } }
  c1: { uses: test.concat, in: { a: s1.out, b: s2.out }, with: { sleep_ms: 150 } }
  l1: { uses: test.length, in: { in: c1.out }, with: { sleep_ms: 20 } }
  c2: { uses: test.concat, in: { a: c1.out, b: l1.out }, with: { suffix: "!", sleep_ms: 150 } }
  c3: { uses: test.concat, in: { a: c2.out, b: s2.out }, with: { sleep_ms: 100 } }
outputs: { c2: c2.out, c3: c3.out, l1: l1.out }
)";

const std::vector<std::string> kOutputs = {"c2.json", "c3.json", "l1.json"};

TEST(CrashSafety, RandomSigkillsLeaveAConsistentCache) {
  TempDir tmp;
  const std::string wf = WriteWorkflow(tmp / "proj/crashy.yaml", kWorkflow);
  const std::string cache = tmp / "cache";
  std::mt19937 rng(20240611);
  std::uniform_int_distribution<int> delay_ms(0, 900);
  const auto t0 = std::chrono::steady_clock::now();
  int finished_before_kill = 0;
  for (int i = 0; i < 50; ++i) {
    // Vary s1's text (25 values) so most iterations have work to interrupt;
    // the second pass over the values meets partial results. Alternate
    // --jobs 1 and 2.
    std::vector<std::string> args = {"run",   wf, "--cache", cache, "--out", tmp / "out",
                                     "--set", "s1.text=alpha-" + std::to_string(i % 25),
                                     "--jobs", i % 2 ? "2" : "1", "-q"};
    const pid_t pid = Spawn(args);
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(rng)));
    ::kill(-pid, SIGKILL);
    const int code = Wait(pid);
    if (code != 128 + SIGKILL) {
      EXPECT_EQ(code, 0) << "iteration " << i;
      ++finished_before_kill;
    }
  }
  const double loop_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("50 kills in %.1f s; %d runs finished before their kill\n", loop_s, finished_before_kill);
  EXPECT_GE(50 - finished_before_kill, 10) << "too few runs were interrupted to test anything";

  // The cache is consistent...
  const RunResult v1 = pbtest::Run({"cache", "--cache", cache, "verify"});
  EXPECT_EQ(v1.exit_code, 0) << v1.Describe();
  EXPECT_NE(v1.out.find(" 0 problems"), std::string::npos) << v1.out;

  // ...a run completes on it...
  const RunResult done = pbtest::Run({"run", wf, "--cache", cache, "--out", tmp / "out", "--jobs", "2"});
  ASSERT_EQ(done.exit_code, 0) << done.Describe();
  const RunResult variant =
      pbtest::Run({"run", wf, "--cache", cache, "--out", tmp / "out_v", "--set", "s1.text=alpha-5"});
  ASSERT_EQ(variant.exit_code, 0) << variant.Describe();
  const RunResult v2 = pbtest::Run({"cache", "--cache", cache, "verify"});
  EXPECT_EQ(v2.exit_code, 0) << v2.Describe();
  EXPECT_NE(v2.out.find(" 0 problems"), std::string::npos) << v2.out;

  // ...and gives what an uninterrupted run in a fresh cache gives.
  const RunResult ref = pbtest::Run({"run", wf, "--cache", tmp / "fresh_cache", "--out", tmp / "ref"});
  ASSERT_EQ(ref.exit_code, 0) << ref.Describe();
  const RunResult ref_v = pbtest::Run({"run", wf, "--cache", tmp / "fresh_cache", "--out", tmp / "ref_v",
                               "--set", "s1.text=alpha-5"});
  ASSERT_EQ(ref_v.exit_code, 0) << ref_v.Describe();
  for (const std::string& f : kOutputs) {
    const std::string expected = ReadFile(tmp / "ref/" + f);
    EXPECT_FALSE(expected.empty()) << f;
    EXPECT_EQ(ReadFile(tmp / "out/" + f), expected) << f;
    EXPECT_EQ(ReadFile(tmp / "out_v/" + f), ReadFile(tmp / "ref_v/" + f)) << f;
  }
  EXPECT_GT(ReadFile(tmp / "ref/c3.json").size(), 4000u);
  // No run.json left half-written either.
  EXPECT_TRUE(ReadJson(tmp / "out/run.json").is_object());
}

}  // namespace
}  // namespace pbtest
