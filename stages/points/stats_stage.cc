// points.stats: a one-row table describing a point cloud.
#include <cmath>

#include "stages/geometry/core/table.h"
#include "stages/points_io.h"
#include "stages/builtin.h"

namespace pb {
namespace {

constexpr const char* kId = "points.stats";

Table Describe(const PointCloud& points) {
  const size_t n = points.size();
  const Bounds bounds = AbsoluteBounds(points);
  // Sums of origin-relative floats in double, then the origin: exact enough
  // for any scan and independent of how far the scan is from (0,0,0).
  double sum[3] = {0, 0, 0};
  uint64_t color_sum[3] = {0, 0, 0};
  for (size_t i = 0; i < n; ++i) {
    for (int axis = 0; axis < 3; ++axis) sum[axis] += points.positions[3 * i + axis];
    if (points.has_colors()) {
      for (int c = 0; c < 3; ++c) color_sum[c] += points.colors[3 * i + c];
    }
  }
  Table table;
  table.columns = {"points",       "min_x_m",      "min_y_m",      "min_z_m",     "max_x_m",
                   "max_y_m",      "max_z_m",      "centroid_x_m", "centroid_y_m", "centroid_z_m",
                   "has_normals",  "has_colors",   "mean_red",     "mean_green",  "mean_blue"};
  std::vector<TableValue> row(table.columns.size());  // null unless set below
  row[0] = static_cast<int64_t>(n);
  if (n > 0) {
    for (int axis = 0; axis < 3; ++axis) {
      row[1 + axis] = bounds.min_m[axis];
      row[4 + axis] = bounds.max_m[axis];
      row[7 + axis] = points.origin[axis] + sum[axis] / static_cast<double>(n);
    }
  }
  row[10] = points.has_normals();
  row[11] = points.has_colors();
  if (points.has_colors() && n > 0) {
    for (int c = 0; c < 3; ++c) row[12 + c] = static_cast<double>(color_sum[c]) / static_cast<double>(n);
  }
  table.rows.push_back(std::move(row));
  return table;
}

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const InputPoints input, ReadInputPoints(ctx, kId, 0.8));
  const PointCloud& points = input.cloud;
  Table table;
  {
    PB_PHASE(ctx, "compute");
    table = Describe(points);
  }
  PB_RETURN_IF_ERROR(WriteTable(ctx.output_path("table", "table.json"), table));
  ctx.counter("points", static_cast<double>(points.size()));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType StatsStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Point count, bounds, centroid and mean color as a table";
  type.doc =
      "Describes a point cloud in a one-row table (table.json): `points`; the absolute "
      "bounding box `min_x_m` .. `max_z_m` and centroid `centroid_x_m` .. `centroid_z_m` in "
      "meters (origin added, double precision); `has_normals`, `has_colors`; and the mean "
      "color `mean_red`, `mean_green`, `mean_blue` on the 0..255 scale (null without colors). "
      "Bounds and centroid are null for an empty cloud.";
  type.params_schema = R"({"type": "object", "additionalProperties": false, "properties": {}})";
  type.inputs = {{"points", "points", "The points to describe.", false}};
  type.outputs = {{"table", "table", "One row of statistics.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
