#pragma once

#include "engine/stage.h"

namespace pb {

// mesh.decimate, mesh.clean.
void RegisterMeshStages(StageRegistry& registry);

// mesh.decimate (decimate_stage.cc), for tests.
StageType DecimateStage();

}  // namespace pb
