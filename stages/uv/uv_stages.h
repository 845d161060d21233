#pragma once

#include "engine/stage.h"

namespace pb {

void RegisterUvStages(StageRegistry& registry);

// uv.unwrap: charts or per-triangle UV atlas (stages/geometry/uv_atlas.h).
StageType UnwrapStage();

}  // namespace pb
