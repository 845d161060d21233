#include "stages/io/io_stages.h"

#include <cassert>

namespace pb {

void RegisterIoStages(StageRegistry& registry) {
  // The registry records failures itself (and the CLI reports them); a
  // built-in stage that fails to register is a bug caught by tests.
  [[maybe_unused]] const Status status = registry.Register(ReadPointsStage());
  assert(status.ok());
}

}  // namespace pb
