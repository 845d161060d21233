// points.outliers: statistical outlier removal (stages/geometry/points/outliers.h)
// or the points in the air (stages/geometry/points/strays.h).
#include <algorithm>
#include <cstdio>
#include <string>

#include "stages/geometry/points/outliers.h"
#include "stages/geometry/points/strays.h"
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
    "method": {
      "type": "string",
      "enum": ["statistical", "air"],
      "default": "statistical",
      "description": "'statistical': PCL's rule (std_ratio, below). 'air': points in the air (points/strays.h): sparser than spacing_ratio times the cloud's median local spacing and on no plane or line with half their k nearest; the shipped workflows remove these before meshing (docs/real-scans.md, \"Points in the air\")."
    },
    "k": {
      "type": "integer",
      "minimum": 1,
      "maximum": 1000,
      "default": 16,
      "description": "Neighbours (the point excluded) over which each point's mean distance (statistical) or its local spacing and plane (air, 3..64) is taken."
    },
    "spacing_ratio": {
      "type": "number",
      "minimum": 0,
      "default": 4.0,
      "description": "air: a point is sparse when its local spacing exceeds this many times the cloud's median (> 1; 0 removes nothing)."
    },
    "plane_tolerance": {
      "type": "number",
      "exclusiveMinimum": 0,
      "default": 0.1,
      "description": "air: a sparse point is on a surface when a plane through it and two of its k nearest holds half of them within this many of its local spacings (neighbours sampled over 3 times more densely than the point do not count), or within noise_tolerance times the scan's surface noise if that is more."
    },
    "noise_tolerance": {
      "type": "number",
      "minimum": 0,
      "default": 2.5,
      "description": "air: the plane test allows at least this many times the scan's surface noise (the median RMS distance of a point and its k nearest to their plane), so a sparse, noisy surface (the side of an object one far station saw) is not taken for points in the air; 0: plane_tolerance alone."
    },
    "seen_through": {
      "type": "boolean",
      "default": true,
      "description": "air: also remove the points another station saw through (points/seen_through.h): a person, a bird or a clump one station recorded and the others saw past (every sample of another station around the point's direction lies farther than the point by the margin below). Needs the scan's stations; a scan without them, or with one, loses none this way."
    },
    "seen_through_spacings": {
      "type": "number",
      "minimum": 0,
      "default": 3.0,
      "description": "air, seen_through: the margin around a point that another station must have seen past, at least this many of the point's local spacings ..."
    },
    "seen_through_range": {
      "type": "number",
      "minimum": 0,
      "default": 0.01,
      "description": "... and at least this fraction of its distance to that station (the registration error between stations and the noise stay within it)."
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

// method: air. Removes the points AirPoints marks.
Status RunAir(StageContext& ctx, int k) {
  PB_ASSIGN_OR_RETURN(const double spacing_ratio, NumberParam(ctx, kId, "spacing_ratio"));
  PB_ASSIGN_OR_RETURN(const double plane_tolerance, NumberParam(ctx, kId, "plane_tolerance"));
  PB_ASSIGN_OR_RETURN(const double noise_tolerance, NumberParam(ctx, kId, "noise_tolerance"));
  PB_ASSIGN_OR_RETURN(const bool seen_through, BoolParam(ctx, kId, "seen_through"));
  PB_ASSIGN_OR_RETURN(const double seen_spacings, NumberParam(ctx, kId, "seen_through_spacings"));
  PB_ASSIGN_OR_RETURN(const double seen_range, NumberParam(ctx, kId, "seen_through_range"));
  PB_ASSIGN_OR_RETURN(const std::string implementation, StringParam(ctx, kId, "implementation"));
  if (implementation != "own")
    return Status::Invalid(std::string(kId) + ": method 'air' has implementation 'own' only, got '" +
                           implementation + "'");
  PB_ASSIGN_OR_RETURN(const InputPoints in, ReadInputPoints(ctx, kId, 0.3));
  const PointCloud& input = in.cloud;
  PointCloud output;
  AirReport report;
  {
    PB_PHASE(ctx, "compute");
    Expected<PointCloud> kept = RemoveAirPoints(
        input,
        {.k = k, .spacing_ratio = spacing_ratio, .plane_tolerance = plane_tolerance,
         .noise_tolerance = noise_tolerance, .seen_through = seen_through,
         .seen = {.margin_spacings = seen_spacings, .margin_range = seen_range},
         .progress = [&ctx](double fraction) { ctx.progress(0.3 + 0.5 * fraction); }},
        ctx.threads(), &report);
    if (!kept.ok()) return kept.status().WithContext(std::string(kId) + ": " + in.path);
    output = std::move(*kept);
  }
  ctx.progress(0.8);
  const size_t removed = input.size() - output.size();
  ctx.counter("points_in", double(input.size()));
  ctx.counter("points_out", double(output.size()));
  ctx.counter("removed", double(removed));
  ctx.counter("noise_m", report.noise_m);
  ctx.counter("seen_through", double(report.seen_through));
  ctx.counter("seen_through_stations", double(report.seen_stations));
  ctx.counter("seen_through_decided", double(report.seen_decided));
  auto number = [](const char* format, double value) {
    char text[32];
    std::snprintf(text, sizeof text, format, value);
    return std::string(text);
  };
  const size_t sparse = removed - std::min(removed, report.seen_through);
  if (sparse > 0)
    ctx.warning(std::string(kId) + ": " + std::to_string(sparse) + " of " +
                std::to_string(input.size()) + " points are in the air (sparser than " + number("%g", spacing_ratio) +
                " x the median spacing, " + number("%.2f", report.median_spacing_m * 1000) +
                " mm, and on no surface) and are left out of the meshes");
  if (report.seen_through > 0)
    ctx.warning(std::string(kId) + ": " + std::to_string(report.seen_through) + " of " +
                std::to_string(input.size()) +
                " points are where another scanner station saw through (a person, a bird, a clump only one "
                "station recorded) and are left out of the meshes");
  const nlohmann::json meta = InputPointsMetaWith(
      ctx, {{"points", output.size()}, {"outliers_removed", removed}, {"outliers_method", "air"}});
  PB_RETURN_IF_ERROR(WriteOutputPoints(ctx, output, meta));
  ctx.progress(1.0);
  return Status::Ok();
}

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const int64_t k, IntegerParam(ctx, kId, "k", {1, 1000}));
  PB_ASSIGN_OR_RETURN(const std::string method, StringParam(ctx, kId, "method"));
  if (method == "air") {
    if (k < 3 || k > 64)
      return Status::Invalid(std::string(kId) + ": method 'air' takes k in 3..64, got " + std::to_string(k));
    return RunAir(ctx, int(k));
  }
  if (method != "statistical")
    return Status::Invalid(std::string(kId) + ": parameter 'method' must be 'statistical' or 'air', got '" + method +
                           "'");
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
  type.version = 5;  // 2: method air; 3: its plane test allows the scan's noise; 4: and what another station saw through;
                     // 5: the same points, each station reading only those within its reach (seen_through_decided: of those)
  type.summary = "Outlier removal: statistical (as PCL's StatisticalOutlierRemoval), or the points in the air";
  type.doc =
      "For every point, the mean distance to its `k` nearest other points (exact kd-tree "
      "search); points whose mean exceeds the cloud-wide mean of those distances plus "
      "`std_ratio` sample standard deviations are removed. Kept points keep all their "
      "attributes and their order. The result does not depend on the thread count. "
      "`implementation: pcl` runs PCL's StatisticalOutlierRemoval instead (pointbake-pcl.so, "
      "loaded on first use), for campaigns that compare implementations.\n\n"
      "`method: air` removes the points in the air instead (stages/geometry/points/strays.h, "
      "AirPoints): points whose local spacing over their `k` nearest exceeds `spacing_ratio` times "
      "the cloud's median and which lie on no plane with half of those neighbours (within "
      "`plane_tolerance` local spacings, or `noise_tolerance` times the scan's surface noise if "
      "that is more): dust, mixed returns, floaters, which screened Poisson otherwise wraps in a "
      "hull that the scan's own sparse points seem to support. A scan's far field, a floor at "
      "grazing angle, the edge of two sparse walls (sparse, on planes), the side of an object one "
      "far station saw (sparse and noisy) and a rough surface (dense) stay. With `seen_through` "
      "(default) and a scan of several stations, it also removes the points another station saw "
      "through (stages/geometry/points/seen_through.h): every sample of that station in the "
      "directions of a ball around the point (radius: `seen_through_spacings` local spacings, at "
      "least `seen_through_range` of its distance to the station) lies beyond the ball; a "
      "person walking past one station, a bird, a clump of dust returns, a mixed return "
      "another station saw behind. It warns with the counts when it removes any.\n\n"
      "Meta added: `points`, `outliers_removed`, `outliers_implementation`, "
      "`outliers_threshold_m` (meters; own implementation only); with `air`: `points`, "
      "`outliers_removed`, `outliers_method`. "
      "Counters: `points_in`, `points_out`, `removed`; with `air`, `noise_m` (the surface noise), "
      "`seen_through` (of the removed, the points another station saw through; they may "
      "also be sparse), `seen_through_stations` (the stations looked through: 0 for a scan without "
      "stations or with one) and `seen_through_decided` (the points whose surroundings another "
      "station sampled in every direction, so that it could tell).";
  type.params_schema = kSchema;
  type.inputs = {{"points", "points", "The points to clean.", false}};
  type.outputs = {{"points", "points", "The points that are not outliers.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
