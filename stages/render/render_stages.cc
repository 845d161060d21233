#include "stages/render/render_stages.h"

namespace pb {

void RegisterRenderStages(StageRegistry& registry) { (void)registry; }

}  // namespace pb
