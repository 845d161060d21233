// Executors run one stage job and measure it. The scheduler only sees this
// interface; the cluster executor (Slurm, on a shared cache) is in
// slurm_executor.h.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "engine/cache.h"
#include "engine/registry.h"

namespace pb {

struct JobSpec {
  std::string stage_id;
  const StageType* type = nullptr;
  nlohmann::json params;
  std::map<std::string, ArtifactView> inputs;  // by port
  std::string staging_dir;                     // outputs go to <staging_dir>/<port>/<file>
  std::vector<std::string> plugins;
  int threads = 0;  // 0: all cores
  std::string log_path;  // stdout+stderr of the stage (child executors)
  // What the stage is expected to need (learned from its last run, else
  // declared): a cluster executor sizes its request from them.
  uint64_t peak_estimate_bytes = 0;
  double wall_estimate_s = 0;

  nlohmann::json ToJson() const;
};

struct JobResult {
  Status status;
  std::map<std::string, Cache::StagedOutput> outputs;  // by port
  nlohmann::json counters = nlohmann::json::object();
  nlohmann::json phases = nlohmann::json::array();  // [{name, start_s, dur_s}]
  double wall_s = 0, user_s = 0, sys_s = 0;
  uint64_t peak_rss_bytes = 0;
  uint64_t read_bytes = 0, write_bytes = 0;  // rchar/wchar of /proc/<pid>/io
  std::string log_tail;                      // last lines of the log on failure
  std::vector<std::string> warnings;         // StageContext::warning, in order
};

using ProgressFn = std::function<void(double fraction)>;

class Executor {
 public:
  virtual ~Executor() = default;
  // Thread-safe: the scheduler calls it from several threads.
  virtual JobResult Run(const JobSpec& job, const ProgressFn& progress) = 0;
};

// Runs each stage as a child process: `<self> __stage <staging>/_job.json`.
// Peak RSS and CPU come from wait4(), I/O from /proc/<pid>/io read before the
// child is reaped. The child dies with the parent (PR_SET_PDEATHSIG).
class LocalProcessExecutor : public Executor {
 public:
  explicit LocalProcessExecutor(std::string self_exe) : self_exe_(std::move(self_exe)) {}
  JobResult Run(const JobSpec& job, const ProgressFn& progress) override;

 private:
  std::string self_exe_;
};

// Runs the stage function on the calling thread (tests, debugging). No
// isolation: a crash takes the process down, and RSS is not per stage.
class InProcessExecutor : public Executor {
 public:
  JobResult Run(const JobSpec& job, const ProgressFn& progress) override;
};

// A job file (JobSpec::ToJson) read back, with its plugins loaded into
// `registry`: `status` says why the job cannot run (a plugin that does not
// load, an unknown stage type); an unreadable or non-JSON file is an error.
// Shared by `pointbake __stage` and `pointbake __job` (Slurm).
struct LoadedJob {
  JobSpec job;
  Status status;
};
Expected<LoadedJob> LoadJobFile(const std::string& job_path, Registry& registry);

// Body of the hidden `pointbake __stage JOB.json` sub-command: runs the job
// with `registry`, writes <staging>/_result.json, returns the exit status.
int RunStageSubcommand(const std::string& job_path, Registry& registry);

}  // namespace pb
