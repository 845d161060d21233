// Rectangle packing for UV atlases: a skyline bottom-left packer (Jylänki,
// "A Thousand Ways to Pack the Bin", 2010, SKYLINE-BL) and the uniform scale
// search that makes all charts fill one square atlas.
//
// Units: chart extents in meters (any unit works), positions in texels.
#pragma once

#include <cstdint>
#include <vector>

#include "base/status.h"

namespace pb {

// A chart's axis-aligned extent after rotation, in meters.
struct ChartExtent {
  double width = 0;
  double height = 0;
};

struct PackResult {
  double texels_per_meter = 0;    // the one scale of every chart
  std::vector<int64_t> x_texels;  // lower-left corner of each chart's box
  std::vector<int64_t> y_texels;
  // 1: the chart is placed a quarter turn counter-clockwise (its box is
  // height x width).
  std::vector<char> turned;
  int attempts = 0;          // packings tried by the scale search
};

// Packs every chart, scaled by one factor s, into a size x size texel atlas:
// chart i occupies ceil(width_i * s) x ceil(height_i * s) texels from its
// corner (swapped when turned), at least `gutter_texels` from every other chart and from the
// border. s is the largest found by bisection (to 1/256 relative) for which the skyline packer fits
// everything; largest charts (by height) go first. Deterministic. Status::Invalid if no scale above
// 10^-5 of the area bound fits (far more charts than gutter-padded cells in the atlas).
Expected<PackResult> PackCharts(const std::vector<ChartExtent>& charts, int size_texels,
                                int gutter_texels);

}  // namespace pb
