#include "stages/bake/bake_stages.h"

#include <cassert>

namespace pb {

void RegisterBakeStages(StageRegistry& registry) {
  for (StageType type : {VertexColorsBakeStage(), FromMeshBakeStage(), FromPointsBakeStage()}) {
    [[maybe_unused]] const Status status = registry.Register(std::move(type));
    assert(status.ok());
  }
}

}  // namespace pb
