#include "stages/bake/bake_stages.h"

#include <cassert>

namespace pb {

void RegisterBakeStages(StageRegistry& registry) {
  (void)registry;  // the stages register here as they land
}

}  // namespace pb
