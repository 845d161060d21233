#include "stages/metrics/metrics_stages.h"

#include <cassert>

#include "stages/metrics/geometry_stage.h"
#include "stages/metrics/image_stage.h"

namespace pb {

StageType FpsStage();  // estimate.fps, fps_stage.cc

void RegisterMetricsStages(StageRegistry& registry) {
  [[maybe_unused]] const Status status = registry.Register(GeometryMetricsStage());
  assert(status.ok());
  [[maybe_unused]] const Status image_status = registry.Register(ImageMetricsStage());
  assert(image_status.ok());
  [[maybe_unused]] const Status fps_status = registry.Register(FpsStage());
  assert(fps_status.ok());
}

}  // namespace pb
