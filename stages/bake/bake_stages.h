#pragma once

#include "engine/stage.h"

namespace pb {

// bake.vertex_colors, bake.from_mesh, bake.from_points.
void RegisterBakeStages(StageRegistry& registry);

StageType VertexColorsBakeStage();
StageType FromMeshBakeStage();
StageType FromPointsBakeStage();

}  // namespace pb
