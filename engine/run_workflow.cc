#include "engine/run_workflow.h"

#include <unistd.h>

#include <chrono>
#include <ctime>
#include <thread>

#include "base/env.h"
#include "engine/executor.h"
#include "engine/progress.h"
#include "engine/run_record.h"
#include "engine/scheduler.h"

namespace pb {
std::string UtcTimestamp() {
  std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

std::string SelfExe() { return "/proc/self/exe"; }

std::string SummaryCounts(const WorkflowRunSummary& s) {
  std::string text = std::to_string(s.stages) + " stages, " + std::to_string(s.ran) + " ran, " +
                     std::to_string(s.hit) + " cached, " + std::to_string(s.failed) + " failed, " +
                     std::to_string(s.skipped) + " not run";
  if (s.warnings > 0)
    text += ", " + std::to_string(s.warnings) + (s.warnings == 1 ? " warning" : " warnings");
  return text;
}

WorkflowRunSummary RunWorkflowInto(const Workflow& wf, Cache& cache, const WorkflowRunOptions& o,
                                   const std::string& out_dir) {
  WorkflowRunSummary summary;
  summary.outputs = Env::Default()->CreateDirs(out_dir + "/logs");
  if (!summary.outputs.ok()) return summary;
  RunOptions opts;
  opts.jobs = o.jobs;
  opts.mem_budget_bytes = o.mem_budget_bytes;
  opts.keep_going = o.keep_going;
  opts.threads_per_stage = o.threads_per_stage;
  opts.force = o.force;
  opts.forced_keys = o.forced_keys;
  opts.log_dir = ResolvePath(".", out_dir + "/logs");
  LocalProcessExecutor local(SelfExe());
  InProcessExecutor in_process;
  Executor& executor = o.executor     ? *o.executor
                       : o.in_process ? static_cast<Executor&>(in_process)
                                      : local;
  ProgressPrinter printer(::isatty(2) != 0, o.quiet);
  Scheduler scheduler(wf, cache, executor, &printer);
  const std::string started = UtcTimestamp();
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<StageOutcome> outcomes = scheduler.Run(opts);
  summary.total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  nlohmann::json info = {{"started", started},
                         {"total_wall_s", summary.total_s},
                         {"cache", cache.dir()},
                         {"options",
                          {{"jobs", o.jobs}, {"mem_budget_bytes", o.mem_budget_bytes},
                           {"keep_going", o.keep_going}, {"sets", o.sets}, {"scene", wf.scene_file}}},
                         {"host", {{"cores", std::thread::hardware_concurrency()}}}};
  if (!o.force.empty()) info["options"]["force"] = o.force;
  if (!o.until.empty()) info["options"]["until"] = o.until;
  summary.outputs = WriteRunOutputs(wf, outcomes, info, cache, out_dir, &summary.written);
  summary.stages = static_cast<int>(outcomes.size());
  for (const auto& s : outcomes) {
    if (s.state == StageOutcome::State::kRan) ++summary.ran;
    if (s.state == StageOutcome::State::kHit) ++summary.hit;
    if (s.state == StageOutcome::State::kFailed) ++summary.failed;
    if (s.state == StageOutcome::State::kSkipped) ++summary.skipped;
    summary.warnings += static_cast<int>(s.warnings.size());
  }
  return summary;
}

}  // namespace pb
