#include "stages/points/points_stages.h"

#include <cassert>

namespace pb {

void RegisterPointsStages(StageRegistry& registry) {
  for (StageType type : {DownsampleStage(), StatsStage(), OutliersStage(), NormalsStage(), SpacingStage()}) {
    [[maybe_unused]] const Status status = registry.Register(std::move(type));
    assert(status.ok());
  }
}

}  // namespace pb
