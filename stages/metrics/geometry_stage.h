#pragma once

#include "engine/stage.h"

namespace pb {

// metrics.geometry: MeasureMeshDistance (stages/geometry/mesh_distance.h) as a stage.
StageType GeometryMetricsStage();

}  // namespace pb
