#pragma once

#include "engine/stage.h"

namespace pb {

// metrics.geometry.
void RegisterMetricsStages(StageRegistry& registry);

}  // namespace pb
