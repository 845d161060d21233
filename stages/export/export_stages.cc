#include "stages/export/export_stages.h"

namespace pb {

void RegisterExportStages(StageRegistry& registry) { (void)registry; }

}  // namespace pb
