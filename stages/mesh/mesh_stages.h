#pragma once

#include "engine/stage.h"

namespace pb {

// mesh.poisson, mesh.decimate, mesh.clean.
void RegisterMeshStages(StageRegistry& registry);

// mesh.decimate (decimate_stage.cc), for tests.
StageType DecimateStage();

// mesh.poisson (poisson_stage.cc), for tests.
StageType PoissonStage();

}  // namespace pb
