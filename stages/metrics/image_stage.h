// metrics.image: PSNR, SSIM, MS-SSIM and FLIP of a frame set against a
// reference frame set (stages/geometry/image_metrics.h), as a table, plus the
// FLIP error maps.
#pragma once

#include "engine/stage.h"

namespace pb {

StageType ImageMetricsStage();

}  // namespace pb
