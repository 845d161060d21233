// The engine's StageContext: runs one stage function on the calling thread and
// collects what it reports. Used by the child process and InProcessExecutor.
#pragma once

#include "engine/executor.h"

namespace pb {

// Runs `job` here. Output files of port P are <staging_dir>/P/<file>.
JobResult RunStageHere(const JobSpec& job, const ProgressFn& progress);

}  // namespace pb
