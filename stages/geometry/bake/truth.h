// How far a baked color map is from a synthetic scene's ground truth: the
// texture-space counterpart of metrics.geometry, used by the bake
// comparison test and bench/bake_picture.
#pragma once

#include <cstddef>

#include "base/status.h"
#include "stages/geometry/bake/bake.h"
#include "stages/geometry/synth/scene.h"

namespace pb {

struct TruthColorError {
  double mean_abs = 0;  // mean |baked - true albedo| over channels, 0..255
  size_t texels = 0;    // texels compared
};

// Over every texel whose centre lies inside a face of result.mesh: the
// baked color against 255 x the true albedo (SampleSurface) at the texel's
// 3-D position. Texels farther than `max_off_surface_m` from the true
// surface (Poisson's surface across openings) or in openings are skipped.
Expected<TruthColorError> ColorErrorAgainstTruth(const SynthScene& scene, const BakeResult& result,
                                                 double max_off_surface_m = 0.01);

}  // namespace pb
