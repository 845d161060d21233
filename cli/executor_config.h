// Choosing the executor of `run` and `campaign`: the command line
// (`--executor slurm`, `--partition`, ...) over the user's config file.
//
// The user config file is YAML, found at `--config FILE`, else
// $POINTBAKE_CONFIG, else $XDG_CONFIG_HOME/pointbake/config.yaml, else
// ~/.config/pointbake/config.yaml (a missing default file is no error):
//
//   executor: slurm            # local (default) | slurm
//   slurm:
//     partition: batch         # sbatch --partition
//     account: heritage        # --account
//     qos: normal              # --qos
//     time: "4:00:00"          # --time for every stage (default: learned)
//     default_mem: 4G          # --mem for a stage never run before
//     sbatch_args: ["--constraint=avx2"]
//
// Errors name the file, line and column.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "base/status.h"
#include "engine/executor.h"

namespace CLI {
class App;
}

namespace pb {

struct ExecutorFlags {
  std::string config;    // --config
  std::string executor;  // --executor; empty: the config's, else local
  std::string partition, account, qos, time, default_mem;
  std::vector<std::string> sbatch_args;  // --sbatch-arg, after the config's
};

void AddExecutorOptions(CLI::App* cmd, ExecutorFlags& flags);

// The executor the flags and the config file ask for; null for the local one.
Expected<std::unique_ptr<Executor>> MakeExecutor(const ExecutorFlags& flags);

}  // namespace pb
