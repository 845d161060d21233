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
//
// Points in the air (AirPoints, below): a cloud of returns scattered through
// the space in front of or around the surface (dust, rain, a scanner's mixed
// returns off many edges, a photogrammetric reconstruction's floaters) is
// as sparse as each of its points: its points link to each other, and
// through those near the surface to it, so the clusters above keep them;
// screened Poisson wraps them in a hull, and their sparse spacing makes it
// look supported (mesh.trim). Such a cloud is what no surface is: sparse and
// on no plane. A point is in the air when its local spacing s (over its `k`
// nearest, spacing.h) exceeds `spacing_ratio` times the cloud's median local
// spacing AND no plane through it and two of its peers (nor a line through
// it and one: a wire) holds half of its k nearest within `plane_tolerance` x
// s, its peers being the neighbours not
// sampled over 3 times more densely than itself (a return in front of a
// scanned surface has that surface among its nearest, and a plane through
// the return and two surface samples holds a strip of them). Either test
// alone takes surface: a scan's far field and a floor seen at grazing angle
// are sparse but on a plane, a rough surface is on no plane but as dense as
// the rest. The edge where two sparse walls meet has half its neighbours on
// each wall; at most the apex of a sparse corner of three walls goes. Up to
// `passes` passes, each without the points found so far (a return whose
// nearest were other returns may have had a plane among them by chance).
// The plane's tolerance is at least `noise_tolerance` times the scan's
// surface noise (the median RMS distance of a point and its k nearest to
// their plane): at 0.1 spacing alone, the side of an object that only one
// far station saw, sparse and as noisy as the rest, failed the plane test
// (a statue stand-in: 861 of such points, 40 with the allowance; the
// returns in front of it are found as before).
// Points another station saw through (seen_through.h: a person or a clump
// of returns one station recorded, as dense as the surface) are in the air
// too where the cloud's stations are known: RemoveAirPoints, and
// LocalSpacingAndStrays given the cloud.
// Measured (docs/real-scans.md, "Points in the air"): none on the synthetic
// presets, the bunny's scans and the statue stand-in; a few dozen sparse
// returns of the pump and the office frame; nearly all of the returns
// scattered in front of the statue stand-in.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/point_cloud.h"
#include "stages/geometry/points/knn.h"
#include "stages/geometry/points/seen_through.h"
#include "stages/geometry/points/spacing.h"

namespace pb {

struct AirOptions {
  int k = 16;                    // neighbours, 3..64
  double spacing_ratio = 4.0;    // > 1; 0: no point is in the air
  double plane_tolerance = 0.1;   // > 0, in the point's local spacings
  int passes = 3;                 // 1..10: again without the points found, while any are
  double noise_tolerance = 2.5;   // >= 0: the plane test allows at least this many times the
                                  // scan's surface noise (SurfaceNoise in strays.cc); 0: not
  // Points another station saw through (seen_through.h: a person, a bird, a
  // floating clump one station recorded and the others saw past) are in the
  // air too, whatever their density; needs the cloud's stations (the
  // functions given only a KnnIndex cannot tell).
  bool seen_through = true;
  SeenThroughOptions seen;  // its `progress` is not called: `progress` below covers it
  // Called from the calling thread after each pass and each station looked
  // through, with the fraction done, in [0, 1] (RemoveAirPoints,
  // LocalSpacingAndStrays).
  std::function<void(double fraction)> progress;
};

struct StrayOptions {
  int k = 8;                       // neighbours linked per point, 1..64 (LocalSpacing's k)
  double link_spacings = 2.0;      // > 0
  double max_spacing_ratio = 3.0;  // >= 1; 1: the smaller spacing always
  size_t min_cluster_points = 50;  // 0: no point is a stray
  AirOptions air;                  // points in the air are strays too (air.spacing_ratio 0: not;
                                   // min_cluster_points 0: no stray at all)
};

struct SpacingAndStrays {
  std::vector<float> spacing;  // per point: LocalSpacing(index, options.k), the same values
  std::vector<uint8_t> stray;  // per point: 1 for a stray, else 0
  size_t air = 0;              // of the strays, points in the air (AirPoints or seen through)
  size_t seen_through = 0;     // of those, points another station saw through (seen_through.h)
};


struct AirReport {
  size_t air = 0;                  // points in the air (sparse and on no surface, or seen through)
  size_t seen_through = 0;         // of those, points another station saw through (seen_through.h)
  size_t seen_stations = 0;        // stations looked through (SeenThroughReport::stations)
  size_t seen_decided = 0;         // points some other station's samples answered (::decided)
  double median_spacing_m = 0;     // the cloud's median local spacing over k
  double noise_m = 0;              // the scan's surface noise (RMS off a plane over k + 1 points)
  int passes = 0;                  // passes run
};

// Per point of `index`, 1 when it is in the air (above), else 0.
// Status::Invalid for options out of range or at most k points.
Expected<std::vector<uint8_t>> AirPoints(const KnnIndex& index, const AirOptions& options,
                                         AirReport* report = nullptr);

// The cloud without its points in the air, and without the points another
// station saw through when options.seen_through and the cloud has stations;
// kept points keep every attribute
// and their order (as RemoveStatisticalOutliers, outliers.h). A cloud of at
// most k points, or spacing_ratio 0 with nothing to look through (no
// seen_through, or fewer than two stations), comes back as it is. Status::Invalid
// for options out of range, inconsistent attributes or a non-finite
// coordinate. `threads` 0: TBB's default.
Expected<PointCloud> RemoveAirPoints(const PointCloud& cloud, const AirOptions& options, int threads = 0,
                                     AirReport* report = nullptr);

// The local spacing and the strays of the points of `index` (KnnIndex::Build
// over the cloud's positions), from one k-NN query per point: a caller that
// needs both (render.splats, metrics.geometry) does not query twice.
// `cloud`: the cloud the index was built over, for its stations: the points
// another station saw through are strays too (options.air.seen_through and
// min_cluster_points > 0), as RemoveAirPoints leaves them out of the meshes
// (the same points: their spacings over options.air.k, as it takes them);
// nullptr or a cloud without stations: none is.
// Status::Invalid for options out of range or at most k points (as
// LocalSpacing), or a cloud of another size than the index.
Expected<SpacingAndStrays> LocalSpacingAndStrays(const KnnIndex& index, const StrayOptions& options,
                                                 const PointCloud* cloud = nullptr);

}  // namespace pb
