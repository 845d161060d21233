// The render family: render.frames (a deterministic CPU reference renderer).
#pragma once

#include "engine/stage.h"

namespace pb {

void RegisterRenderStages(StageRegistry& registry);

}  // namespace pb
