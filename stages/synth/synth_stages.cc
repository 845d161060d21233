#include "stages/synth/synth_stages.h"

#include <cassert>

namespace pb {

// Defined in synth_scan_stage.cc.
StageType SynthScanStage();

void RegisterSynthStages(StageRegistry& registry) {
  [[maybe_unused]] const Status status = registry.Register(SynthScanStage());
  assert(status.ok());
}

}  // namespace pb
