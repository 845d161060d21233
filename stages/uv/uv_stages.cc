#include "stages/uv/uv_stages.h"

#include <cassert>

namespace pb {

void RegisterUvStages(StageRegistry& registry) {
  for (StageType type : {UnwrapStage()}) {
    [[maybe_unused]] const Status status = registry.Register(std::move(type));
    assert(status.ok());
  }
}

}  // namespace pb
