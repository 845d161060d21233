// points.smooth: moving-least-squares smoothing (stages/geometry/points/smooth.h,
// PCL's MovingLeastSquares in pointbake-pcl.so).
#include <string>

#include "stages/builtin.h"
#include "stages/geometry/points/smooth.h"
#include "stages/geometry/points/spacing.h"
#include "stages/params.h"
#include "stages/points_io.h"

namespace pb {
namespace {

constexpr const char* kId = "points.smooth";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "radius_spacings": {
      "type": "number",
      "minimum": 0,
      "maximum": 50,
      "default": 4,
      "description": "Neighbourhood radius in point spacings (the input's `spacing_m` meta, else the median nearest-neighbour distance measured here). Larger removes more noise and rounds more edges; 4 leaves about 50 points in each fit. 0 passes the points through unchanged (a campaign can then compare with and without smoothing, as mesh.poisson's trim 0). docs/implementations.md measures it."
    },
    "radius_m": {
      "type": "number",
      "exclusiveMinimum": 0,
      "description": "Neighbourhood radius in meters; when given, `radius_spacings` is ignored."
    },
    "polynomial_order": {
      "type": "integer",
      "minimum": 0,
      "maximum": 3,
      "default": 2,
      "description": "Order of the surface fitted around each point: 0 or 1 projects onto the local plane (flattens curved surface by its sagitta), 2 keeps curvature (PCL's default)."
    }
  }
})";

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const double radius_spacings, NumberParam(ctx, kId, "radius_spacings"));
  PB_ASSIGN_OR_RETURN(const int64_t order, IntegerParam(ctx, kId, "polynomial_order", {0, 3}));
  double radius_m = 0;
  if (ctx.params().contains("radius_m") && !ctx.params()["radius_m"].is_null()) {
    PB_ASSIGN_OR_RETURN(radius_m, NumberParam(ctx, kId, "radius_m"));
  }
  if (!(radius_spacings >= 0 && radius_spacings <= 50)) {
    return Status::Invalid(std::string(kId) + ": parameter 'radius_spacings' must be in [0, 50], got " +
                           std::to_string(radius_spacings));
  }
  if (radius_m <= 0 && radius_spacings == 0) {
    // Off: the input file, unchanged.
    PB_ASSIGN_OR_RETURN(const std::string path, InputFilePath(ctx, kId, "points"));
    PB_RETURN_IF_ERROR(CopyInputPoints(
        ctx, path, InputPointsMetaWith(ctx, {{"smooth", {{"radius_m", 0}}}})));
    ctx.progress(1.0);
    return Status::Ok();
  }
  PB_ASSIGN_OR_RETURN(const InputPoints input, ReadInputPoints(ctx, kId, 0.2));
  const PointCloud& cloud = input.cloud;
  double spacing_m = InputPointsSpacing(ctx);
  PointCloud output;
  SmoothReport report;
  {
    PB_PHASE(ctx, "compute");
    if (radius_m <= 0) {
      if (spacing_m <= 0) {
        SpacingOptions spacing_options;
        spacing_options.threads = ctx.threads();
        auto measured = MedianSpacing(cloud, spacing_options);
        if (!measured.ok()) return measured.status().WithContext(input.path);
        spacing_m = *measured;
      }
      radius_m = radius_spacings * spacing_m;
    }
    SmoothOptions options;
    options.radius_m = radius_m;
    options.polynomial_order = static_cast<int>(order);
    options.threads = ctx.threads();
    auto smoothed = SmoothMovingLeastSquares(cloud, options, &report);
    if (!smoothed.ok()) return smoothed.status().WithContext(std::string(kId) + ": " + input.path);
    output = std::move(*smoothed);
  }
  ctx.progress(0.8);
  ctx.counter("points", static_cast<double>(report.points));
  ctx.counter("mean_shift_mm", report.mean_shift_m * 1e3);
  ctx.counter("max_shift_mm", report.max_shift_m * 1e3);
  const nlohmann::json meta = InputPointsMetaWith(
      ctx, {{"points", output.size()},
            {"has_normals", false},
            {"smooth", {{"implementation", "PCL 1.13 MovingLeastSquares"},
                        {"radius_m", radius_m},
                        {"polynomial_order", order},
                        {"mean_shift_m", report.mean_shift_m},
                        {"max_shift_m", report.max_shift_m}}}});
  PB_RETURN_IF_ERROR(WriteOutputPoints(ctx, output, meta));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType SmoothStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Moving-least-squares smoothing of range noise (PCL MovingLeastSquares)";
  type.doc =
      "Moves every point onto a polynomial surface (order `polynomial_order`) fitted, with "
      "Gaussian weights, to the points within the radius around it (Alexa et al. 2003; PCL "
      "1.13's pcl::MovingLeastSquares, no upsampling). Run it on noisy scans before "
      "points.normals and meshing; the points keep their order, colors, intensities and "
      "stations, and lose their normals (estimate them afterwards). The radius is "
      "`radius_m`, or `radius_spacings` times the points' spacing; `radius_spacings: 0` "
      "passes the points through unchanged. Needs pointbake-pcl.so "
      "(built when libpcl-dev is installed), loaded on first use. docs/implementations.md "
      "measures what it does to the mesh and to point-transfer normal maps.\n\n"
      "Meta added: `smooth` (radius_m, polynomial_order, mean_shift_m, max_shift_m); "
      "`has_normals` false. Counters: `points`, `mean_shift_mm`, `max_shift_mm`.";
  type.params_schema = kSchema;
  type.inputs = {{"points", "points", "The points to smooth.", false}};
  type.outputs = {{"points", "points", "The same points, moved onto the fitted surface.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
