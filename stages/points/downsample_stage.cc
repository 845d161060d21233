// points.downsample: voxel-grid downsampling (stages/geometry/points/voxel_downsample.h).
#include "stages/geometry/points/voxel_downsample.h"
#include "stages/params.h"
#include "stages/points_io.h"
#include "stages/builtin.h"

namespace pb {
namespace {

constexpr const char* kId = "points.downsample";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "voxel": {
      "type": "number",
      "exclusiveMinimum": 0,
      "default": 0.01,
      "description": "Voxel edge length in meters. One output point per occupied voxel; e.g. 0.01 keeps about one point per square centimeter of surface."
    }
  }
})";

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const double voxel_m, NumberParam(ctx, kId, "voxel"));
  PB_ASSIGN_OR_RETURN(const InputPoints in, ReadInputPoints(ctx, kId, 0.4));
  const PointCloud& input = in.cloud;
  PointCloud output;
  {
    PB_PHASE(ctx, "compute");
    VoxelDownsampleOptions options;
    options.voxel_m = voxel_m;
    PB_ASSIGN_OR_RETURN(output, VoxelDownsample(input, options));
  }
  ctx.counter("points_in", static_cast<double>(input.size()));
  ctx.counter("points_out", static_cast<double>(output.size()));
  ctx.progress(0.8);
  PB_RETURN_IF_ERROR(WriteOutputPoints(ctx, output,
                                       {{"origin", output.origin},
                                        {"points", output.size()},
                                        {"has_normals", output.has_normals()},
                                        {"has_colors", output.has_colors()},
                                        {"voxel_m", voxel_m}}));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType DownsampleStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Voxel-grid downsampling: one averaged point per voxel";
  type.doc =
      "Replaces all points inside each cubic voxel of edge `voxel` meters by their mean: mean "
      "position, mean color (rounded), mean normal renormalized. The grid is aligned to "
      "absolute coordinates and output points are sorted by voxel, so the result is "
      "deterministic.\n\n"
      "Counters: `points_in`, `points_out`.";
  type.params_schema = kSchema;
  type.inputs = {{"points", "points", "The points to downsample.", false}};
  type.outputs = {{"points", "points", "One point per occupied voxel.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
