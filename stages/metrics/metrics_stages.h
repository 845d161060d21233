#pragma once

#include "engine/stage.h"

namespace pb {

// metrics.geometry, metrics.image and estimate.fps (the frame rate a device
// profile predicts, stages/metrics/fps_model.h).
void RegisterMetricsStages(StageRegistry& registry);

}  // namespace pb
