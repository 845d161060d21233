#include "stages/builtin.h"

#include "stages/bake/bake_stages.h"
#include "stages/export/export_stages.h"
#include "stages/io/io_stages.h"
#include "stages/mesh/mesh_stages.h"
#include "stages/metrics/metrics_stages.h"
#include "stages/points/points_stages.h"
#include "stages/render/render_stages.h"
#include "stages/synth/synth_stages.h"
#include "stages/uv/uv_stages.h"

namespace pb {

void RegisterBuiltinStages(StageRegistry& registry) {
  RegisterIoStages(registry);
  RegisterPointsStages(registry);
  RegisterSynthStages(registry);
  RegisterMeshStages(registry);
  RegisterMetricsStages(registry);
  RegisterUvStages(registry);
  RegisterBakeStages(registry);
  RegisterExportStages(registry);
  RegisterRenderStages(registry);
}

}  // namespace pb
