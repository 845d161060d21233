#include "stages/synth/synth_stages.h"

namespace pb {

void RegisterSynthStages(StageRegistry&) {}

}  // namespace pb
