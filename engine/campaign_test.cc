#include "engine/campaign.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "engine/test_util.h"
#include "engine/workflow.h"

namespace pb {
namespace {

using testing::TempDir;

// A campaign running one.yaml twice on scene a (the runs share every key).
constexpr const char* kOneTwice = R"(name: demo
scenes: [../scenes/a.yaml]
workflows:
  - ../workflows/one.yaml
  - { file: ../workflows/one.yaml, label: again }
)";

class CampaignTest : public ::testing::Test {
 protected:
  void SetUp() override {
    testing::RegisterTestStages(registry_);
    dir_.Write("scenes/a.yaml", "name: room-a\nparams: { word: aa }\n");
    dir_.Write("scenes/b.yaml", "name: room-b\nparams: { word: bb }\n");
    dir_.Write("workflows/one.yaml", R"(name: one
stages:
  src: { uses: t.text, with: { text: "${scene.params.word}" }, group: input }
  up: { uses: t.upper, in: { in: src.out }, group: bake }
)");
    dir_.Write("workflows/data.txt", "x");
    dir_.Write("workflows/three.yaml", "name: three\nstages:\n  f: { uses: t.file, with: { path: data.txt } }\n");
    dir_.Write("workflows/two.yaml", R"(name: two
stages:
  src: { uses: t.text, with: { text: "${scene.params.word}", count: 1 } }
)");
  }
  // Runs in this process, printing failures and summaries only, into
  // dir_ + `out`.
  CampaignOptions InProcessInto(const std::string& out) {
    CampaignOptions options;
    options.out_dir = dir_.path() + out;
    options.run.in_process = true;
    options.run.quiet = true;
    return options;
  }
  Expected<Campaign> Load(const std::string& text) {
    return LoadCampaign(dir_.Write("campaigns/c.yaml", text), registry_);
  }
  Registry registry_;
  TempDir dir_;
};

TEST_F(CampaignTest, ExpandsScenesTimesWorkflowsTimesMatrixWithReadableNames) {
  auto c = Load(R"(name: demo
scenes: [../scenes/a.yaml, ../scenes/b.yaml]
workflows:
  - ../workflows/one.yaml
  - file: ../workflows/two.yaml
    set: { src.threads: 1 }
    matrix: { src.count: [2, 3], src.text: [x, "y z"] }
)");
  ASSERT_TRUE(c.ok()) << c.status().message();
  EXPECT_EQ(c->name, "demo");
  ASSERT_EQ(c->runs.size(), 2u * (1 + 4));
  EXPECT_EQ(c->runs[0].name, "room-a/one");
  EXPECT_EQ(c->runs[0].dir, "runs/room-a/one");
  EXPECT_EQ(c->runs[0].variant, "");
  EXPECT_TRUE(c->runs[0].sets.empty());
  EXPECT_EQ(c->runs[0].scene_file, dir_.path() + "/scenes/a.yaml");
  EXPECT_EQ(c->runs[1].name, "room-a/two+count=2,text=x");
  EXPECT_EQ(c->runs[1].sets, (std::vector<std::string>{"src.threads=1", "src.count=2", "src.text=x"}));
  EXPECT_EQ(c->runs[2].name, "room-a/two+count=2,text=y z");
  EXPECT_EQ(c->runs[2].dir, "runs/room-a/two+count=2,text=y_z");
  EXPECT_EQ(c->runs[4].variant, "count=3,text=y z");
  EXPECT_EQ(c->runs[5].name, "room-b/one");
  EXPECT_EQ(c->runs[9].scene, "room-b");
  EXPECT_EQ(c->runs[9].workflow, "two");
}

TEST_F(CampaignTest, ReportsEveryBadRunBeforeAnythingRuns) {
  auto c = Load(R"(name: demo
scenes: [../scenes/a.yaml, ../scenes/missing.yaml]
workflows:
  - ../workflows/one.yaml
  - { file: ../workflows/nope.yaml }
)");
  ASSERT_FALSE(c.ok());
  const std::string msg = c.status().message();
  EXPECT_NE(msg.find("c.yaml:2:28: scene file not found: " + dir_.path() + "/scenes/missing.yaml"),
            std::string::npos) << msg;
  EXPECT_NE(msg.find("c.yaml:5:13: workflow file not found"), std::string::npos) << msg;

  auto bad_set = Load(R"(name: demo
scenes: [../scenes/a.yaml]
workflows:
  - { file: ../workflows/one.yaml, matrix: { src.count: [1, "many"] } }
)");
  ASSERT_FALSE(bad_set.ok());
  const std::string set_msg = bad_set.status().message();
  EXPECT_NE(set_msg.find("c.yaml:4:5: workflow " + dir_.path() + "/workflows/one.yaml on scene " +
                         dir_.path() + "/scenes/a.yaml (count=many) does not load"),
            std::string::npos) << set_msg;
  EXPECT_NE(set_msg.find("<command line> --set src.count=many"), std::string::npos) << set_msg;

  auto schema = Load("name: demo\nscenes: []\nworkflows: [{ file: x.yaml, matrix: {} }]\nextra: 1\n");
  ASSERT_FALSE(schema.ok());
  EXPECT_NE(schema.status().message().find("c.yaml:2:9:"), std::string::npos) << schema.status().message();
  EXPECT_NE(schema.status().message().find("c.yaml:4:1:"), std::string::npos) << schema.status().message();

  auto twice = Load(R"(name: demo
scenes: [../scenes/a.yaml]
workflows: [../workflows/one.yaml, ../workflows/one.yaml]
)");
  ASSERT_FALSE(twice.ok());
  EXPECT_NE(twice.status().message().find("run 'room-a/one' appears twice; give one entry a `label:`"),
            std::string::npos) << twice.status().message();
}

TEST_F(CampaignTest, RunsShareTheCacheAndWriteTheManifestAndRecords) {
  auto c = Load(std::string(kOneTwice) + "  - ../workflows/three.yaml\n");
  ASSERT_TRUE(c.ok()) << c.status().message();
  // A file that goes missing after the campaign was checked fails its run only.
  std::filesystem::remove(dir_.path() + "/workflows/data.txt");
  auto cache = Cache::Open(dir_.path() + "/cache");
  ASSERT_TRUE(cache.ok()) << cache.status().message();
  CampaignOptions options = InProcessInto("/out");
  std::string report_called;
  auto result = RunCampaign(*c, **cache, options, registry_,
                            [&](const std::string& campaign_dir, const std::string& report_dir) {
                              report_called = campaign_dir + " -> " + report_dir;
                              return Status::Ok();
                            });
  ASSERT_TRUE(result.report.ok()) << result.report.message();
  EXPECT_EQ(result.runs, 3);
  EXPECT_EQ(result.failed_runs, 1);
  EXPECT_EQ(report_called, options.out_dir + " -> " + options.out_dir + "/report");

  std::ifstream in(options.out_dir + "/campaign.json");
  const auto manifest = nlohmann::json::parse(in);
  EXPECT_EQ(manifest["format"], "pointbake-campaign");
  EXPECT_EQ(manifest["version"], 1);
  ASSERT_EQ(manifest["runs"].size(), 3u);
  EXPECT_EQ(manifest["runs"][0]["status"], "ok");
  EXPECT_EQ(manifest["runs"][1]["name"], "room-a/one+again");
  EXPECT_EQ(manifest["runs"][2]["status"], "failed");
  EXPECT_NE(manifest["runs"][2]["error"].get<std::string>().find("file not found"), std::string::npos);
  EXPECT_GT(manifest["host"]["cores"].get<int>(), 0);

  // The second run of the same workflow found everything in the cache; the
  // records keep the stages' groups.
  std::ifstream first(options.out_dir + "/runs/room-a/one/run.json");
  const auto run1 = nlohmann::json::parse(first);
  std::ifstream second(options.out_dir + "/runs/room-a/one+again/run.json");
  const auto run2 = nlohmann::json::parse(second);
  ASSERT_EQ(run2["stages"].size(), 2u);
  for (const auto& stage : run2["stages"]) EXPECT_EQ(stage["status"], "hit") << stage.dump();
  for (const auto& stage : run1["stages"]) EXPECT_EQ(stage["status"], "ran") << stage.dump();
  EXPECT_EQ(run1["stages"][0]["group"], "input");
  EXPECT_EQ(run1["stages"][1]["group"], "bake");
}

// `campaign --force up`: both runs of one.yaml share up's key; the first
// run forces it, the second reuses the new entry. An id no run has is an
// error before anything runs.
TEST_F(CampaignTest, ForceRunsAStageTheRunsShareOnce) {
  auto c = Load(kOneTwice);
  ASSERT_TRUE(c.ok()) << c.status().message();
  auto cache = Cache::Open(dir_.path() + "/cache");
  ASSERT_TRUE(cache.ok()) << cache.status().message();
  CampaignOptions options = InProcessInto("/out");
  const auto no_report = [](const std::string&, const std::string&) { return Status::Ok(); };
  ASSERT_EQ(RunCampaign(*c, **cache, options, registry_, no_report).failed_runs, 0);
  options.run.force = {"up"};
  ASSERT_EQ(RunCampaign(*c, **cache, options, registry_, no_report).failed_runs, 0);
  const auto status_of = [&](const std::string& run, const std::string& stage) {
    std::ifstream in(options.out_dir + "/runs/room-a/" + run + "/run.json");
    const nlohmann::json record = nlohmann::json::parse(in);
    for (const auto& s : record["stages"])
      if (s["stage"] == stage) return s["status"].get<std::string>();
    return std::string("missing");
  };
  EXPECT_EQ(status_of("one", "up"), "ran");
  EXPECT_EQ(status_of("one", "src"), "hit");
  EXPECT_EQ(status_of("one+again", "up"), "hit");

  EXPECT_TRUE(CheckCampaignStageIds(*c, {"up", "src"}, "--force").ok());
  const Status unknown = CheckCampaignStageIds(*c, {"up", "upp"}, "--force");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.message().find("--force: no run of campaign demo has a stage 'upp' (its runs' "
                                   "stages: src, up)"),
            std::string::npos)
      << unknown.message();
}

}  // namespace
}  // namespace pb
