// The scheduler: runs a workflow's stages in dependency order, at most
// `jobs` at a time and within a memory budget, through an Executor, with
// every result going through the cache.
#pragma once

#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "engine/cache.h"
#include "engine/executor.h"
#include "engine/workflow.h"

namespace pb {

// The keys forced so far by the runs of one campaign: a stage that several
// runs share (the same key) is forced once, by the first run that reaches
// it; the later ones find its new entry. Thread-safe (runs may go in
// parallel).
class ForcedKeys {
 public:
  // True the first time `key` is claimed.
  bool Claim(const std::string& key) {
    std::lock_guard<std::mutex> lock(mu_);
    return keys_.insert(key).second;
  }

 private:
  std::mutex mu_;
  std::set<std::string> keys_;
};

struct RunOptions {
  int jobs = 1;
  uint64_t mem_budget_bytes = 0;  // 0: no budget
  bool keep_going = false;        // run independent stages after a failure
  int threads_per_stage = 0;      // 0: all cores
  std::string log_dir;            // <log_dir>/<stage>.log; empty: inside the staging folder
  // Stage ids run even if their key is in the cache (--force); the new
  // result replaces the entry. Their dependents follow the usual rule: they
  // hit if the forced stage's outputs come out unchanged (early cutoff).
  std::set<std::string> force;
  // Campaigns: a forced stage's key already claimed here is not forced again
  // (another run forced it); null: every forced stage runs.
  ForcedKeys* forced_keys = nullptr;
};

struct StageOutcome {
  enum class State { kPending, kRunning, kHit, kRan, kFailed, kSkipped };
  std::string id;
  std::string type;
  State state = State::kPending;
  std::string key;
  nlohmann::json components;
  std::map<std::string, Artifact> outputs;  // by port (hit or ran)
  JobResult result;                         // kRan / kFailed: this run's figures
  nlohmann::json cached_record;             // kHit: figures of the run that made the entry
  double start_s = 0, end_s = 0;            // seconds since the run started
  int slot = 0;                             // lane in the trace
  std::string error;
  // The stage's warnings (StageContext::warning): this run's for kRan and
  // kFailed; for kHit those of the run that made the entry, kept with it.
  std::vector<std::string> warnings;
  bool forced = false;  // run because of RunOptions::force
};

const char* StateName(StageOutcome::State state);

class RunObserver {
 public:
  virtual ~RunObserver() = default;
  virtual void OnStageStart(const std::string& id, const std::string& type) = 0;
  virtual void OnStageWaiting(const std::string& id, const std::string& why) = 0;
  virtual void OnStageProgress(const std::string& id, double fraction) = 0;
  virtual void OnStageEnd(const StageOutcome& outcome, int done, int total) = 0;
};

class Scheduler {
 public:
  Scheduler(const Workflow& workflow, Cache& cache, Executor& executor, RunObserver* observer)
      : wf_(workflow), cache_(cache), executor_(executor), observer_(observer) {}
  // Outcomes in the workflow's topological order.
  std::vector<StageOutcome> Run(const RunOptions& options);

 private:
  void RunOne(StageOutcome& outcome, const std::map<std::string, StageOutcome>& done,
              const RunOptions& options, double t0_offset);

  const Workflow& wf_;
  Cache& cache_;
  Executor& executor_;
  RunObserver* observer_;
};

}  // namespace pb
