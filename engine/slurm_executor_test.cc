// The Slurm executor's pure parts: reading scontrol, sizing requests,
// recognizing a memory kill, the result file's round trip. The executor
// itself runs against real Slurm daemons in tests/slurm/slurm_test.sh.
#include "engine/slurm_executor.h"

#include <gtest/gtest.h>

namespace pb {
namespace {

// Lines as Slurm 22.05's `scontrol show job -o` prints them (shortened).
constexpr const char* kOverMemory =
    "JobId=9 JobName=wrap UserId=root(0) GroupId=root(0) MCS_label=N/A Priority=4294901751 "
    "Nice=0 Account=(null) QOS=(null) JobState=FAILED Reason=JobLaunchFailure Dependency=(null) "
    "Requeue=1 Restarts=0 BatchFlag=1 Reboot=0 ExitCode=0:9 RunTime=00:00:02 "
    "NodeList=vm BatchHost=vm NumNodes=1";
constexpr const char* kTimeout =
    "JobId=12 JobName=pb:bake JobState=TIMEOUT Reason=TimeLimit Dependency=(null) ExitCode=0:0 "
    "BatchHost=node17";
constexpr const char* kHeld =
    "JobId=13 JobName=pb:scan JobState=PENDING Reason=Resources waiting for node Dependency=(null) "
    "ExitCode=0:0 BatchHost=(null)";

TEST(ParseScontrolJob, ReadsStateReasonExitCodeAndNode) {
  auto s = ParseScontrolJob(kOverMemory);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->state, "FAILED");
  EXPECT_EQ(s->reason, "JobLaunchFailure");
  EXPECT_EQ(s->exit_code, "0:9");
  EXPECT_EQ(s->node, "vm");
  EXPECT_TRUE(s->Terminal());
  auto t = ParseScontrolJob(kTimeout);
  ASSERT_TRUE(t);
  EXPECT_EQ(t->state, "TIMEOUT");
  EXPECT_EQ(t->reason, "TimeLimit");
  EXPECT_EQ(t->node, "node17");
  EXPECT_TRUE(t->Terminal());
}

TEST(ParseScontrolJob, ReasonWithSpacesAndLiveStates) {
  auto s = ParseScontrolJob(kHeld);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->reason, "Resources waiting for node");
  EXPECT_FALSE(s->Terminal());
  EXPECT_FALSE(ParseScontrolJob("slurm_load_jobs error: Invalid job id specified"));
  for (const char* live : {"RUNNING", "COMPLETING", "CONFIGURING", "REQUEUED"})
    EXPECT_FALSE(ParseScontrolJob(std::string("JobState=") + live + " Reason=None")->Terminal()) << live;
  for (const char* done : {"COMPLETED", "CANCELLED", "NODE_FAIL", "OUT_OF_MEMORY", "PREEMPTED"})
    EXPECT_TRUE(ParseScontrolJob(std::string("JobState=") + done + " Reason=None")->Terminal()) << done;
}

TEST(SlurmMemMiB, LearnedPeakWithMarginElseDefaultAndDoubledOnRetry) {
  SlurmOptions o;
  o.mem_factor = 1.25;
  o.mem_margin_bytes = 256ull << 20;
  o.default_mem_bytes = 2ull << 30;
  EXPECT_EQ(SlurmMemMiB(o, 0, 1), 2048u);
  EXPECT_EQ(SlurmMemMiB(o, 0, 2), 4096u);
  EXPECT_EQ(SlurmMemMiB(o, 1024ull << 20, 1), 1280u + 256u);
  EXPECT_EQ(SlurmMemMiB(o, 1024ull << 20, 2), 2 * (1280u + 256u));
  EXPECT_EQ(SlurmMemMiB(o, 1, 1), 257u);  // rounded up to whole MiB
}

TEST(SlurmTimeLimit, GivenElseThreeTimesLearnedPlusTenMinutes) {
  SlurmOptions o;
  EXPECT_EQ(SlurmTimeLimit(o, 0), o.unknown_time);
  EXPECT_EQ(SlurmTimeLimit(o, 60), "0:13:00");
  EXPECT_EQ(SlurmTimeLimit(o, 3600), "3:10:00");
  o.time = "45";
  EXPECT_EQ(SlurmTimeLimit(o, 3600), "45");
}

TEST(SlurmKilledForMemory, CgroupStateOrOverMemoryKillMessage) {
  SlurmJobState s;
  s.state = "OUT_OF_MEMORY";
  EXPECT_TRUE(SlurmKilledForMemory(s, ""));
  s.state = "FAILED";
  EXPECT_FALSE(SlurmKilledForMemory(s, "error: something else\n"));
  EXPECT_TRUE(SlurmKilledForMemory(
      s, "slurmstepd-vm: error: StepId=9.batch exceeded memory limit (224882688 > 52428800), being killed\n"));
  s.state = "CANCELLED";
  EXPECT_FALSE(SlurmKilledForMemory(s, "*** JOB 10 ON vm CANCELLED AT 2026-11-25T18:51:33 ***\n"));
}

TEST(JobResultJson, RoundTripKeepsOutputsAndFigures) {
  JobResult r;
  r.wall_s = 1.5;
  r.user_s = 2.25;
  r.sys_s = 0.125;
  r.peak_rss_bytes = 123456789;
  r.read_bytes = 42;
  r.write_bytes = 4242;
  r.counters = {{"points", 1000}};
  r.phases = nlohmann::json::array({{{"name", "io"}, {"start_s", 0.0}, {"dur_s", 0.5}}});
  r.warnings = {"3 scans merged", "12 invalid points dropped"};
  r.outputs["points"] = Cache::StagedOutput{"points", {{"points.ply", "/c/tmp/x/points/points.ply"}}, {{"n", 3}}};
  JobResult back = JobResultFromJson(nlohmann::json::parse(JobResultToJson(r).dump()));
  EXPECT_TRUE(back.status.ok());
  EXPECT_EQ(back.wall_s, 1.5);
  EXPECT_EQ(back.user_s, 2.25);
  EXPECT_EQ(back.sys_s, 0.125);
  EXPECT_EQ(back.peak_rss_bytes, 123456789u);
  EXPECT_EQ(back.read_bytes, 42u);
  EXPECT_EQ(back.write_bytes, 4242u);
  EXPECT_EQ(back.counters, r.counters);
  EXPECT_EQ(back.phases, r.phases);
  EXPECT_EQ(back.warnings, r.warnings);
  ASSERT_EQ(back.outputs.count("points"), 1u);
  EXPECT_EQ(back.outputs["points"].files.at("points.ply"), "/c/tmp/x/points/points.ply");
  EXPECT_EQ(back.outputs["points"].meta, r.outputs["points"].meta);

  r.status = Status::Invalid("planned failure");
  back = JobResultFromJson(JobResultToJson(r));
  EXPECT_FALSE(back.status.ok());
  EXPECT_NE(back.status.message().find("planned failure"), std::string::npos);
}

}  // namespace
}  // namespace pb
