#include "engine/scheduler.h"

#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <set>
#include <thread>

#include "engine/key.h"
#include "engine/run_record.h"
#include "engine/test_util.h"

namespace pb {
namespace {

using testing::TempDir;

// Runs stages in-process and counts executions; can hold each job a while
// and record how many run at once.
class CountingExecutor : public Executor {
 public:
  JobResult Run(const JobSpec& job, const ProgressFn& progress) override {
    const int now = ++concurrent_;
    int seen = max_concurrent_.load();
    while (now > seen && !max_concurrent_.compare_exchange_weak(seen, now)) {
    }
    if (hold_ms_) std::this_thread::sleep_for(std::chrono::milliseconds(hold_ms_));
    JobResult r = inner_.Run(job, progress);
    r.peak_rss_bytes = 100 << 20;  // pretend each stage needs 100 MiB
    --concurrent_;
    {
      std::lock_guard<std::mutex> g(mu_);
      ran_.push_back(job.stage_id);
    }
    return r;
  }
  std::vector<std::string> ran() {
    std::lock_guard<std::mutex> g(mu_);
    std::sort(ran_.begin(), ran_.end());
    auto out = ran_;
    ran_.clear();
    return out;
  }
  int hold_ms_ = 0;
  std::atomic<int> max_concurrent_{0};

 private:
  InProcessExecutor inner_;
  std::atomic<int> concurrent_{0};
  std::mutex mu_;
  std::vector<std::string> ran_;
};

class SchedulerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    testing::RegisterTestStages(registry_);
    cache_ = Cache::Open(dir_.path() + "/cache").value();
  }
  std::vector<StageOutcome> Run(const std::string& yaml, std::vector<std::string> sets = {},
                                RunOptions opts = {}) {
    auto wf = LoadWorkflow(dir_.Write("wf.yaml", yaml), LoadOptions{"", sets}, registry_);
    EXPECT_TRUE(wf.ok()) << wf.status().message();
    workflow_ = std::move(wf).value();
    return Scheduler(workflow_, *cache_, executor_, nullptr).Run(opts);
  }
  static std::map<std::string, std::string> States(const std::vector<StageOutcome>& outs) {
    std::map<std::string, std::string> m;
    for (const auto& o : outs) m[o.id] = StateName(o.state);
    return m;
  }
  Registry registry_;
  TempDir dir_;
  std::unique_ptr<Cache> cache_;
  CountingExecutor executor_;
  Workflow workflow_;
};

constexpr const char* kChain = R"(name: chain
stages:
  src: { uses: t.text, with: { text: abc } }
  len: { uses: t.len, in: { in: src.out } }
  up: { uses: t.upper, in: { in: len.out } }
  side: { uses: t.upper, in: { in: src.out } }
)";

TEST_F(SchedulerTest, SecondRunHitsEverything) {
  auto first = Run(kChain);
  EXPECT_EQ(executor_.ran(), (std::vector<std::string>{"len", "side", "src", "up"}));
  auto second = Run(kChain);
  EXPECT_TRUE(executor_.ran().empty());
  for (const auto& o : second) EXPECT_EQ(o.state, StageOutcome::State::kHit) << o.id;
}

TEST_F(SchedulerTest, ParameterChangeRerunsStageAndDependentsWithEarlyCutoff) {
  Run(kChain);
  executor_.ran();
  // Same length: len re-runs (its input changed) but writes the same bytes,
  // so `up` hits; `side` sees new text and re-runs.
  auto outs = Run(kChain, {"src.text=xyz"});
  EXPECT_EQ(executor_.ran(), (std::vector<std::string>{"len", "side", "src"}));
  EXPECT_EQ(States(outs)["up"], "hit");
  // A parameter outside the key changes nothing.
  Run(kChain, {"src.text=xyz", "src.threads=8"});
  EXPECT_TRUE(executor_.ran().empty());
}

TEST_F(SchedulerTest, ExplainNamesTheChangedParameter) {
  Run(kChain);
  auto wf = LoadWorkflow(dir_.path() + "/wf.yaml", LoadOptions{"", {"src.text=abcd"}}, registry_);
  ASSERT_TRUE(wf.ok());
  auto plan = PlanWorkflow(*wf, *cache_).value();
  ASSERT_EQ(plan[0].stage, "src");
  EXPECT_EQ(plan[0].state, PlanLine::State::kMiss);
  ASSERT_FALSE(plan[0].reasons.empty());
  EXPECT_EQ(plan[0].reasons[0], "parameter 'text' changed: \"abc\" -> \"abcd\"");
  for (size_t i = 1; i < plan.size(); ++i) EXPECT_EQ(plan[i].state, PlanLine::State::kDependsOnUpstream);
}

TEST_F(SchedulerTest, FailureStopsDependentsAndKeepGoingRunsSiblings) {
  registry_.Register(StageType{.id = "t.boom",
                               .summary = "fails",
                               .outputs = {{"out", "table"}},
                               .run = [](StageContext&) { return Status::Invalid("boom"); }});
  const std::string yaml = R"(name: fail
stages:
  a: { uses: t.boom }
  b: { uses: t.upper, in: { in: a.out } }
  c: { uses: t.text }
)";
  RunOptions keep;
  keep.keep_going = true;
  auto outs = Run(yaml, {}, keep);
  auto states = States(outs);
  EXPECT_EQ(states["a"], "failed");
  EXPECT_EQ(states["b"], "skipped");
  EXPECT_EQ(states["c"], "ran");
  EXPECT_EQ(outs[0].error, "boom");
  // The failure is not cached.
  outs = Run(yaml, {}, keep);
  EXPECT_EQ(States(outs)["a"], "failed");
}

TEST_F(SchedulerTest, MemoryBudgetHoldsBackParallelStages) {
  const std::string yaml = R"(name: wide
stages:
  a: { uses: t.text, with: { text: a } }
  b: { uses: t.text, with: { text: b } }
  c: { uses: t.text, with: { text: c } }
  d: { uses: t.text, with: { text: d } }
)";
  executor_.hold_ms_ = 50;
  RunOptions opts;
  opts.jobs = 4;
  Run(yaml, {}, opts);
  EXPECT_GE(executor_.max_concurrent_.load(), 2);
  // Learned peaks (100 MiB each) against a 250 MiB budget: at most 2 at once.
  executor_.max_concurrent_ = 0;
  opts.mem_budget_bytes = 250ull << 20;
  Run(yaml, {"a.text=A", "b.text=B", "c.text=C", "d.text=D"}, opts);
  EXPECT_EQ(executor_.ran().size(), 8u);
  EXPECT_LE(executor_.max_concurrent_.load(), 2);
  EXPECT_GE(executor_.max_concurrent_.load(), 1);
}

// Warnings travel with the outcome, are kept with the cache entry (not in the
// key), come back on a hit, and reach the run record.
TEST_F(SchedulerTest, WarningsReachTheRecordAndComeBackOnHits) {
  registry_.Register(StageType{
      .id = "t.warn",
      .summary = "warns",
      .params_schema = R"({"type":"object","properties":{"n":{"type":"integer","default":2}}})",
      .outputs = {{"out", "table"}},
      .run = [](StageContext& ctx) {
        const int n = ctx.params()["n"].get<int>();
        for (int i = 0; i < n; ++i) ctx.warning("careful #" + std::to_string(i) + "\n");
        std::ofstream(ctx.output_path("out", "table.json")) << "w";
        return Status::Ok();
      }});
  const std::string yaml = R"(name: warn
stages:
  w: { uses: t.warn }
  len: { uses: t.len, in: { in: w.out } }
)";
  auto first = Run(yaml);
  ASSERT_EQ(States(first)["w"], "ran");
  ASSERT_EQ(first[0].id, "w");  // topological order
  EXPECT_EQ(first[0].warnings, (std::vector<std::string>{"careful #0", "careful #1"}));
  EXPECT_TRUE(first[1].warnings.empty());
  const nlohmann::json record = RunRecordJson(workflow_, first, nlohmann::json::object());
  EXPECT_EQ(record["stages"][0]["warnings"], nlohmann::json({"careful #0", "careful #1"}));
  EXPECT_FALSE(record["stages"][1].contains("warnings")) << record.dump();
  // Every named output says which stage output it is.
  ASSERT_TRUE(record.contains("outputs")) << record.dump();
  for (const auto& [name, ref] : workflow_.outputs)
    EXPECT_EQ(record["outputs"][name], ref.first + "." + ref.second) << name;
  EXPECT_EQ(record["outputs"].size(), workflow_.outputs.size());
  EXPECT_EQ(record["outputs"].value("len.out", ""), "len.out") << record["outputs"].dump();  // the target's

  auto second = Run(yaml);
  ASSERT_EQ(States(second)["w"], "hit");
  EXPECT_EQ(second[0].warnings, first[0].warnings);

  // Past the limit: the first kMaxStageWarnings and a count of the rest.
  auto many = Run(yaml, {"w.n=" + std::to_string(kMaxStageWarnings + 7)});
  ASSERT_EQ(many[0].warnings.size(), static_cast<size_t>(kMaxStageWarnings) + 1);
  EXPECT_EQ(many[0].warnings.back(), "... and 7 more warnings (see the stage's log)");
}

// --force: the stage runs though cached, and its result replaces the entry;
// dependents keep the usual rule (early cutoff when the bytes are the same).
TEST_F(SchedulerTest, ForceRerunsAStageAndReplacesItsEntry) {
  static int counter = 0;
  registry_.Register(StageType{.id = "t.counter",
                               .summary = "a new text each run",
                               .outputs = {{"out", "table"}},
                               .run = [](StageContext& ctx) {
                                 std::ofstream(ctx.output_path("out", "table.json")) << ++counter;
                                 return Status::Ok();
                               }});
  const std::string yaml = R"(name: force
stages:
  src: { uses: t.text, with: { text: abc } }
  len: { uses: t.len, in: { in: src.out } }
  c: { uses: t.counter }
  up: { uses: t.upper, in: { in: c.out } }
)";
  Run(yaml);
  executor_.ran();
  RunOptions opts;
  opts.force = {"src", "c"};
  auto forced = Run(yaml, {}, opts);
  // src writes the same bytes: len hits. c writes a new number: up re-runs.
  EXPECT_EQ(executor_.ran(), (std::vector<std::string>{"c", "src", "up"}));
  auto states = States(forced);
  EXPECT_EQ(states["len"], "hit");
  EXPECT_EQ(states["up"], "ran");
  for (const auto& o : forced) EXPECT_EQ(o.forced, o.id == "src" || o.id == "c") << o.id;
  const std::string c_digest =
      forced[0].id == "c" ? forced[0].outputs.at("out").ComputeDigest().Hex() : "";
  ASSERT_FALSE(c_digest.empty());
  // The forced result replaced the entry: the next run hits it.
  auto after = Run(yaml);
  EXPECT_TRUE(executor_.ran().empty());
  EXPECT_EQ(after[0].id, "c");
  EXPECT_EQ(after[0].outputs.at("out").ComputeDigest().Hex(), c_digest);

  // The plan says so.
  PlanOptions plan_opts;
  plan_opts.force = {"c"};
  auto plan = PlanWorkflow(workflow_, *cache_, plan_opts).value();
  EXPECT_EQ(plan[0].stage, "c");
  EXPECT_EQ(plan[0].state, PlanLine::State::kMiss);
  ASSERT_FALSE(plan[0].reasons.empty());
  EXPECT_NE(plan[0].reasons[0].find("forced (--force): in the cache"), std::string::npos);
  EXPECT_EQ(plan[1].state, PlanLine::State::kHit);  // src
  for (const auto& line : plan)
    if (line.stage == "up") EXPECT_EQ(line.state, PlanLine::State::kDependsOnUpstream);
}

// Campaign plans: what an earlier run computes counts as "reuse" later,
// along the whole shared chain, not only its first stage.
TEST_F(SchedulerTest, PlansOfACampaignShareKeysAcrossRuns) {
  const std::string a = R"(name: a
stages:
  src: { uses: t.text, with: { text: abc } }
  up: { uses: t.upper, in: { in: src.out } }
  len: { uses: t.len, in: { in: up.out } }
)";
  const std::string b = R"(name: b
stages:
  src: { uses: t.text, with: { text: abc } }
  up: { uses: t.upper, in: { in: src.out } }
  other: { uses: t.text, with: { text: zzz } }
)";
  std::set<std::string> planned;
  PlanOptions opts;
  opts.planned_keys = &planned;
  auto wa = LoadWorkflow(dir_.Write("a.yaml", a), {}, registry_).value();
  auto wb = LoadWorkflow(dir_.Write("b.yaml", b), {}, registry_).value();
  auto pa = PlanWorkflow(wa, *cache_, opts).value();
  auto pb = PlanWorkflow(wb, *cache_, opts).value();
  std::map<std::string, PlanLine::State> sa, sb;
  for (const auto& l : pa) sa[l.stage] = l.state;
  for (const auto& l : pb) sb[l.stage] = l.state;
  EXPECT_EQ(sa["src"], PlanLine::State::kMiss);
  EXPECT_EQ(sa["up"], PlanLine::State::kDependsOnUpstream);
  EXPECT_EQ(sb["src"], PlanLine::State::kEarlierRun);
  EXPECT_EQ(sb["up"], PlanLine::State::kEarlierRun);
  EXPECT_EQ(sb["other"], PlanLine::State::kMiss);
  // Without a campaign nothing is shared.
  auto alone = PlanWorkflow(wb, *cache_).value();
  for (const auto& l : alone) EXPECT_NE(l.state, PlanLine::State::kEarlierRun) << l.stage;
}

// A campaign's --force: a stage the runs share (the same key) is forced by
// the first run only; the plan says the later ones reuse it.
TEST_F(SchedulerTest, ACampaignForcesASharedKeyOnce) {
  const std::string yaml = R"(name: w
stages:
  src: { uses: t.text, with: { text: abc } }
)";
  Run(yaml);  // cached
  executor_.ran();
  ForcedKeys forced;
  RunOptions opts;
  opts.force = {"src"};
  opts.forced_keys = &forced;
  auto first = Run(yaml, {}, opts);
  EXPECT_EQ(executor_.ran(), (std::vector<std::string>{"src"}));
  EXPECT_TRUE(first[0].forced);
  auto second = Run(yaml, {}, opts);
  EXPECT_TRUE(executor_.ran().empty());
  EXPECT_FALSE(second[0].forced);
  EXPECT_EQ(second[0].state, StageOutcome::State::kHit);

  std::set<std::string> planned;
  PlanOptions plan_opts;
  plan_opts.force = {"src"};
  plan_opts.planned_keys = &planned;
  const Workflow wf = LoadWorkflow(dir_.Write("w.yaml", yaml), {}, registry_).value();
  EXPECT_EQ(PlanWorkflow(wf, *cache_, plan_opts).value()[0].state, PlanLine::State::kMiss);
  const PlanLine again = PlanWorkflow(wf, *cache_, plan_opts).value()[0];
  EXPECT_EQ(again.state, PlanLine::State::kEarlierRun);
  ASSERT_FALSE(again.reasons.empty());
  EXPECT_NE(again.reasons[0].find("forced (--force), and computed by an earlier run"),
            std::string::npos);
}

}  // namespace
}  // namespace pb
