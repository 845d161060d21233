// Stray points (strays.h): clusters of the k-NN graph restricted to pairs
// closer than a multiple of their local spacings, found with union-find
// (core/union_find.h).
#include "stages/geometry/points/strays.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "stages/geometry/core/union_find.h"
#include "stages/geometry/core/vec3.h"
#include "stages/geometry/points/normals.h"

namespace pb {
namespace {

// AirPoints, and the local spacings over options.k of its first pass in
// `spacing` (left empty when spacing_ratio is 0: no pass ran), for the
// callers that look through the stations with the same spacings.
Expected<std::vector<uint8_t>> AirPointsAndSpacing(const KnnIndex& index, const AirOptions& options,
                                                   AirReport* report, std::vector<float>* spacing);

// AirPoints over `index` and, given the `cloud` the index was built over
// with two stations or more and options.seen_through, the points another
// station saw through too (SeenThroughPoints, with the spacings of the air's
// first pass): what RemoveAirPoints leaves out of the meshes and
// LocalSpacingAndStrays out of the scan's render, the same points for both.
Expected<std::vector<uint8_t>> AirAndSeenThrough(const KnnIndex& index, const AirOptions& options,
                                                 const PointCloud* cloud, AirReport* report);

}  // namespace

Expected<SpacingAndStrays> LocalSpacingAndStrays(const KnnIndex& index, const StrayOptions& options,
                                                 const PointCloud* cloud) {
  if (options.k < 1 || options.k > 64)
    return Status::Invalid("stray points: k must be in 1..64, got " + std::to_string(options.k));
  if (!(options.link_spacings > 0) || !std::isfinite(options.link_spacings))
    return Status::Invalid("stray points: link_spacings must be > 0");
  if (!(options.max_spacing_ratio >= 1) || !std::isfinite(options.max_spacing_ratio))
    return Status::Invalid("stray points: max_spacing_ratio must be >= 1");
  const size_t n = index.size(), k = size_t(options.k);
  if (n <= k)
    return Status::Invalid("local spacing: needs more than k = " + std::to_string(k) + " points, the cloud has " +
                           std::to_string(n));
  if (cloud && cloud->size() != n)
    return Status::Invalid("stray points: a cloud of " + std::to_string(cloud->size()) + " points for an index of " +
                           std::to_string(n));
  SpacingAndStrays result;
  result.spacing.resize(n);
  result.stray.assign(n, 0);
  // links[i * k + j]: first the j-th nearest neighbour of point i, then (below)
  // that neighbour if it links to i, else i itself.
  std::vector<uint32_t> links(n * k);
  // Walk the tree's slot order: neighbouring queries share cache lines.
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<Neighbor> neighbors(k);
    for (size_t slot = range.begin(); slot < range.end(); ++slot) {
      const uint32_t i = index.PointAtSlot(slot);
      const int found = index.QueryPoint(i, int(k), neighbors);  // found == k: n > k
      result.spacing[i] = SpacingOfKthNeighbour(neighbors[size_t(found - 1)].squared_distance_m2, int(k));
      for (size_t j = 0; j < k; ++j) links[size_t(i) * k + j] = neighbors[j].index;
    }
  });
  if (options.min_cluster_points > 0 && n > size_t(options.air.k)) {
    AirReport air_report;
    PB_ASSIGN_OR_RETURN(result.stray, AirAndSeenThrough(index, options.air, cloud, &air_report));
    result.air = air_report.air;
    result.seen_through = air_report.seen_through;
  }
  if (options.min_cluster_points <= 1) return result;
  const std::vector<float>& spacing = result.spacing;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t slot = range.begin(); slot < range.end(); ++slot) {
      const uint32_t i = index.PointAtSlot(slot);
      const std::array<float, 3> p = index.PositionAtSlot(slot);
      for (size_t j = 0; j < k; ++j) {
        uint32_t& link = links[size_t(i) * k + j];
        const std::array<float, 3> q = index.PositionAtSlot(index.SlotOf(link));
        // The squared distance as KnnIndex computes it (double from float).
        const double dx = double(q[0]) - double(p[0]), dy = double(q[1]) - double(p[1]),
                     dz = double(q[2]) - double(p[2]);
        const double lo = std::min(spacing[i], spacing[link]);
        const double hi = std::max(spacing[i], spacing[link]);
        const double reach = options.link_spacings * (hi <= options.max_spacing_ratio * lo ? hi : lo);
        if (!(dx * dx + dy * dy + dz * dz <= reach * reach)) link = i;
      }
    }
  });
  UnionFind clusters(n);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < k; ++j) clusters.Union(uint32_t(i), links[i * k + j]);
  for (size_t i = 0; i < n; ++i) result.stray[i] |= clusters.SizeOf(uint32_t(i)) < options.min_cluster_points;
  return result;
}

namespace {

// A neighbour whose local spacing times this is below a point's own is
// sampled too densely to be of the point's surface (StrayOptions'
// max_spacing_ratio default).
constexpr float kPeerSpacingRatio = 3.0f;

// Whether a plane through `p` (the origin) and two of `q`, or a line through
// `p` and one of `q`, holds at least `needed` of the points of `q` within
// `tolerance` of it, counting only the points `peer` marks.
bool OnAPlane(std::span<const vec3::V3> q, std::span<const uint8_t> peer, double tolerance, size_t needed) {
  using vec3::Cross, vec3::Dot, vec3::Norm;
  const size_t m = q.size();
  // A line through p and one of them holds a plane's worth: a wire, whose
  // samples span no plane.
  for (size_t a = 0; a < m; ++a) {
    const double la = Norm(q[a]);
    if (!peer[a] || !(la > 0)) continue;
    size_t held = 0;
    for (size_t c = 0; c < m; ++c) held += peer[c] && Norm(Cross(q[c], q[a])) <= tolerance * la;
    if (held >= needed) return true;
  }
  for (size_t a = 0; a < m; ++a)
    for (size_t b = a + 1; b < m; ++b) {
      if (!peer[a] || !peer[b]) continue;
      const vec3::V3 n = Cross(q[a], q[b]);
      const double length = Norm(n);
      // Two neighbours nearly in line with p span no plane.
      if (!(length > 0.1 * Norm(q[a]) * Norm(q[b]))) continue;
      size_t held = 0;
      for (size_t c = 0; c < m; ++c) held += peer[c] && std::abs(Dot(n, q[c])) <= tolerance * length;
      if (held >= needed) return true;
    }
  return false;
}

// The scan's noise off its surfaces: the median, over up to 20,000 points
// spread evenly through the tree's slot order, of the RMS distance of a
// point and its k nearest to their least-squares plane (the square root of
// the smallest eigenvalue of their covariance). Most points lie on smooth
// surface at a spacing where curvature adds little, so this is the range
// noise and roughness a plane test must allow (and registration error where
// stations overlap).
double SurfaceNoise(const KnnIndex& index, int k) {
  const size_t n = index.size(), stride = std::max<size_t>(1, n / 20000), samples = (n + stride - 1) / stride;
  std::vector<double> rms(samples);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, samples, 256), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<Neighbor> neighbors(static_cast<size_t>(k));
    std::vector<vec3::V3> offsets(static_cast<size_t>(k) + 1);
    for (size_t s = range.begin(); s < range.end(); ++s) {
      const size_t slot = s * stride;
      const int found = index.QueryPoint(index.PointAtSlot(slot), k, neighbors);
      // Offsets from the point, so the covariance keeps its digits far from
      // the origin (as normals.cc and surfels.cc).
      const std::array<float, 3> p = index.PositionAtSlot(slot);
      offsets[0] = {0, 0, 0};
      for (int j = 0; j < found; ++j) {
        const std::array<float, 3> q = index.PositionAtSlot(index.SlotOf(neighbors[size_t(j)].index));
        offsets[size_t(j) + 1] = {double(q[0]) - double(p[0]), double(q[1]) - double(p[1]),
                                  double(q[2]) - double(p[2])};
      }
      const size_t m = size_t(found) + 1;
      double mean[3] = {0, 0, 0};
      for (size_t j = 0; j < m; ++j)
        for (int a = 0; a < 3; ++a) mean[a] += offsets[j][size_t(a)] / double(m);
      double covariance[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
      for (size_t j = 0; j < m; ++j) {
        const double d[3] = {offsets[j][0] - mean[0], offsets[j][1] - mean[1], offsets[j][2] - mean[2]};
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) covariance[3 * a + b] += d[a] * d[b] / double(m);
      }
      double normal[3];
      rms[s] = std::sqrt(std::max(0.0, SmallestEigenvector(covariance, normal)));
    }
  });
  std::nth_element(rms.begin(), rms.begin() + ptrdiff_t(samples / 2), rms.end());
  return rms[samples / 2];
}

// One pass of AirPoints over the points of `index`, whose local spacings
// over k are `spacing`: marks `air` (per point of the index) where a point is
// sparser than `limit` and on no plane with its peers within the larger of
// plane_tolerance times its spacing and `noise_floor`.
void MarkAir(const KnnIndex& index, const AirOptions& options, std::span<const float> spacing, double limit,
             double noise_floor, std::vector<uint8_t>& air) {
  const size_t n = index.size(), k = size_t(options.k);
  // The plane test, on the sparse points only (a clean scan has few).
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<Neighbor> neighbors(k);
    std::vector<vec3::V3> q(k);
    std::vector<uint8_t> peer(k);
    for (size_t slot = range.begin(); slot < range.end(); ++slot) {
      const uint32_t i = index.PointAtSlot(slot);
      if (!(double(spacing[i]) > limit)) continue;
      const int found = index.QueryPoint(i, int(k), neighbors);
      const std::array<float, 3> p = index.PositionAtSlot(slot);
      for (int j = 0; j < found; ++j) {
        const std::array<float, 3> r = index.PositionAtSlot(index.SlotOf(neighbors[size_t(j)].index));
        q[size_t(j)] = {double(r[0]) - double(p[0]), double(r[1]) - double(p[1]), double(r[2]) - double(p[2])};
        // A neighbour sampled much more densely than the point is not of its
        // surface: a return in front of a scanned surface sees that surface
        // among its nearest, on planes through itself that cut it.
        peer[size_t(j)] = kPeerSpacingRatio * spacing[neighbors[size_t(j)].index] >= spacing[i];
      }
      const size_t needed = (size_t(found) + 1) / 2;
      air[i] = !OnAPlane(std::span(q).first(size_t(found)), std::span(peer).first(size_t(found)),
                         std::max(options.plane_tolerance * double(spacing[i]), noise_floor), needed);
    }
  });
}

Status CheckAirOptions(const AirOptions& options) {
  if (options.k < 3 || options.k > 64)
    return Status::Invalid("points in the air: k must be in 3..64, got " + std::to_string(options.k));
  if (!std::isfinite(options.spacing_ratio) || (options.spacing_ratio != 0 && !(options.spacing_ratio > 1)))
    return Status::Invalid("points in the air: spacing_ratio must be > 1 (or 0: off)");
  if (!(options.plane_tolerance > 0) || !std::isfinite(options.plane_tolerance))
    return Status::Invalid("points in the air: plane_tolerance must be > 0");
  if (!(options.noise_tolerance >= 0) || !std::isfinite(options.noise_tolerance))
    return Status::Invalid("points in the air: noise_tolerance must be >= 0");
  if (options.passes < 1 || options.passes > 10)
    return Status::Invalid("points in the air: passes must be in 1..10, got " + std::to_string(options.passes));
  return Status::Ok();
}

}  // namespace

Expected<std::vector<uint8_t>> AirPoints(const KnnIndex& index, const AirOptions& options, AirReport* report) {
  return AirPointsAndSpacing(index, options, report, nullptr);
}

namespace {

Expected<std::vector<uint8_t>> AirAndSeenThrough(const KnnIndex& index, const AirOptions& options,
                                                 const PointCloud* cloud, AirReport* report) {
  const bool look = cloud && options.seen_through && cloud->stations.size() >= 2;
  AirReport local;
  std::vector<float> spacing;
  // The passes take the first half of the progress when the stations are
  // looked through, which take the rest.
  AirOptions passes = options;
  if (look && options.progress) passes.progress = [&options](double f) { options.progress(0.5 * f); };
  PB_ASSIGN_OR_RETURN(std::vector<uint8_t> air, AirPointsAndSpacing(index, passes, &local, look ? &spacing : nullptr));
  if (look) {
    if (spacing.empty()) {  // spacing_ratio 0: the air ran no pass
      PB_ASSIGN_OR_RETURN(spacing, LocalSpacing(index, options.k));
    }
    SeenThroughReport seen_report;
    SeenThroughOptions seen_options = options.seen;
    seen_options.progress = nullptr;
    if (options.progress) seen_options.progress = [&options](double f) { options.progress(0.5 + 0.5 * f); };
    PB_ASSIGN_OR_RETURN(const std::vector<uint8_t> seen,
                        SeenThroughPoints(*cloud, spacing, seen_options, &seen_report));
    local.seen_through = seen_report.seen_through;
    local.seen_stations = seen_report.stations;
    local.seen_decided = seen_report.decided;
    local.air = 0;
    for (size_t i = 0; i < air.size(); ++i) {
      air[i] |= seen[i];
      local.air += air[i];
    }
  }
  if (report) *report = local;
  return air;
}

Expected<std::vector<uint8_t>> AirPointsAndSpacing(const KnnIndex& index, const AirOptions& options,
                                                   AirReport* report, std::vector<float>* first_spacing) {
  PB_RETURN_IF_ERROR(CheckAirOptions(options));
  const size_t n = index.size(), k = size_t(options.k);
  std::vector<uint8_t> air(n, 0);
  AirReport local;
  if (options.spacing_ratio == 0) {
    if (report) *report = local;
    return air;
  }
  if (n <= k)
    return Status::Invalid("points in the air: needs more than k = " + std::to_string(k) + " points, the cloud has " +
                           std::to_string(n));
  PB_ASSIGN_OR_RETURN(std::vector<float> spacing, LocalSpacing(index, int(k)));
  local.median_spacing_m = MedianLocalSpacing(spacing);
  local.noise_m = SurfaceNoise(index, int(k));
  const double limit = options.spacing_ratio * local.median_spacing_m;
  const double noise_floor = options.noise_tolerance * local.noise_m;
  MarkAir(index, options, spacing, limit, noise_floor, air);
  local.passes = 1;
  // The first pass (with the spacings and the noise) is half the work; the
  // later ones share the rest.
  const auto report_progress = [&](double f) {
    if (options.progress) options.progress(f);
  };
  report_progress(options.passes > 1 ? 0.5 : 1.0);
  // Later passes, without the points found: a return whose nearest were
  // other returns may have had a plane among them by chance.
  for (size_t found = size_t(std::count(air.begin(), air.end(), uint8_t{1}));
       found > 0 && local.passes < options.passes;) {
    std::vector<uint32_t> rest;
    std::vector<float> xyz;
    for (size_t slot = 0; slot < n; ++slot) {
      const uint32_t i = index.PointAtSlot(slot);
      if (air[i]) continue;
      rest.push_back(i);
      const std::array<float, 3> p = index.PositionAtSlot(slot);
      xyz.insert(xyz.end(), p.begin(), p.end());
    }
    if (rest.size() <= k) break;
    PB_ASSIGN_OR_RETURN(const KnnIndex sub, KnnIndex::Build(xyz));
    PB_ASSIGN_OR_RETURN(const std::vector<float> sub_spacing, LocalSpacing(sub, int(k)));
    std::vector<uint8_t> more(rest.size(), 0);
    MarkAir(sub, options, sub_spacing, limit, noise_floor, more);
    ++local.passes;
    report_progress(0.5 + 0.5 * double(local.passes - 1) / double(options.passes - 1));
    found = 0;
    for (size_t j = 0; j < rest.size(); ++j)
      if (more[j]) {
        air[rest[j]] = 1;
        ++found;
      }
  }
  report_progress(1.0);  // no more pass needed
  for (uint8_t a : air) local.air += a;
  if (report) *report = local;
  if (first_spacing) *first_spacing = std::move(spacing);
  return air;
}

}  // namespace

Expected<PointCloud> RemoveAirPoints(const PointCloud& cloud, const AirOptions& options, int threads,
                                     AirReport* report) {
  PB_RETURN_IF_ERROR(CheckAirOptions(options));
  PB_RETURN_IF_ERROR(Validate(cloud));
  PB_RETURN_IF_ERROR(CheckFinitePositions(cloud, "points in the air"));
  AirReport local;
  const bool look_through = options.seen_through && cloud.stations.size() >= 2;
  if ((options.spacing_ratio == 0 && !look_through) || cloud.size() <= size_t(options.k)) {
    if (report) *report = local;
    return cloud;
  }
  PB_ASSIGN_OR_RETURN(const KnnIndex index, KnnIndex::Build(cloud.positions));
  Expected<std::vector<uint8_t>> air = Status::Internal("not run");
  auto run = [&] { air = AirAndSeenThrough(index, options, &cloud, &local); };
  if (threads > 0) {
    tbb::task_arena(threads).execute(run);
  } else {
    run();
  }
  if (!air.ok()) return air.status();
  if (report) *report = local;
  if (local.air == 0) return cloud;
  std::vector<uint32_t> kept;
  kept.reserve(cloud.size() - local.air);
  for (size_t i = 0; i < cloud.size(); ++i)
    if (!(*air)[i]) kept.push_back(uint32_t(i));
  return SelectPoints(cloud, kept);
}

}  // namespace pb
