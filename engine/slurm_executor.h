// The Slurm executor: each stage job becomes one Slurm batch job
// (`sbatch` of `pointbake __job <staging>/_slurm_job.json`), so a workflow
// or a campaign runs on a cluster with the cache on a shared file system
// (docs/cluster.md).
//
// Who does what:
//   - the submitting process (`pointbake run|campaign --executor slurm`) keeps
//     the scheduler, the cache locks and the commits, exactly as locally; per
//     stage it writes the job file into the stage's staging folder inside the
//     cache, submits it, and waits for the job;
//   - the job, on a compute node, runs `pointbake __job`, which runs the stage
//     as a child process with the local executor (so wall, CPU, peak RSS and
//     I/O are measured inside the job, by wait4 and /proc/<pid>/io, as
//     locally) and writes everything into <staging>/_slurm_result.json by
//     temporary name + rename; the stage's outputs stay in the staging folder
//     until the submitter commits them, so a killed job leaves nothing in the
//     cache that looks complete.
//
// Files in the staging folder (all on the shared file system):
//   _slurm_job.json     the job (JobSpec::ToJson)
//   _slurm_result.json  written last by the job: JobResult with its figures
//   _slurm.out          Slurm's stdout/stderr of the batch job (sbatch -o)
//   _log.txt            the stage's own stdout/stderr; copied to the run's
//                       logs/<stage>.log by the submitter
//
// Faults: a job that ends without a result is reported with Slurm's state
// and reason (OUT_OF_MEMORY, TIMEOUT, CANCELLED, NODE_FAIL, ...); a job
// killed for exceeding its --mem is submitted once more with twice the
// memory. Ctrl-C (SIGINT/SIGTERM) scancels every job this process submitted.
#pragma once

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "engine/executor.h"

namespace pb {

struct SlurmOptions {
  std::string partition;  // sbatch --partition; empty: the cluster's default
  std::string account;    // --account
  std::string qos;        // --qos
  // --time for every job, in a Slurm time format ("30", "1:00:00",
  // "2-00:00:00"); empty: three times the stage's learned wall time plus
  // 10 minutes, or `unknown_time` for a stage never run before.
  std::string time;
  std::string unknown_time = "2:00:00";
  // --mem = learned (or declared) peak RSS × mem_factor + mem_margin_bytes;
  // a stage with neither asks for default_mem_bytes.
  double mem_factor = 1.25;
  uint64_t mem_margin_bytes = 256ull << 20;
  uint64_t default_mem_bytes = 2ull << 30;
  std::vector<std::string> sbatch_args;  // passed to sbatch as they are
  std::string sbatch = "sbatch";         // the commands, found in PATH
  std::string scontrol = "scontrol";
  std::string scancel = "scancel";
  double poll_s = 0.05;  // how often the result file is looked for at first
  // After Slurm reports a job ended, how long to wait for its result file to
  // show up (a shared file system's attribute cache may hide it for a while).
  double result_grace_s = 60;
};

// What `scontrol show job -o ID` says about one job.
struct SlurmJobState {
  std::string state;      // PENDING, RUNNING, COMPLETED, FAILED, OUT_OF_MEMORY, ...
  std::string reason;     // Reason=...
  std::string exit_code;  // ExitCode=status:signal
  std::string node;       // BatchHost=...
  bool Terminal() const;  // the job will not run any more
};

// Parses one line of `scontrol show job -o`. nullopt if it has no JobState.
std::optional<SlurmJobState> ParseScontrolJob(const std::string& line);

// The --mem value in MiB for a stage expected to peak at `estimate_bytes`
// (0: unknown), on attempt 1 or 2 (the retry after running out of memory).
uint64_t SlurmMemMiB(const SlurmOptions& options, uint64_t estimate_bytes, int attempt);

// The --time value for a stage whose last run took `learned_wall_s` (0: never ran).
std::string SlurmTimeLimit(const SlurmOptions& options, double learned_wall_s);

// True if the job's state or Slurm's output says it was killed for memory
// (OUT_OF_MEMORY under cgroups; "exceeded memory limit" under OverMemoryKill).
bool SlurmKilledForMemory(const SlurmJobState& state, const std::string& slurm_output);

// The full result of a stage job as JSON (outputs, counters, phases and the
// figures), and back; the job's side of _slurm_result.json.
nlohmann::json JobResultToJson(const JobResult& result);
JobResult JobResultFromJson(const nlohmann::json& j);

class SlurmExecutor : public Executor {
 public:
  // `self_exe`: the absolute path of this binary, which must be at the same
  // path on the compute nodes (a shared file system, or the same install).
  SlurmExecutor(std::string self_exe, SlurmOptions options);
  ~SlurmExecutor() override;
  JobResult Run(const JobSpec& job, const ProgressFn& progress) override;

  // True once SIGINT/SIGTERM arrived: running jobs are cancelled, no new one
  // is submitted.
  static bool Interrupted();

 private:
  JobResult RunAttempt(const JobSpec& job, int attempt, bool* killed_for_memory);
  void Cancel(const std::string& job_id);

  std::string self_exe_;
  SlurmOptions options_;
};

// Body of the hidden `pointbake __job JOB.json` sub-command, run inside a
// Slurm job: runs the stage with the local executor (a child process,
// measured) and writes <staging>/_slurm_result.json. Exit status 0 if the
// stage succeeded, 1 if it failed, 2 if no result could be written.
int RunSlurmJobSubcommand(const std::string& job_path, Registry& registry);

}  // namespace pb
