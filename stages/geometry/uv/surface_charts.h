// Charts that follow curved surfaces, for the `conformal` method of atlas.h
// (used by atlas.cc; the public API is atlas.h).
//
// 1. Growth. Seeds are taken flattest first (smallest largest dihedral angle
//    to an edge neighbour, then face order); a chart grows over manifold edges
//    in order of how close a face's normal is to the chart's running
//    area-weighted mean normal (a priority queue, so a chart spreads over
//    smooth surface first and meets its neighbours at creases), taking faces
//    within `cone_deg` of that mean and never crossing an edge whose dihedral
//    angle exceeds `cone_deg` (a crease is a seam).
// 2. Smoothing and merging. A face with two or three neighbours in one other
//    chart moves there if its normal is within 1.5 cone_deg of that chart's
//    mean (greedy growth leaves saw-tooth borders on noisy meshes). A chart of
//    fewer than 16 faces joins the neighbouring chart it shares the longest
//    boundary with, if its faces are within 1.5 cone_deg of the union's mean
//    normal (growth leaves such scraps between charts). Neither crosses an
//    edge folding more than 75 deg (growth stops at cone_deg; single faces
//    of a noisy scan often fold 45 deg, which merging may cross).
// 3. Flattening. A chart whose projection on the plane of its mean normal
//    stretches it by at most 1/50 of the allowed excess (L2 <= 1.0006 by
//    default: flat or relief walls) keeps that projection (exact rectangles
//    for walls, and no solve); any other is flattened by LSCM (conformal.h),
//    or split first if it has more than 10,000 vertices.
// 4. Validation and splitting. A flattened chart must have every face
//    counter-clockwise, no two faces overlapping, and its L2 stretch
//    (Sander et al. 2001, normalized on the chart) at most
//    `max_chart_stretch`; otherwise it is split in two by a breadth-first
//    race from two far-apart faces (geodesic halves) and each half is
//    flattened again, each half as a task of its own (no rounds). A
//    one-face chart is always valid.
//    Afterwards a chart still under 16 faces joins a neighbour (longest
//    non-crease border first, three tried) if the union flattens validly:
//    in order, each seeing the joins before it, the attempts made in
//    parallel and speculatively (a stale one is made again).
// 5. Each chart is scaled so that its UV area equals its 3-D area (one texel
//    density for the whole atlas) and rotated to its minimal-area rectangle.
//
// Compare Lévy et al. 2002 (LSCM, charts by feature detection and growth),
// Sander et al. 2001 (charts merged by planarity and compactness) and
// Zhou, Snyder, Guo, Shum 2004 (Iso-charts, stretch-driven splitting); the
// cone growth is Blender's Smart UV Project criterion applied to connected
// growth, with the conformal map instead of a planar projection.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "stages/geometry/core/mesh.h"
#include "stages/geometry/uv/charts.h"

namespace pb {

struct SurfaceChartOptions {
  double cone_deg = 45;             // growth: face normal vs chart mean normal, (0, 90)
  double max_chart_stretch = 1.03;  // split a chart whose L2 stretch exceeds this (> 1)
  // Faces (by id, increasing) that become isolated one-face charts and that
  // no chart grows into (slivers, see atlas.h).
  std::vector<uint32_t> isolated_faces;
};

// The charts of `mesh` (valid), flattened, scaled to 3-D area and rotated
// to their minimal rectangle; isolated faces last, as FlatChart::isolated.
// Every face is in exactly one chart. Threads through TBB; the result does
// not depend on the thread count.
std::vector<FlatChart> MakeSurfaceCharts(const Mesh& mesh, const SurfaceChartOptions& options,
                                         const std::function<void(double)>& progress);

// L2 texture stretch of a flattened chart normalized on its own area (1 = an
// isometry up to scale; Sander et al. 2001, see atlas.h), over faces with
// positive 3-D and UV area. `mesh` gives the 3-D positions.
double ChartStretchL2(const Mesh& mesh, const FlatChart& chart);

}  // namespace pb
