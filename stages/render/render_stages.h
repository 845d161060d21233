// The render family: render.frames (a deterministic CPU reference renderer,
// stages/geometry/render.h; docs/render.md).
#pragma once

#include "engine/stage.h"

namespace pb {

void RegisterRenderStages(StageRegistry& registry);

// render.frames (frames_stage.cc).
StageType FramesStage();

}  // namespace pb
