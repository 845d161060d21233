#pragma once

#include "engine/stage.h"

namespace pb {

void RegisterUvStages(StageRegistry& registry);

}  // namespace pb
