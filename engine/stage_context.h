// The engine's StageContext: runs one stage function on the calling thread and
// collects what it reports. Used by the child process and InProcessExecutor.
#pragma once

#include "engine/executor.h"

namespace pb {

// Runs `job` here. Output files of port P are <staging_dir>/P/<file>.
// `log_warnings`: also write each warning to stderr as "warning: TEXT" (the
// child process, whose stderr is the stage's log).
JobResult RunStageHere(const JobSpec& job, const ProgressFn& progress, bool log_warnings = false);

}  // namespace pb
