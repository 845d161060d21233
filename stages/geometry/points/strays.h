// Stray points: samples of no surface the scan saw as a surface. A laser
// scan or a photogrammetric cloud carries single returns in the air (a
// flying pixel at a depth edge, a reflection, dust) and small floating
// clusters of them; no mesh of the project keeps them (mesh.trim's support
// is local, mesh.clean drops specks), so an evaluation that draws them as
// the scan (render.splats) charges every model with their pixels.
//
// Definition: link every point to each of its k nearest other points that
// lies closer than `link_spacings` times the smaller of the two points' local
// spacings (spacing.h, LocalSpacing: the distance between neighbouring
// samples around a point); the points of a linked cluster of fewer than
// `min_cluster_points` points are strays. A lone point far from the surface
// links to nothing: its neighbours' spacing is small and it is far from
// them. A one-station scan's far field, sparser with range, links (its
// neighbours are as sparse); so do a scan's border (spacing about 1.4 times
// the interior's) and a thin wire of samples. Within a uniformly sampled
// surface the k-th neighbour lies at s sqrt(k / pi) = 1.6 s for k = 8, so
// `link_spacings` 2 links every k-NN pair there.
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

namespace pb {

struct StrayOptions {
  int k = 8;                       // neighbours linked per point, 1..64 (LocalSpacing's k)
  double link_spacings = 2.0;      // > 0
  size_t min_cluster_points = 50;  // 0: no point is a stray
};

// `index`: KnnIndex::Build over the cloud's positions; `spacing`: one local
// spacing per point of the index (LocalSpacing). Returns one flag per point,
// 1 for a stray. Status::Invalid for options out of range or a spacing of
// another length.
Expected<std::vector<uint8_t>> StrayPoints(const KnnIndex& index, std::span<const float> spacing,
                                           const StrayOptions& options);

}  // namespace pb
