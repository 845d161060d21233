// Running one loaded workflow into an output folder: the scheduler with the
// local process executor, then run.json / run.jsonl / trace.json and the
// named outputs (run_record.h). Shared by `pointbake run` and campaigns.
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "base/status.h"
#include "engine/cache.h"
#include "engine/executor.h"
#include "engine/workflow.h"

namespace pb {

class ForcedKeys;  // scheduler.h

struct WorkflowRunOptions {
  int jobs = 1;                   // stages in parallel
  uint64_t mem_budget_bytes = 0;  // 0: no budget
  bool keep_going = false;
  int threads_per_stage = 0;      // 0: all cores
  bool quiet = false;             // progress: failures and the summary only
  bool in_process = false;        // debugging: no child processes
  Executor* executor = nullptr;   // null: child processes on this machine
  std::vector<std::string> sets;  // recorded in run.json's options
  std::set<std::string> force;    // --force: run these stages whatever the cache holds
  ForcedKeys* forced_keys = nullptr;  // campaigns: force a shared key once (scheduler.h)
  std::vector<std::string> until;  // --until (recorded; the workflow is already cut)
};

struct WorkflowRunSummary {
  int stages = 0, ran = 0, hit = 0, failed = 0, skipped = 0;
  int warnings = 0;  // over every stage, hits' cached warnings included
  double total_s = 0;
  std::vector<std::string> written;  // output files copied or kept
  Status outputs;                    // writing the records and outputs
  bool ok() const { return failed == 0 && skipped == 0 && outputs.ok(); }
};

// The counts of a summary line: "7 stages, 7 ran, 0 cached, 0 failed, 0 not
// run" and ", 2 warnings" when there are some.
std::string SummaryCounts(const WorkflowRunSummary& summary);

// Now as an ISO 8601 UTC timestamp ("2026-11-21T23:47:34Z"), for records.
std::string UtcTimestamp();

// The command that runs stages in child processes: this very binary
// (/proc/self/exe), even if a rebuild replaced the file meanwhile.
std::string SelfExe();

// Runs `workflow` with `cache` (held with a shared lock by the caller) and
// writes its records and outputs into `out_dir` (created).
WorkflowRunSummary RunWorkflowInto(const Workflow& workflow, Cache& cache,
                                   const WorkflowRunOptions& options, const std::string& out_dir);

}  // namespace pb
