#include "stages/render/render_stages.h"

#include <cassert>

namespace pb {

void RegisterRenderStages(StageRegistry& registry) {
  [[maybe_unused]] const Status status = registry.Register(FramesStage());
  assert(status.ok());
}

}  // namespace pb
