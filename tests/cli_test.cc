// End-to-end tests of the `pointbake` binary: real child processes, real
// cache folders under /tmp.
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/cli_test_util.h"

namespace pbtest {
namespace {

namespace fs = std::filesystem;

constexpr const char* kChain = R"(name: chain
plugins: [$PLUGIN]
stages:
  src:
    uses: test.source
    with: { text: hello }
  up:
    uses: test.concat
    in: { a: src.out }
    with: { suffix: " world" }
  len:
    uses: test.length
    in: { in: up.out }
  other:
    uses: test.source
    with: { text: other }
outputs:
  greeting: up.out
  length: len.out
  other: other.out
)";

std::string TextOf(const std::string& table_file) {
  const Json j = ReadJson(table_file);
  return j.is_object() ? j.value("text", "<no text>") : "<not json: " + ReadFile(table_file) + ">";
}

class Cli : public CliTest {
 protected:
  // `pointbake run WF --cache <tmp>/cache --out <tmp>/OUT EXTRA...`
  RunResult RunWf(const std::string& wf, const std::string& out = "out",
                  std::vector<std::string> extra = {}, const std::string& cache = "cache") {
    std::vector<std::string> args = {"run", wf, "--cache", P(cache), "--out", P(out)};
    args.insert(args.end(), extra.begin(), extra.end());
    return pbtest::Run(args);
  }
  Json RunJson(const std::string& out = "out") { return ReadJson(P(out) + "/run.json"); }
};

// 1. A chain runs; outputs copied; run.json, trace.json, run.jsonl written.
TEST_F(Cli, ChainRunsAndWritesRecords) {
  const std::string wf = WriteWorkflow(P("proj/chain.yaml"), kChain);
  const RunResult r = RunWf(wf);
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  EXPECT_EQ(TextOf(P("out/greeting.json")), "hello world");
  EXPECT_EQ(TextOf(P("out/length.json")), "11");
  EXPECT_EQ(TextOf(P("out/other.json")), "other");

  const Json run = RunJson();
  ASSERT_TRUE(run.is_object()) << ReadFile(P("out/run.json"));
  EXPECT_EQ(run.value("format", ""), "pointbake-run 1");
  EXPECT_EQ(run.value("workflow", ""), "chain");
  ASSERT_EQ(run["stages"].size(), 4u);
  for (const Json& s : run["stages"]) {
    SCOPED_TRACE(s.dump());
    EXPECT_EQ(s.value("status", ""), "ran");
    ASSERT_TRUE(s.contains("peak_rss_bytes"));
    EXPECT_GT(s["peak_rss_bytes"].get<double>(), 0);
    ASSERT_TRUE(s.contains("user_s"));
    EXPECT_GE(s["user_s"].get<double>(), 0);
    EXPECT_TRUE(s.contains("phases"));
    EXPECT_TRUE(s.contains("counters"));
    EXPECT_FALSE(s.value("key", "").empty());
  }
  // test.source reports a counter and a phase.
  const Json src = StageRecord(run, "src");
  EXPECT_EQ(src["counters"].value("chars", -1.0), 5.0) << src.dump();
  bool has_compute = false;
  for (const Json& ph : src["phases"]) has_compute |= ph.value("name", "") == "compute";
  EXPECT_TRUE(has_compute) << src["phases"].dump();

  const Json trace = ReadJson(P("out/trace.json"));
  ASSERT_TRUE(trace.is_object() && trace.contains("traceEvents")) << ReadFile(P("out/trace.json"));
  int x_events = 0;
  for (const Json& e : trace["traceEvents"]) x_events += e.value("ph", "") == "X";
  EXPECT_GE(x_events, 4);

  const std::vector<Json> lines = ReadJsonLines(P("out/run.jsonl"));
  ASSERT_EQ(lines.size(), 4u);
  for (const Json& l : lines) EXPECT_TRUE(l.is_object() && l.contains("stage")) << l.dump();
  EXPECT_NE(r.out.find("4 ran"), std::string::npos) << r.out;
}

// 2. A second run hits everything and writes identical outputs.
TEST_F(Cli, RerunHitsEverything) {
  const std::string wf = WriteWorkflow(P("proj/chain.yaml"), kChain);
  ASSERT_EQ(RunWf(wf, "out1").exit_code, 0);
  const RunResult r = RunWf(wf, "out2");
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  const Json run = RunJson("out2");
  for (const Json& s : run["stages"]) {
    EXPECT_EQ(s.value("status", ""), "hit") << s.dump();
    EXPECT_TRUE(s.contains("cached_run")) << s.dump();
  }
  for (const char* f : {"greeting.json", "length.json", "other.json"})
    EXPECT_EQ(ReadFile(P("out1/") + f), ReadFile(P("out2/") + f)) << f;
  EXPECT_NE(r.out.find("0 ran, 4 cached"), std::string::npos) << r.out;
}

// 3. --set re-runs exactly the changed stage and its dependents; explain says why.
TEST_F(Cli, SetParameterRerunsStageAndDependents) {
  const std::string wf = WriteWorkflow(P("proj/chain.yaml"), kChain);
  ASSERT_EQ(RunWf(wf).exit_code, 0);

  const RunResult ex = pbtest::Run({"explain", wf, "--cache", P("cache"), "--set", "src.text=bye"});
  ASSERT_EQ(ex.exit_code, 0) << ex.Describe();
  EXPECT_NE(ex.out.find("parameter 'text' changed: "), std::string::npos) << ex.out;
  const size_t at = ex.out.find("parameter 'text' changed");
  const std::string line = at == std::string::npos ? "" : ex.out.substr(at, ex.out.find('\n', at) - at);
  EXPECT_NE(line.find("hello"), std::string::npos) << line;
  EXPECT_NE(line.find("bye"), std::string::npos) << line;
  EXPECT_LT(line.find("hello"), line.find("bye")) << "old value first: " << line;

  const RunResult r = RunWf(wf, "out", {"--set", "src.text=bye"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  const Json run = RunJson();
  EXPECT_EQ(StageStatus(run, "src"), "ran") << Statuses(run);
  EXPECT_EQ(StageStatus(run, "up"), "ran") << Statuses(run);
  EXPECT_EQ(StageStatus(run, "len"), "ran") << Statuses(run);  // 9 != 11
  EXPECT_EQ(StageStatus(run, "other"), "hit") << Statuses(run);
  EXPECT_EQ(TextOf(P("out/greeting.json")), "bye world");
  EXPECT_EQ(TextOf(P("out/length.json")), "9");
}

// 4. Early cutoff: an upstream change that leaves an output's bytes equal
// stops the re-runs there.
TEST_F(Cli, EarlyCutoff) {
  const std::string body = R"(name: cutoff
plugins: [$PLUGIN]
stages:
  src: { uses: test.source, with: { text: TEXT } }
  len: { uses: test.length, in: { in: src.out } }
  tail: { uses: test.concat, in: { a: len.out }, with: { suffix: "!" } }
outputs: { tail: tail.out }
)";
  auto with_text = [&](const std::string& t) {
    std::string s = body;
    s.replace(s.find("TEXT"), 4, t);
    return s;
  };
  const std::string wf = WriteWorkflow(P("proj/cutoff.yaml"), with_text("abc"));
  ASSERT_EQ(RunWf(wf).exit_code, 0);
  EXPECT_EQ(TextOf(P("out/tail.json")), "3!");
  WriteWorkflow(wf, with_text("xyz"));
  const RunResult r = RunWf(wf);
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  const Json run = RunJson();
  EXPECT_EQ(StageStatus(run, "src"), "ran") << Statuses(run);
  EXPECT_EQ(StageStatus(run, "len"), "ran") << Statuses(run);
  EXPECT_EQ(StageStatus(run, "tail"), "hit") << Statuses(run);
  EXPECT_EQ(TextOf(P("out/tail.json")), "3!");
}

// 5. Moving the cache and the project keeps every hit.
TEST_F(Cli, RelocatableCache) {
  const std::string wf = WriteWorkflow(P("proj/chain.yaml"), kChain);
  ASSERT_EQ(RunWf(wf, "out1", {}, "cache").exit_code, 0);
  fs::rename(P("proj"), P("moved_proj"));
  fs::rename(P("cache"), P("moved_cache"));
  const RunResult r = RunWf(P("moved_proj/chain.yaml"), "out2", {}, "moved_cache");
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  const Json run = RunJson("out2");
  for (const Json& s : run["stages"]) EXPECT_EQ(s.value("status", ""), "hit") << Statuses(run);
  EXPECT_EQ(ReadFile(P("out1/greeting.json")), ReadFile(P("out2/greeting.json")));
  EXPECT_FALSE(Exists(P("cache")));
}

// 6. Memory figures are the stage child's peak RSS.
TEST_F(Cli, PeakRssOfAllocStage) {
  const std::string wf = WriteWorkflow(P("proj/alloc.yaml"), R"(name: alloc
plugins: [$PLUGIN]
stages:
  big: { uses: test.alloc, with: { mib: 512 } }
)");
  const RunResult r = RunWf(wf);
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  const Json big = StageRecord(RunJson(), "big");
  ASSERT_TRUE(big.contains("peak_rss_bytes")) << big.dump();
  const double rss = big["peak_rss_bytes"].get<double>();
  const double mib512 = 512.0 * 1024 * 1024;
  EXPECT_EQ(big["counters"].value("bytes", 0.0), mib512);
  EXPECT_GE(rss, 0.9 * mib512) << "peak_rss_bytes=" << rss;
#if defined(__SANITIZE_ADDRESS__)
  // ASan's shadow memory and quarantine add ~35% here: the upper bound only
  // holds for a plain build.
  GTEST_SKIP() << "upper bound not checked under AddressSanitizer; peak_rss_bytes=" << rss;
#endif
  EXPECT_LE(rss, 1.1 * mib512) << "peak_rss_bytes=" << rss;
}

constexpr const char* kFailing = R"(name: failing
plugins: [$PLUGIN]
stages:
  bad: { uses: test.fail, with: { message: "planned boom 42" } }
  after: { uses: test.concat, in: { a: bad.out } }
  sib: { uses: test.source, with: { text: sibling, sleep_ms: 100 } }
)";

// 7. Failures: exit 1; --keep-going runs independent stages, skips
// dependents; errors reach stderr and run.json; nothing is cached for them.
TEST_F(Cli, FailureHandling) {
  const std::string wf = WriteWorkflow(P("proj/failing.yaml"), kFailing);
  const RunResult stop = RunWf(wf, "out_stop", {}, "cache_stop");
  EXPECT_EQ(stop.exit_code, 1) << stop.Describe();
  EXPECT_EQ(StageStatus(RunJson("out_stop"), "bad"), "failed") << Statuses(RunJson("out_stop"));
  EXPECT_EQ(StageStatus(RunJson("out_stop"), "after"), "skipped");

  const RunResult r = RunWf(wf, "out", {"--keep-going"});
  EXPECT_EQ(r.exit_code, 1) << r.Describe();
  const Json run = RunJson();
  EXPECT_EQ(StageStatus(run, "bad"), "failed") << Statuses(run);
  EXPECT_EQ(StageStatus(run, "sib"), "ran") << Statuses(run);
  EXPECT_EQ(StageStatus(run, "after"), "skipped") << Statuses(run);
  EXPECT_NE(r.err.find("planned boom 42"), std::string::npos) << r.Describe();
  EXPECT_NE(StageRecord(run, "bad").value("error", "").find("planned boom 42"), std::string::npos)
      << StageRecord(run, "bad").dump();
  EXPECT_EQ(TextOf(P("out/sib.out.json")), "sibling");  // default outputs: sinks
  EXPECT_EQ(CountEntries(P("cache")), 1) << "only sib is cached";

  const RunResult again = RunWf(wf, "out", {"--keep-going"});
  EXPECT_EQ(again.exit_code, 1) << again.Describe();
  const Json run2 = RunJson();
  EXPECT_EQ(StageStatus(run2, "bad"), "failed") << Statuses(run2);
  EXPECT_EQ(StageStatus(run2, "sib"), "hit") << Statuses(run2);
  EXPECT_EQ(CountEntries(P("cache")), 1);
}

TEST_F(Cli, CrashingStageReportsSignal) {
  const std::string wf = WriteWorkflow(P("proj/crash.yaml"), R"(name: crash
plugins: [$PLUGIN]
stages:
  boom: { uses: test.fail, with: { crash: true } }
)");
  const RunResult r = RunWf(wf);
  EXPECT_EQ(r.exit_code, 1) << r.Describe();
  const Json boom = StageRecord(RunJson(), "boom");
  EXPECT_EQ(boom.value("status", ""), "failed") << boom.dump();
  EXPECT_NE(boom.value("error", "").find("signal"), std::string::npos) << boom.dump();
  EXPECT_EQ(CountEntries(P("cache")), 0);
}

// 8. --jobs 2 runs independent stages at the same time.
TEST_F(Cli, JobsRunInParallel) {
  const std::string wf = WriteWorkflow(P("proj/par.yaml"), R"(name: par
plugins: [$PLUGIN]
stages:
  a: { uses: test.source, with: { text: a, sleep_ms: 600 } }
  b: { uses: test.source, with: { text: b, sleep_ms: 600 } }
)");
  const RunResult r = RunWf(wf, "out", {"--jobs", "2"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  const Json run = RunJson();
  EXPECT_EQ(StageStatus(run, "a"), "ran");
  EXPECT_EQ(StageStatus(run, "b"), "ran");
  const Json trace = ReadJson(P("out/trace.json"));
  Json ea, eb;
  for (const Json& e : trace["traceEvents"]) {
    if (e.value("ph", "") != "X" || e.value("cat", "").rfind("stage", 0) != 0) continue;
    if (e.value("name", "") == "a") ea = e;
    if (e.value("name", "") == "b") eb = e;
  }
  ASSERT_TRUE(ea.is_object() && eb.is_object()) << trace.dump(1);
  const double a0 = ea["ts"].get<double>(), a1 = a0 + ea["dur"].get<double>();
  const double b0 = eb["ts"].get<double>(), b1 = b0 + eb["dur"].get<double>();
  EXPECT_LT(a0, b1) << trace.dump(1);
  EXPECT_LT(b0, a1) << trace.dump(1);
  EXPECT_NE(ea["tid"], eb["tid"]) << "parallel stages share a trace lane";
}

// 9. --dry-run runs nothing.
TEST_F(Cli, DryRunExecutesNothing) {
  const std::string wf = WriteWorkflow(P("proj/chain.yaml"), kChain);
  const RunResult r = RunWf(wf, "out", {"--dry-run"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  EXPECT_NE(r.out.find("run   src"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("run   other"), std::string::npos) << r.out;
  EXPECT_EQ(CountEntries(P("cache")), 0);
  const RunResult ls = pbtest::Run({"cache", "--cache", P("cache"), "ls"});
  ASSERT_EQ(ls.exit_code, 0) << ls.Describe();
  EXPECT_NE(ls.out.find("0 entries"), std::string::npos) << ls.out;
  // The README's form: --cache after the sub-command.
  const RunResult ls_after = pbtest::Run({"cache", "ls", "--cache", P("cache")});
  ASSERT_EQ(ls_after.exit_code, 0) << ls_after.Describe();
  EXPECT_NE(ls_after.out.find("0 entries"), std::string::npos) << ls_after.out;
  EXPECT_FALSE(Exists(P("out/run.json")));
}

// 10. graph and stages.
TEST_F(Cli, GraphAndStages) {
  const std::string wf = WriteWorkflow(P("proj/chain.yaml"), kChain);
  const RunResult g = pbtest::Run({"graph", wf});
  ASSERT_EQ(g.exit_code, 0) << g.Describe();
  EXPECT_NE(g.out.find("digraph"), std::string::npos) << g.out;
  EXPECT_NE(g.out.find("\"src\" -> \"up\""), std::string::npos) << g.out;
  EXPECT_NE(g.out.find("\"up\" -> \"len\""), std::string::npos) << g.out;

  const RunResult all = pbtest::Run({"stages"});
  ASSERT_EQ(all.exit_code, 0) << all.Describe();
  EXPECT_NE(all.out.find("io.read_points"), std::string::npos) << all.out;
  EXPECT_EQ(all.out.find("test.source"), std::string::npos) << "plugin stage listed without plugin";

  const RunResult plugin_stage = pbtest::Run({"stages", "test.source"});
  EXPECT_EQ(plugin_stage.exit_code, 2) << plugin_stage.Describe();
  EXPECT_NE(plugin_stage.err.find("unknown stage type 'test.source'"), std::string::npos)
      << plugin_stage.Describe();

  const RunResult ds = pbtest::Run({"stages", "points.downsample"});
  ASSERT_EQ(ds.exit_code, 0) << ds.Describe();
  EXPECT_NE(ds.out.find("voxel"), std::string::npos) << ds.out;
}

// 11. cache verify / --repair / gc.
TEST_F(Cli, CacheVerifyRepairAndGc) {
  const std::string wf = WriteWorkflow(P("proj/chain.yaml"), kChain);
  ASSERT_EQ(RunWf(wf).exit_code, 0);
  const RunResult ok = pbtest::Run({"cache", "--cache", P("cache"), "verify"});
  EXPECT_EQ(ok.exit_code, 0) << ok.Describe();
  EXPECT_NE(ok.out.find(" 0 problems"), std::string::npos) << ok.out;

  // The object holding up's output has the bytes of out/greeting.json.
  const std::string greeting = ReadFile(P("out/greeting.json"));
  std::string victim;
  for (const std::string& f : ListFiles(P("cache/objects")))
    if (ReadFile(P("cache/objects/") + f) == greeting) victim = P("cache/objects/") + f;
  ASSERT_FALSE(victim.empty()) << "no object with the greeting's bytes";
  fs::permissions(victim, fs::perms::owner_write, fs::perm_options::add);
  std::string corrupt(greeting.size(), 'X');
  WriteFile(victim, corrupt);  // same size, other bytes

  const RunResult bad = pbtest::Run({"cache", "--cache", P("cache"), "verify"});
  EXPECT_EQ(bad.exit_code, 1) << bad.Describe();
  const std::string victim_name = fs::path(victim).filename().string();
  EXPECT_NE(bad.out.find(victim_name), std::string::npos) << bad.out;
  // The object, and the entry that names it.
  EXPECT_EQ(bad.out.find(" 0 problems"), std::string::npos) << bad.out;
  EXPECT_NE(bad.out.find("corrupt object"), std::string::npos) << bad.out;

  const RunResult repair = pbtest::Run({"cache", "--cache", P("cache"), "verify", "--repair"});
  EXPECT_EQ(repair.exit_code, 0) << repair.Describe();
  EXPECT_FALSE(Exists(victim));
  const RunResult after = pbtest::Run({"cache", "--cache", P("cache"), "verify"});
  EXPECT_EQ(after.exit_code, 0) << after.Describe();
  EXPECT_NE(after.out.find(" 0 problems"), std::string::npos) << after.out;

  const RunResult rerun = RunWf(wf);
  ASSERT_EQ(rerun.exit_code, 0) << rerun.Describe();
  Json run = RunJson();
  EXPECT_EQ(StageStatus(run, "up"), "ran") << Statuses(run);
  EXPECT_EQ(StageStatus(run, "src"), "hit") << Statuses(run);
  EXPECT_EQ(StageStatus(run, "other"), "hit") << Statuses(run);
  EXPECT_EQ(TextOf(P("out/greeting.json")), "hello world");

  const RunResult gc = pbtest::Run({"cache", "--cache", P("cache"), "gc", "--max-size", "0"});
  ASSERT_EQ(gc.exit_code, 0) << gc.Describe();
  EXPECT_EQ(CountEntries(P("cache")), 0) << gc.out;
  EXPECT_TRUE(ListFiles(P("cache/objects")).empty()) << gc.out;
  const RunResult fresh = RunWf(wf);
  ASSERT_EQ(fresh.exit_code, 0) << fresh.Describe();
  run = RunJson();
  for (const Json& s : run["stages"]) EXPECT_EQ(s.value("status", ""), "ran") << Statuses(run);
}

// 12. Two runs at once on one cache.
TEST_F(Cli, ConcurrentRunsShareCache) {
  const std::string wf = WriteWorkflow(P("proj/conc.yaml"), R"(name: conc
plugins: [$PLUGIN]
stages:
  s1: { uses: test.source, with: { text: "abc", repeat: 2000, sleep_ms: 200 } }
  s2: { uses: test.source, with: { text: "de", repeat: 1000, sleep_ms: 100 } }
  cat: { uses: test.concat, in: { a: s1.out, b: s2.out }, with: { sleep_ms: 200 } }
  len: { uses: test.length, in: { in: cat.out }, with: { sleep_ms: 100 } }
outputs: { cat: cat.out, len: len.out }
)");
  const auto args = [&](const std::string& out) {
    return std::vector<std::string>{"run", wf, "--cache", P("cache"), "--out", P(out), "--jobs", "2"};
  };
  const pid_t a = Spawn(args("outA"), P("a.stdout"), P("a.stderr"));
  const pid_t b = Spawn(args("outB"), P("b.stdout"), P("b.stderr"));
  const int ca = WaitWithTimeout(a, 60), cb = WaitWithTimeout(b, 60);
  EXPECT_EQ(ca, 0) << ReadFile(P("a.stderr"));
  EXPECT_EQ(cb, 0) << ReadFile(P("b.stderr"));
  for (const char* f : {"cat.json", "len.json"}) {
    EXPECT_TRUE(Exists(P("outA/") + f)) << f;
    EXPECT_EQ(ReadFile(P("outA/") + f), ReadFile(P("outB/") + f)) << f;
  }
  EXPECT_EQ(TextOf(P("outA/len.json")), "8000");
  const RunResult v = pbtest::Run({"cache", "--cache", P("cache"), "verify"});
  EXPECT_EQ(v.exit_code, 0) << v.Describe();
  EXPECT_NE(v.out.find(" 0 problems"), std::string::npos) << v.out;
  EXPECT_EQ(CountEntries(P("cache")), 4);
}

// 13. The example plugin, and a missing plugin.
TEST_F(Cli, HelloPluginAndMissingPlugin) {
  const std::string wf = WriteWorkflow(P("proj/hello.yaml"), R"(name: hello
plugins: [$HELLO]
stages:
  greet: { uses: hello.greet, with: { name: "tests", times: 2 } }
outputs: { greeting: greet.greeting }
)");
  const RunResult r = RunWf(wf);
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  const Json g = ReadJson(P("out/greeting.json"));
  EXPECT_EQ(g.value("greeting", ""), "Hello, tests!") << g.dump();
  EXPECT_EQ(g.value("times", 0), 2) << g.dump();
  EXPECT_EQ(StageRecord(RunJson(), "greet")["counters"].value("greetings", 0.0), 2.0);

  const std::string missing = WriteWorkflow(P("proj/missing.yaml"), R"(name: missing
plugins:
  - plugins/libnot_there.so
stages:
  greet: { uses: hello.greet, with: { name: "x" } }
)");
  for (const char* cmd : {"validate", "run"}) {
    std::vector<std::string> args = {cmd, missing};
    if (std::string(cmd) == "run") args.insert(args.end(), {"--cache", P("cache2")});
    const RunResult m = pbtest::Run(args);
    EXPECT_EQ(m.exit_code, 2) << m.Describe();
    EXPECT_NE(m.err.find(missing + ":3:5:"), std::string::npos) << m.Describe();
    EXPECT_NE(m.err.find("libnot_there.so"), std::string::npos) << m.Describe();
  }
  EXPECT_EQ(CountEntries(P("cache2")), 0);
}

// 14. A memory budget smaller than any stage still completes, one at a time.
TEST_F(Cli, TinyMemoryBudgetDoesNotDeadlock) {
  const std::string body = R"(name: mem
plugins: [$PLUGIN]
stages:
  a: { uses: test.alloc, with: { mib: MIBA } }
  b: { uses: test.alloc, with: { mib: MIBB } }
  c: { uses: test.source, with: { text: c, sleep_ms: 100 } }
  d: { uses: test.concat, in: { a: a.out, b: c.out } }
)";
  auto with_mib = [&](int mib) {
    std::string s = body;
    s.replace(s.find("MIBA"), 4, std::to_string(mib));
    s.replace(s.find("MIBB"), 4, std::to_string(mib + 8));
    return s;
  };
  const std::string wf = WriteWorkflow(P("proj/mem.yaml"), with_mib(16));
  // First run: peaks are unknown (no history, nothing declared), so the
  // budget cannot hold anything back; it must still complete.
  for (int round = 0; round < 2; ++round) {
    SCOPED_TRACE(round);
    if (round == 1) WriteWorkflow(wf, with_mib(17));  // every stage re-runs, peaks now known
    const std::string out = "out" + std::to_string(round);
    const pid_t pid = Spawn({"run", wf, "--cache", P("cache"), "--out", P(out), "--mem", "1M", "--jobs", "2"},
                            P("stdout"), P("stderr"));
    const int code = WaitWithTimeout(pid, 60);
    ASSERT_EQ(code, 0) << (code == -2 ? "timed out (deadlock?)\n" : "") << ReadFile(P("stderr"));
    const Json run = RunJson(out);
    EXPECT_EQ(StageStatus(run, "a"), "ran") << Statuses(run);
    EXPECT_EQ(StageStatus(run, "b"), "ran") << Statuses(run);
    EXPECT_EQ(StageStatus(run, "d"), "ran") << Statuses(run);
    if (round == 0) continue;
    // Held back stages run one at a time: no two stage boxes overlap.
    std::vector<std::pair<double, double>> boxes;
    const Json trace = ReadJson(P(out) + "/trace.json");
    for (const Json& e : trace["traceEvents"])
      if (e.value("ph", "") == "X" && e.value("cat", "").rfind("stage,ran", 0) == 0)
        boxes.push_back({e["ts"].get<double>(), e["ts"].get<double>() + e["dur"].get<double>()});
    EXPECT_EQ(boxes.size(), 3u) << Statuses(run);  // a, b and d re-run; c hits (unchanged)
    for (size_t i = 0; i < boxes.size(); ++i)
      for (size_t j = i + 1; j < boxes.size(); ++j)
        EXPECT_TRUE(boxes[i].second <= boxes[j].first || boxes[j].second <= boxes[i].first)
            << "stages " << i << " and " << j << " overlap under a 1M budget\n" << trace.dump(1);
  }
}

// 15. Input files are keyed by content: touch keeps hits, edits re-run.
TEST_F(Cli, InputFileDigests) {
  const std::string ply_header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "end_header\n";
  WriteFile(P("proj/data/scan.ply"), ply_header + "0 0 0\n1 0 0\n0 1 0\n");
  const std::string wf = WriteWorkflow(P("proj/read.yaml"), R"(name: read
stages:
  scan: { uses: io.read_points, with: { path: data/scan.ply } }
)");
  const RunResult r1 = RunWf(wf);
  ASSERT_EQ(r1.exit_code, 0) << r1.Describe();
  EXPECT_EQ(StageStatus(RunJson(), "scan"), "ran");

  const RunResult r2 = RunWf(wf);
  ASSERT_EQ(r2.exit_code, 0) << r2.Describe();
  EXPECT_EQ(StageStatus(RunJson(), "scan"), "hit");

  // Same bytes, new mtime.
  const auto t = fs::last_write_time(P("proj/data/scan.ply"));
  fs::last_write_time(P("proj/data/scan.ply"), t + std::chrono::seconds(10));
  const RunResult r3 = RunWf(wf);
  ASSERT_EQ(r3.exit_code, 0) << r3.Describe();
  EXPECT_EQ(StageStatus(RunJson(), "scan"), "hit") << "touch must not re-run";

  // New bytes (same size), mtime moved too.
  WriteFile(P("proj/data/scan.ply"), ply_header + "0 0 0\n2 0 0\n0 2 0\n");
  fs::last_write_time(P("proj/data/scan.ply"), t + std::chrono::seconds(20));
  const RunResult ex = pbtest::Run({"explain", wf, "--cache", P("cache")});
  EXPECT_NE(ex.out.find("file of parameter 'path' changed"), std::string::npos) << ex.Describe();
  const RunResult r4 = RunWf(wf);
  ASSERT_EQ(r4.exit_code, 0) << r4.Describe();
  EXPECT_EQ(StageStatus(RunJson(), "scan"), "ran") << "content change must re-run";
}

// Warnings (StageContext::warning) reach the progress line, the summary,
// run.json and the stage's log; a cache hit shows them again; a stage
// without warnings keeps its record and entry as before.
constexpr const char* kWarnings = R"(name: warny
plugins: [$PLUGIN]
stages:
  src: { uses: test.source, with: { text: hello } }
  w:
    uses: test.warn
    in: { in: src.out }
    with: { warnings: ["colors dropped: not every scan has colorRed/Green/Blue", "3 scans merged"] }
  len: { uses: test.length, in: { in: w.out } }
)";

TEST_F(Cli, WarningsReachProgressRecordSummaryAndLog) {
  const std::string wf = WriteWorkflow(P("proj/warny.yaml"), kWarnings);
  const RunResult r = RunWf(wf);
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  EXPECT_NE(r.err.find("[2/3] ran     w (test.warn)"), std::string::npos) << r.Describe();
  EXPECT_NE(
      r.err.find(
          "; 2 warnings\n        warning: colors dropped: not every scan has colorRed/Green/Blue\n"
          "        warning: 3 scans merged\n"),
      std::string::npos)
      << r.Describe();
  EXPECT_NE(r.out.find("warny: 3 stages, 3 ran, 0 cached, 0 failed, 0 not run, 2 warnings in "),
            std::string::npos)
      << r.Describe();
  const Json run = RunJson();
  EXPECT_EQ(StageRecord(run, "w")["warnings"],
            Json({"colors dropped: not every scan has colorRed/Green/Blue", "3 scans merged"}));
  EXPECT_FALSE(StageRecord(run, "src").contains("warnings")) << StageRecord(run, "src").dump();
  EXPECT_NE(ReadFile(P("out/logs/w.log")).find("warning: 3 scans merged"), std::string::npos);
  // Cache entries: the record keeps the warnings; entries of stages without
  // any keep their earlier form (no "warnings" member).
  int with = 0, without = 0;
  for (const std::string& f : ListFiles(P("cache/entries"))) {
    const Json entry = ReadJson(P("cache/entries/") + f);
    (entry["record"].contains("warnings") ? with : without)++;
  }
  EXPECT_EQ(with, 1);
  EXPECT_EQ(without, 2);

  // A hit shows them again, marked as such.
  const RunResult hit = RunWf(wf, "out2");
  ASSERT_EQ(hit.exit_code, 0) << hit.Describe();
  EXPECT_NE(hit.err.find("[2/3] hit     w (test.warn)  2 warnings (from the cached run)\n"
                         "        warning: colors dropped"),
            std::string::npos)
      << hit.Describe();
  EXPECT_EQ(StageRecord(RunJson("out2"), "w")["warnings"].size(), 2u);
  EXPECT_NE(hit.out.find("0 ran, 3 cached, 0 failed, 0 not run, 2 warnings in"), std::string::npos);

  // --quiet: the count, not the text.
  const RunResult quiet = RunWf(wf, "out3", {"-q"});
  EXPECT_EQ(quiet.err.find("warning:"), std::string::npos) << quiet.Describe();
  EXPECT_NE(quiet.out.find("2 warnings"), std::string::npos) << quiet.Describe();

  // A failed stage's warnings are kept too.
  const RunResult failed = RunWf(wf, "out4", {"--set", "w.fail=true"});
  EXPECT_EQ(failed.exit_code, 1) << failed.Describe();
  const Json frec = StageRecord(RunJson("out4"), "w");
  EXPECT_EQ(frec.value("status", ""), "failed");
  EXPECT_EQ(frec["warnings"].size(), 2u) << frec.dump();
}

// --force re-runs a cached stage and replaces its entry; early cutoff holds
// downstream. --until runs only what a stage needs and copies its outputs.
TEST_F(Cli, ForceAndUntil) {
  std::string yaml = kChain;
  yaml.insert(yaml.find("outputs:"), R"(  stamp: { uses: test.stamp }
  shout: { uses: test.concat, in: { a: stamp.out }, with: { suffix: "!" } }
)");
  yaml += "  stamp: stamp.out\n  shout: shout.out\n";
  const std::string wf = WriteWorkflow(P("proj/chain.yaml"), yaml);
  // --until: only src, up and len; len's output is named already.
  const RunResult until = RunWf(wf, "out", {"--until", "len"});
  ASSERT_EQ(until.exit_code, 0) << until.Describe();
  EXPECT_EQ(Statuses(RunJson()), "src=ran up=ran len=ran ") << until.Describe();
  EXPECT_TRUE(Exists(P("out/length.json")));
  EXPECT_FALSE(Exists(P("out/other.json")));
  EXPECT_EQ(RunJson()["options"]["until"], Json({"len"}));
  // The target's output, under the name the workflow gives it.
  ASSERT_EQ(RunWf(wf, "out_up", {"--until", "up"}).exit_code, 0);
  EXPECT_EQ(TextOf(P("out_up/greeting.json")), "hello world");
  EXPECT_FALSE(Exists(P("out_up/length.json")));

  ASSERT_EQ(RunWf(wf, "full").exit_code, 0);
  const std::string stamp = TextOf(P("full/stamp.json"));
  // Forcing a stage that writes the same bytes: its dependents hit.
  const RunResult same = RunWf(wf, "forced", {"--force", "src"});
  ASSERT_EQ(same.exit_code, 0) << same.Describe();
  const Json f1 = RunJson("forced");
  EXPECT_EQ(StageStatus(f1, "src"), "ran");
  EXPECT_TRUE(StageRecord(f1, "src").value("forced", false));
  EXPECT_EQ(StageStatus(f1, "up"), "hit") << Statuses(f1);
  EXPECT_EQ(StageStatus(f1, "len"), "hit") << Statuses(f1);
  // Forcing a stage that writes new bytes: its dependents run, and the new
  // result replaces the entry, so the next plain run hits it.
  const RunResult fresh = RunWf(wf, "forced2", {"--force", "stamp"});
  ASSERT_EQ(fresh.exit_code, 0) << fresh.Describe();
  EXPECT_EQ(StageStatus(RunJson("forced2"), "shout"), "ran") << Statuses(RunJson("forced2"));
  const std::string new_stamp = TextOf(P("forced2/stamp.json"));
  EXPECT_NE(new_stamp, stamp);
  const RunResult after = RunWf(wf, "after");
  ASSERT_EQ(after.exit_code, 0) << after.Describe();
  EXPECT_NE(after.out.find(" 0 ran,"), std::string::npos) << after.Describe();
  EXPECT_EQ(TextOf(P("after/stamp.json")), new_stamp);
  EXPECT_EQ(TextOf(P("after/shout.json")), new_stamp + "!");

  // The plan says what --force does; -n is --dry-run.
  const RunResult plan = RunWf(wf, "plan", {"-n", "--force", "src"});
  ASSERT_EQ(plan.exit_code, 0) << plan.Describe();
  EXPECT_NE(plan.out.find("run   src"), std::string::npos) << plan.out;
  EXPECT_NE(plan.out.find("forced (--force): in the cache, but runs again"), std::string::npos)
      << plan.out;
  EXPECT_NE(plan.out.find("run?  up"), std::string::npos) << plan.out;
  EXPECT_FALSE(Exists(P("plan/run.json")));

  // Unknown ids: exit 2, named against the command line, nothing runs.
  for (const char* flag : {"--force", "--until"}) {
    const RunResult bad = RunWf(wf, "bad", {flag, "uq"});
    EXPECT_EQ(bad.exit_code, 2) << bad.Describe();
    EXPECT_NE(bad.err.find(std::string("<command line>: ") + flag +
                           " uq: no stage 'uq' in workflow chain (did you mean 'up'?)"),
              std::string::npos)
        << bad.Describe();
    EXPECT_FALSE(Exists(P("bad/run.json")));
  }
}

// Help, usage and unknown commands.
TEST_F(Cli, HelpNamesTheProgramEnvironmentExitCodesAndUnknownCommands) {
  const RunResult help = pbtest::Run({"--help"});
  EXPECT_EQ(help.exit_code, 0) << help.Describe();
  for (const char* text :
       {"Usage: pointbake [OPTIONS] SUBCOMMAND", "Examples:", "pointbake run WF.yaml --until",
        "POINTBAKE_CACHE", "XDG_CACHE_HOME", "Exit status: 0 done; 1 a stage",
        "2 bad input or usage", "docs/engine.md"})
    EXPECT_NE(help.out.find(text), std::string::npos) << text << "\n" << help.out;
  EXPECT_EQ(help.out.find(Binary()), std::string::npos) << "usage shows the binary's path";

  const RunResult run_help = pbtest::Run({"run", "--help"});
  EXPECT_EQ(run_help.exit_code, 0);
  EXPECT_NE(run_help.out.find("Usage: pointbake run [OPTIONS] WORKFLOW"), std::string::npos)
      << run_help.out;
  EXPECT_NE(run_help.out.find("--force STAGE"), std::string::npos) << run_help.out;
  EXPECT_EQ(run_help.out.find("Examples:"), std::string::npos)
      << "the footer belongs to the top level";

  // explain lists only options that change what it prints.
  const RunResult explain_help = pbtest::Run({"explain", "--help"});
  EXPECT_EQ(explain_help.exit_code, 0);
  for (const char* option : {"--jobs", "--mem", "--out", "--threads", "--keep-going"})
    EXPECT_EQ(explain_help.out.find(option), std::string::npos) << option << "\n"
                                                                << explain_help.out;
  for (const char* option : {"--scene", "--set", "--cache", "--force", "--until"})
    EXPECT_NE(explain_help.out.find(option), std::string::npos) << option << "\n"
                                                                << explain_help.out;

  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"publish", "--help"}, {"nosuchcmd"}, {"rnu", "x.yaml"}}) {
    const RunResult r = pbtest::Run(args);
    EXPECT_EQ(r.exit_code, 2) << r.Describe();
    EXPECT_NE(r.err.find("pointbake: unknown command '" + args[0] + "'"), std::string::npos)
        << r.Describe();
    EXPECT_NE(r.err.find("commands: run, campaign,"), std::string::npos) << r.Describe();
    EXPECT_TRUE(r.out.empty()) << r.Describe();
  }
  EXPECT_NE(pbtest::Run({"rnu"}).err.find("(did you mean 'run'?)"), std::string::npos);
  // serve is a command (cli/serve_command.cc): its own help, exit 0.
  const RunResult serve_help = pbtest::Run({"serve", "--help"});
  EXPECT_EQ(serve_help.exit_code, 0) << serve_help.Describe();
  EXPECT_NE(serve_help.out.find("Usage: pointbake serve [DIR]"), std::string::npos) << serve_help.Describe();
  // `help COMMAND` is `COMMAND --help`.
  const RunResult help_run = pbtest::Run({"help", "run"});
  EXPECT_EQ(help_run.exit_code, 0) << help_run.Describe();
  EXPECT_EQ(help_run.out, run_help.out);
  EXPECT_EQ(pbtest::Run({"help"}).out, help.out);
  const RunResult none = pbtest::Run({});
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("Usage: pointbake"), std::string::npos) << none.Describe();
}

// `stages ID`: parameters required first, then in the schema's order, with
// plain types, bounds and defaults, and a snippet to paste into a workflow.
TEST_F(Cli, StagesShowsReadableParametersAndASnippet) {
  const RunResult ds = pbtest::Run({"stages", "points.downsample"});
  ASSERT_EQ(ds.exit_code, 0) << ds.Describe();
  EXPECT_NE(ds.out.find("  voxel : number (> 0)  default 0.01\n"), std::string::npos) << ds.out;
  EXPECT_EQ(ds.out.find("\"number\""), std::string::npos) << ds.out;
  EXPECT_NE(ds.out.find("in a workflow:\n  my_downsample:\n    uses: points.downsample\n    in:\n"
                        "      points: STAGE.PORT   # points\n    with:\n      voxel: 0.01\n"),
            std::string::npos)
      << ds.out;
  const RunResult rp = pbtest::Run({"stages", "io.read_points"});
  ASSERT_EQ(rp.exit_code, 0) << rp.Describe();
  const std::string params = rp.out.substr(rp.out.find("parameters:"));
  EXPECT_EQ(params.find("  path : string  required"), params.find('\n') + 1) << params;
  EXPECT_NE(params.find("format : one of: auto, ply, pcd, xyz, ptx, e57, las  default auto"),
            std::string::npos)
      << params;
  EXPECT_NE(params.find("      path: <string>   # required\n"), std::string::npos) << params;
  // Stable: the same text twice.
  EXPECT_EQ(pbtest::Run({"stages", "io.read_points"}).out, rp.out);
  const RunResult typo = pbtest::Run({"stages", "points.normal"});
  EXPECT_EQ(typo.exit_code, 2);
  EXPECT_NE(typo.err.find("(did you mean 'points.normals'?)"), std::string::npos)
      << typo.Describe();
}

// A workflow without `name:` is named after its file.
TEST_F(Cli, WorkflowNameDefaultsToTheFileStem) {
  WriteWorkflow(P("proj/no_name.yaml"), R"(plugins: [$PLUGIN]
stages:
  src: { uses: test.source, with: { text: hi } }
)");
  const RunResult v = pbtest::Run({"validate", "proj/no_name.yaml"}, {}, tmp_.path());
  EXPECT_EQ(v.exit_code, 0) << v.Describe();
  const RunResult r =
      pbtest::Run({"run", "proj/no_name.yaml", "--cache", P("cache")}, {}, tmp_.path());
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  EXPECT_NE(r.out.find("record in out/no_name/run.json"), std::string::npos) << r.Describe();
  EXPECT_EQ(ReadJson(P("out/no_name/run.json")).value("workflow", ""), "no_name");
}

// `campaign --dry-run` / `-n` and `campaign explain`: per run, what would
// run and what is cached; what an earlier run computes counts as reuse.
TEST_F(Cli, CampaignDryRunAndExplain) {
  WriteFile(P("proj/scene.yaml"), "name: s1\n");
  WriteWorkflow(P("proj/a.yaml"), R"(name: a
plugins: [$PLUGIN]
stages:
  src: { uses: test.source, with: { text: hello } }
  up: { uses: test.concat, in: { a: src.out }, with: { suffix: " a" } }
)");
  WriteWorkflow(P("proj/b.yaml"), R"(name: b
plugins: [$PLUGIN]
stages:
  src: { uses: test.source, with: { text: hello } }
  w: { uses: test.warn, in: { in: src.out }, with: { warnings: ["watch out"] } }
)");
  WriteFile(P("proj/c.yaml"), "name: c\nscenes: [scene.yaml]\nworkflows: [a.yaml, b.yaml]\n");
  const std::vector<std::string> base = {"--cache", P("cache"), "--out", P("camp")};
  auto campaign = [&](std::vector<std::string> args) {
    args.insert(args.end(), base.begin(), base.end());
    return pbtest::Run(args);
  };
  const RunResult dry = campaign({"campaign", P("proj/c.yaml"), "-n"});
  ASSERT_EQ(dry.exit_code, 0) << dry.Describe();
  EXPECT_NE(dry.out.find("campaign c: 2 runs; dry run, nothing runs"), std::string::npos)
      << dry.out;
  EXPECT_NE(dry.out.find("[1/2] s1/a: 0 cached, 1 to run, 1 to run unless"), std::string::npos)
      << dry.out;
  EXPECT_NE(
      dry.out.find("[2/2] s1/b: 0 cached, 0 to run, 1 to run unless upstream outputs come out "
                   "unchanged, 1 computed by an earlier run"),
      std::string::npos)
      << dry.out;
  EXPECT_NE(dry.out.find("  reuse src "), std::string::npos) << dry.out;
  EXPECT_EQ(CountEntries(P("cache")), 0);
  EXPECT_FALSE(Exists(P("camp/campaign.json")));

  const RunResult real = campaign({"campaign", P("proj/c.yaml"), "-q"});
  ASSERT_EQ(real.exit_code, 0) << real.Describe();
  EXPECT_NE(real.out.find("s1/b: 2 stages, 1 ran, 1 cached, 0 failed, 0 not run, 1 warning in"),
            std::string::npos)
      << real.out;
  const Json manifest = ReadJson(P("camp/campaign.json"));
  EXPECT_EQ(manifest["runs"][1].value("warnings", 0), 1) << manifest.dump(1);
  EXPECT_FALSE(manifest["runs"][0].contains("warnings"));

  // Everything cached now; explain gives the reasons for hits too.
  const RunResult explain =
      pbtest::Run({"campaign", "explain", P("proj/c.yaml"), "--cache", P("cache")});
  ASSERT_EQ(explain.exit_code, 0) << explain.Describe();
  EXPECT_NE(
      explain.out.find(
          "campaign c: 4 cached, 0 to run, 0 to run unless upstream outputs come out unchanged\n"),
      std::string::npos)
      << explain.out;
  EXPECT_NE(explain.out.find("  hit   w "), std::string::npos) << explain.out;
  // A dry run with everything cached lists no stage.
  const RunResult cached = campaign({"campaign", P("proj/c.yaml"), "--dry-run"});
  EXPECT_EQ(cached.out.find("  hit "), std::string::npos) << cached.out;
  // No file: a usage error.
  const RunResult nofile = pbtest::Run({"campaign", "-n"});
  EXPECT_EQ(nofile.exit_code, 2) << nofile.Describe();
  EXPECT_NE(nofile.err.find("a campaign FILE is required"), std::string::npos) << nofile.Describe();
}

// The executor from a user config file: a bad value is reported at its file,
// line and column before anything runs; an executor that cannot reach Slurm
// says which command it could not run. (Runs through Slurm: tests/slurm/.)
TEST_F(Cli, UserConfigChoosesTheExecutorAndReportsItsMistakes) {
  const std::string wf = WriteWorkflow(P("proj/chain.yaml"), kChain);
  WriteFile(P("bad.yaml"), "executor: slurm\nslurm:\n  partiton: batch\n");
  RunResult r = RunWf(wf, "out", {"--config", P("bad.yaml")});
  EXPECT_EQ(r.exit_code, 2) << r.Describe();
  EXPECT_NE(r.err.find("bad.yaml:3:3: unknown key 'partiton'"), std::string::npos) << r.Describe();
  EXPECT_FALSE(std::filesystem::exists(P("out/run.json")));

  WriteFile(P("bad_mem.yaml"), "slurm:\n  default_mem: lots\n");
  r = RunWf(wf, "out", {"--config", P("bad_mem.yaml")});
  EXPECT_EQ(r.exit_code, 2) << r.Describe();
  EXPECT_NE(r.err.find("bad_mem.yaml:2:16:"), std::string::npos) << r.Describe();

  // The config asks for Slurm; with no sbatch in PATH the stage fails saying so.
  WriteFile(P("slurm.yaml"), "executor: slurm\n");
  r = pbtest::Run({"run", wf, "--cache", P("cache"), "--out", P("out"), "--config", P("slurm.yaml")},
                  {{"PATH", P("empty-path")}});
  EXPECT_EQ(r.exit_code, 1) << r.Describe();
  EXPECT_NE(RunJson().dump().find("cannot run 'sbatch'"), std::string::npos) << RunJson().dump(1);

  // The command line wins over the config file.
  r = RunWf(wf, "out", {"--config", P("slurm.yaml"), "--executor", "local"});
  EXPECT_EQ(r.exit_code, 0) << r.Describe();
}

}  // namespace
}  // namespace pbtest
