// Stray points: samples of no surface the scan saw as a surface. A laser
// scan or a photogrammetric cloud carries single returns in the air (a
// flying pixel at a depth edge, a reflection, dust) and small floating
// clusters of them; no mesh of the project keeps them (mesh.trim's support
// is local, mesh.clean drops specks), so an evaluation that draws them as
// the scan (render.splats) charges every model with their pixels.
//
// Definition: link every point to each of its k nearest other points that
// lies within `link_spacings` times the two points' local spacing (spacing.h,
// LocalSpacing: the distance between neighbouring samples around a point):
// the larger of the two spacings when they differ by at most
// `max_spacing_ratio`, else the smaller; the points of a linked cluster of
// fewer than `min_cluster_points` points are strays. A lone point far from
// the surface links to nothing: its own spacing is its distance to the
// surface, many times its neighbours', and it is far from them. A
// one-station scan's far field, sparser with range, links (its neighbours
// are as sparse); so do a scan's border (spacing about 1.4 times the
// interior's), a thin wire of samples, and a sparse row next to denser
// sampling (the top of a wall seen at grazing angle beside its face; the
// ceiling above a tripod scanner, where its scan lines converge), which the
// smaller spacing alone cut off as strays (synthetic vault 768 of 10^6
// points, tower 1,093; with the ratio 28 and 48). Within a uniformly sampled
// surface the k-th neighbour lies at s sqrt(k / pi) = 1.6 s for k = 8, so
// `link_spacings` 2 links every k-NN pair there. A point within about
// link_spacings * max_spacing_ratio / (k-NN spacing factor 1.6) = 4 of its
// neighbours' spacings from them links through the ratio: that close, a
// return is noise on the surface rather than a stray.
//
// Deterministic (union-find over the k-NN pairs; the cluster sizes do not
// depend on the order); the k-NN queries run on TBB's threads (run inside a
// tbb::task_arena to limit them).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "base/status.h"
#include "stages/geometry/points/knn.h"
#include "stages/geometry/points/spacing.h"

namespace pb {

struct StrayOptions {
  int k = 8;                       // neighbours linked per point, 1..64 (LocalSpacing's k)
  double link_spacings = 2.0;      // > 0
  double max_spacing_ratio = 3.0;  // >= 1; 1: the smaller spacing always
  size_t min_cluster_points = 50;  // 0: no point is a stray
};

struct SpacingAndStrays {
  std::vector<float> spacing;  // per point: LocalSpacing(index, options.k), the same values
  std::vector<uint8_t> stray;  // per point: 1 for a stray, else 0
};

// The local spacing and the strays of the points of `index` (KnnIndex::Build
// over the cloud's positions), from one k-NN query per point: a caller that
// needs both (render.splats, metrics.geometry) does not query twice.
// Status::Invalid for options out of range or at most k points (as
// LocalSpacing).
Expected<SpacingAndStrays> LocalSpacingAndStrays(const KnnIndex& index, const StrayOptions& options);

}  // namespace pb
