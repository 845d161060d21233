#pragma once

#include "engine/stage.h"

namespace pb {

// synth.scan: synthetic scanned rooms with ground truth.
void RegisterSynthStages(StageRegistry& registry);

}  // namespace pb
