// The `io` stage family: reading scans and writing results in foreign formats.
#pragma once

#include "engine/stage.h"

namespace pb {

// io.read_points: a scan file (PLY, ...) -> `points`.
StageType ReadPointsStage();

void RegisterIoStages(StageRegistry& registry);

}  // namespace pb
