// The stage types built into the pointbake executable.
#pragma once

#include "engine/stage.h"

namespace pb {

// Registers every built-in stage family (io, points, ...).
void RegisterBuiltinStages(StageRegistry& registry);

}  // namespace pb
