// Raster packing of UV charts (the `conformal` method of atlas.h): charts
// are packed by their shape, not their bounding box, so that irregular
// charts nest into each other's concavities.
//
// At a trial scale s (texels per meter, the same for every chart), each
// chart is rasterized conservatively (every texel its triangles touch) into
// a bit mask of its integer box, ceil(width s) x ceil(height s) texels; the
// mask dilated by `gutter` texels (a square) must not meet any texel of a
// chart already placed and must lie inside the atlas, which keeps any two
// charts, and every chart and the border, at least `gutter` texels apart.
// Charts go largest first (3-D area), each at the position and quarter turn
// (0, 90, 180, 270 degrees counter-clockwise: rotations only, so nothing is
// mirrored) with the lowest top edge, then leftmost: a bottom-left fill on
// the texel grid, searched row by row through the free runs of each row
// (compare xatlas's bitmap packer and Lévy et al. 2002's "Tetris" packing
// with horizons; this keeps holes usable). The scale is searched by pairs
// of trial packings run side by side (each packing is sequential), aimed by
// a secant on the packed height, to 0.8 %; then the orders longest side
// first and shortest side first climb by 1.2 % steps while one fits. The
// At most 64 irregular charts (covering under 0.8 of their boxes) then
// also try, above the best scale, turns by multiples of 30, 15 or 45
// degrees besides the quarter turns (RasterPlacement::angle). The
// bounding boxes are also packed by pack.h's skyline; the larger of the
// scales wins (a few large rectangular charts, like a room's walls, pack
// better so).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "base/status.h"
#include "stages/geometry/uv/charts.h"

namespace pb {

struct RasterPlacement {
  int64_t x = 0, y = 0;  // lower-left corner of the turned integer box, texels
  int box_width = 0;     // the chart's integer box before turning, texels
  int box_height = 0;
  int quarter_turns = 0;  // 0..3, counter-clockwise
  // A turn by `angle` (radians, counter-clockwise, a fraction of a quarter
  // turn) before the quarter turns: chart point (u, v) becomes
  // (cos u - sin v - min_u, sin u + cos v - min_v), whose box is the one
  // above. 0 for the minimal rectangle's own orientation.
  double angle = 0, min_u = 0, min_v = 0;
};

struct RasterPackResult {
  double texels_per_meter = 0;
  std::vector<RasterPlacement> placements;  // one per chart
  int attempts = 0;                         // packings tried
  bool boxes = false;  // the box packing of pack.h won (placements are its boxes)
};

// Packs `charts` (flattened, min corner at the origin; isolated charts are
// one-texel right triangles whatever the scale) into a size x size atlas.
// Status::Invalid when even a vanishing scale does not fit (too many charts
// for the gutter). Deterministic (sequential placement; rasterization is
// parallel but per chart).
Expected<RasterPackResult> RasterPackCharts(const std::vector<FlatChart>& charts, int size_texels,
                                            int gutter_texels);

// Texel coordinates of chart point (u, v) (meters) under its placement at
// scale s; isolated charts map their corner k to the fixed triangle
// (0,0), (1,0), (0,1) by the caller.
std::array<double, 2> PlacedTexel(const RasterPlacement& placement, double s, double u, double v);

}  // namespace pb
