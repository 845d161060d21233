// The `points` stage family: point cloud -> point cloud (or a table about it).
#pragma once

#include "engine/stage.h"

namespace pb {

// points.downsample: voxel-grid averaging.
StageType DownsampleStage();
// points.stats: counts, bounds, centroid and mean color as a table.
StageType StatsStage();
// points.outliers: statistical outlier removal.
StageType OutliersStage();
// points.normals: k-NN PCA normals, oriented.
StageType NormalsStage();
// points.spacing: median nearest-neighbour distance into the meta.
StageType SpacingStage();

void RegisterPointsStages(StageRegistry& registry);

}  // namespace pb
