// points.outliers: statistical outlier removal (stages/geometry/points/outliers.h).
#include <string>

#include "stages/geometry/points/outliers.h"
#include "stages/params.h"
#include "stages/points_io.h"
#include "stages/builtin.h"

namespace pb {
namespace {

constexpr const char* kId = "points.outliers";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "k": {
      "type": "integer",
      "minimum": 1,
      "maximum": 1000,
      "default": 16,
      "description": "Neighbours (the point excluded) over which each point's mean distance is taken."
    },
    "std_ratio": {
      "type": "number",
      "minimum": 0,
      "default": 2.0,
      "description": "A point is removed when its mean neighbour distance exceeds the cloud's mean of those distances by more than std_ratio standard deviations. Smaller removes more."
    },
    "implementation": {
      "type": "string",
      "enum": ["own", "pcl"],
      "default": "own",
      "description": "Whose code runs: 'own' (exact kd-tree, parallel, the same result for any thread count) or 'pcl' (PCL 1.13's StatisticalOutlierRemoval, single-threaded, in pointbake-pcl.so; the same rule, so the same points up to float rounding at the threshold). docs/implementations.md compares them."
    }
  }
})";

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const int64_t k, IntegerParam(ctx, kId, "k", {1, 1000}));
  PB_ASSIGN_OR_RETURN(const double std_ratio, NumberParam(ctx, kId, "std_ratio"));
  PB_ASSIGN_OR_RETURN(const std::string implementation, StringParam(ctx, kId, "implementation"));
  if (implementation != "own" && implementation != "pcl") {
    return Status::Invalid(std::string(kId) + ": parameter 'implementation' must be 'own' or "
                           "'pcl', got '" + implementation + "'");
  }
  PB_ASSIGN_OR_RETURN(const InputPoints in, ReadInputPoints(ctx, kId, 0.3));
  const PointCloud& input = in.cloud;
  PointCloud output;
  OutlierReport report;
  {
    PB_PHASE(ctx, "compute");
    OutlierOptions options;
    options.k = static_cast<int>(k);
    options.std_ratio = std_ratio;
    options.implementation =
        implementation == "pcl" ? OutlierImplementation::kPcl : OutlierImplementation::kOwn;
    options.threads = ctx.threads();
    options.progress = [&ctx](double fraction) { ctx.progress(0.3 + 0.5 * fraction); };
    auto removed = RemoveStatisticalOutliers(input, options, &report);
    if (!removed.ok()) return removed.status().WithContext(std::string(kId) + ": " + in.path);
    output = std::move(*removed);
  }
  ctx.counter("points_in", static_cast<double>(report.points_in));
  ctx.counter("points_out", static_cast<double>(report.points_out));
  ctx.counter("removed", static_cast<double>(report.removed));
  nlohmann::json changes = {{"points", output.size()},
                            {"outliers_removed", report.removed},
                            {"outliers_implementation", implementation}};
  // PCL does not expose its threshold.
  if (implementation == "own") changes["outliers_threshold_m"] = report.threshold_m;
  const nlohmann::json meta = InputPointsMetaWith(ctx, changes);
  PB_RETURN_IF_ERROR(WriteOutputPoints(ctx, output, meta));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType OutliersStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Statistical outlier removal (as PCL's StatisticalOutlierRemoval)";
  type.doc =
      "For every point, the mean distance to its `k` nearest other points (exact kd-tree "
      "search); points whose mean exceeds the cloud-wide mean of those distances plus "
      "`std_ratio` sample standard deviations are removed. Kept points keep all their "
      "attributes and their order. The result does not depend on the thread count. "
      "`implementation: pcl` runs PCL's StatisticalOutlierRemoval instead (pointbake-pcl.so, "
      "loaded on first use), for campaigns that compare implementations.\n\n"
      "Meta added: `points`, `outliers_removed`, `outliers_implementation`, "
      "`outliers_threshold_m` (meters; own implementation only). "
      "Counters: `points_in`, `points_out`, `removed`.";
  type.params_schema = kSchema;
  type.inputs = {{"points", "points", "The points to clean.", false}};
  type.outputs = {{"points", "points", "The points that are not outliers.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
