// `pointbake compare REF TEST [--map FLIP.png] [--json] [--ppd X]`: the image
// metrics of metrics.image (stages/geometry/metrics/image_metrics.h) for any two
// 8-bit images, e.g. a user's own renders.
#pragma once

#include "cli/cli.h"

namespace pb {

// Prints PSNR, SSIM (luma and RGB mean), MS-SSIM and FLIP as a table (or one
// JSON object with --json) on stdout; --map writes the FLIP error map as a
// magma-colored PNG. Errors go to stderr; exit 0 on success, 2 on bad input
// or usage.
CliCommand CompareCommand();

}  // namespace pb
