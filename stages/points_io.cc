#include "stages/points_io.h"

#include <cmath>
#include <utility>

#include "base/env.h"
#include "stages/geometry/io/ply.h"
#include "stages/params.h"

namespace pb {

Expected<InputPoints> ReadInputPoints(StageContext& ctx, std::string_view stage_id,
                                      double progress_end) {
  InputPoints input;
  PB_ASSIGN_OR_RETURN(input.path, InputFilePath(ctx, stage_id, "points"));
  PB_PHASE(ctx, "io");
  PlyReadOptions options;
  options.progress = [&ctx, progress_end](double fraction) {
    ctx.progress(progress_end * fraction);
  };
  PB_ASSIGN_OR_RETURN(PlyPoints ply, ReadPlyPoints(input.path, options));
  input.cloud = std::move(ply.points);
  return input;
}

nlohmann::json InputPointsMetaWith(const StageContext& ctx, const nlohmann::json& changes) {
  nlohmann::json meta = ctx.input("points").meta;
  meta.update(changes);
  return meta;
}

Status CopyInputPoints(StageContext& ctx, const std::string& input_path, nlohmann::json meta) {
  {
    PB_PHASE(ctx, "io");
    PB_RETURN_IF_ERROR(
        Env::Default()->CopyFileAtomic(input_path, ctx.output_path("points", "points.ply")));
  }
  ctx.set_output_meta("points", std::move(meta));
  return Status::Ok();
}

Status WriteOutputPoints(StageContext& ctx, const PointCloud& cloud, nlohmann::json meta,
                         std::string_view phase) {
  {
    PB_PHASE(ctx, phase);
    PB_RETURN_IF_ERROR(WritePlyPoints(ctx.output_path("points", "points.ply"), cloud));
  }
  ctx.set_output_meta("points", std::move(meta));
  return Status::Ok();
}

double InputPointsSpacing(const StageContext& ctx) {
  const nlohmann::json& meta = ctx.input("points").meta;
  if (!meta.is_object() || !meta.contains("spacing_m") || !meta["spacing_m"].is_number()) return 0;
  const double spacing_m = meta["spacing_m"].get<double>();
  return spacing_m > 0 && std::isfinite(spacing_m) ? spacing_m : 0;
}

}  // namespace pb
