// The `points` artifact as stage adapters read and write it: one binary PLY
// file, points.ply (stages/geometry/io/ply.h), positions in meters relative to the
// cloud's origin, plus the artifact's JSON meta (origin, point count, spacing_m
// and whatever earlier stages added).
#pragma once

#include <string>
#include <string_view>

#include "base/status.h"
#include "engine/stage.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

struct InputPoints {
  std::string path;  // the input file, for error context
  PointCloud cloud;
};

// Reads the cloud of input port "points" inside an "io" phase, reporting the
// read as stage progress 0..`progress_end`. Errors name `stage_id` when the
// input is missing, else the file and place.
Expected<InputPoints> ReadInputPoints(StageContext& ctx, std::string_view stage_id,
                                      double progress_end);

// The meta of input "points" with the top-level keys of `changes` set over
// it: what a stage that transforms points passes on (origin, spacing_m and
// what earlier stages recorded survive unless changed).
nlohmann::json InputPointsMetaWith(const StageContext& ctx, const nlohmann::json& changes);

// The `spacing_m` the input "points" meta records (synth.scan,
// points.spacing), or 0 when it has none or it is not a positive finite
// number.
double InputPointsSpacing(const StageContext& ctx);

// Passes input "points" through unchanged as output "points" (a file copy,
// no re-encoding) with `meta`: for stages that only measure.
Status CopyInputPoints(StageContext& ctx, const std::string& input_path, nlohmann::json meta);

// Writes `cloud` as output "points" (points.ply) inside phase `phase`, then
// sets that output's meta.
Status WriteOutputPoints(StageContext& ctx, const PointCloud& cloud, nlohmann::json meta,
                         std::string_view phase = "io");

}  // namespace pb
