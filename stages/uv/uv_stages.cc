#include "stages/uv/uv_stages.h"

namespace pb {

void RegisterUvStages(StageRegistry& registry) { (void)registry; }

}  // namespace pb
