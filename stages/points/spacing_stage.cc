// points.spacing: median nearest-neighbour distance (stages/geometry/points/spacing.h),
// recorded in the artifact's meta for later stages' thresholds.
#include "stages/geometry/points/spacing.h"
#include "stages/params.h"
#include "stages/points_io.h"
#include "stages/builtin.h"

namespace pb {
namespace {

constexpr const char* kId = "points.spacing";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "sample": {
      "type": "integer",
      "minimum": 0,
      "default": 100000,
      "description": "Points whose nearest-neighbour distance is measured, evenly spread over the input order (deterministic); 0 measures every point."
    }
  }
})";

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const int64_t sample, IntegerParam(ctx, kId, "sample", {0}));
  PB_ASSIGN_OR_RETURN(const InputPoints input, ReadInputPoints(ctx, kId, 0.4));
  const PointCloud& cloud = input.cloud;
  double spacing_m = 0;
  {
    PB_PHASE(ctx, "compute");
    SpacingOptions options;
    options.sample = static_cast<size_t>(sample);
    options.threads = ctx.threads();
    Expected<double> spacing = MedianSpacing(cloud, options);
    if (!spacing.ok()) return spacing.status().WithContext(input.path);
    spacing_m = *spacing;
  }
  ctx.progress(0.7);
  ctx.counter("spacing_mm", spacing_m * 1000.0);
  PB_RETURN_IF_ERROR(
      CopyInputPoints(ctx, input.path, InputPointsMetaWith(ctx, {{"spacing_m", spacing_m}})));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType SpacingStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Median nearest-neighbour distance, added to the points' meta as spacing_m";
  type.doc =
      "Measures the point spacing: the median, over `sample` points (or all), of the exact "
      "distance from a point to its nearest other point (duplicates count as 0). The output "
      "is the same file, copied unchanged, with `spacing_m` (meters) added to the meta; "
      "later stages express distance thresholds in spacings.\n\n"
      "Counter: `spacing_mm`.";
  type.params_schema = kSchema;
  type.inputs = {{"points", "points", "The points to measure.", false}};
  type.outputs = {{"points", "points", "The same points, with `spacing_m` in the meta.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
