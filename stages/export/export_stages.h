#pragma once

#include "engine/stage.h"

namespace pb {

void RegisterExportStages(StageRegistry& registry);

}  // namespace pb
