#pragma once

#include "engine/stage.h"

namespace pb {

// mesh.clean: CleanMesh (stages/geometry/mesh_clean.h) as a stage.
StageType CleanStage();

}  // namespace pb
