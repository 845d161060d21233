#include "stages/mesh/mesh_stages.h"

#include <cassert>

#include "stages/mesh/clean_stage.h"

namespace pb {

void RegisterMeshStages(StageRegistry& registry) {
  for (StageType type : {PoissonStage(), DecimateStage(), CleanStage()}) {
    [[maybe_unused]] const Status status = registry.Register(std::move(type));
    assert(status.ok());
  }
}

}  // namespace pb
