// FindLostStation (lost_station.h).
#include "stages/geometry/points/lost_station.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <cstdio>
#include <utility>
#include <vector>

#include "stages/geometry/points/knn.h"
#include "stages/geometry/points/spacing.h"

namespace pb {
namespace {

constexpr int kNeighbours = 16;        // of a sample point: its spacing and normal
constexpr double kLeastCosine = 0.05;  // of the incidence and elevation, in the misfit
constexpr int kClearanceNeighbours = 8;  // the clearance is to the 8th nearest point
constexpr int kStarts = 6;             // lattice places the pattern search starts from
constexpr double kNearlyAsGood = 1.25;  // misfit, relative to the best's
constexpr double kAsBlocked = 0.03;     // of the lines of sight, more than the best's
constexpr double kPadding = 0.5;        // of the box's longest side, each way
constexpr double kMarginVoxels = 3;    // a line of sight stops this short of its point,
constexpr double kMarginShare = 0.1;   // or this share of its length if longer

using Vec = std::array<double, 3>;

double Dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

Eigen::Vector3d PositionOf(const float* positions, uint32_t i) {
  return {positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]};
}

double Distance(const Vec& a, const Vec& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

class SightGrid {
 public:
  SightGrid(const PointCloud& cloud, const Bounds& box, double voxel) : voxel_(voxel) {
    for (int a = 0; a < 3; ++a) {
      lo_[a] = box.min_m[a];
      dims_[a] = std::max(1, int(std::ceil((box.max_m[a] - box.min_m[a]) / voxel)));
    }
    occupied_.assign(size_t(dims_[0]) * dims_[1] * dims_[2], 0);
    const float* p = cloud.positions.data();
    for (size_t i = 0; i < cloud.size(); ++i) {
      int c[3];
      if (CellOf(p[3 * i], p[3 * i + 1], p[3 * i + 2], c)) occupied_[Index(c)] = 1;
    }
    // A lone occupied voxel (no occupied one of its 26 neighbours) hides
    // nothing: a return in the air, not a surface. 2 % of the pump's points
    // strewn over its box blocked 18 % of the lines of sight from its station.
    std::vector<uint8_t> lone(occupied_.size(), 0);
    for (int z = 0; z < dims_[2]; ++z)
      for (int y = 0; y < dims_[1]; ++y)
        for (int x = 0; x < dims_[0]; ++x) {
          const int c[3] = {x, y, z};
          if (occupied_[Index(c)] && Neighbours(c) == 0) lone[Index(c)] = 1;
        }
    for (size_t v = 0; v < occupied_.size(); ++v)
      if (lone[v]) occupied_[v] = 0;
  }

  double voxel() const { return voxel_; }

  // Whether the place's voxel or one of its 26 neighbours is occupied.
  bool Crowded(const Vec& q) const {
    int c[3];
    return CellOf(q[0], q[1], q[2], c) && (occupied_[Index(c)] || Neighbours(c) > 0);
  }

  // Whether the line of sight from `from` to `to` enters an occupied voxel
  // before the margin short of `to`.
  bool Blocked(const Vec& from, const float* to) const {
    const double d[3] = {to[0] - from[0], to[1] - from[1], to[2] - from[2]};
    const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const double end = length - std::max(kMarginVoxels * voxel_, kMarginShare * length);
    const double step = 0.5 * voxel_;
    for (double t = voxel_; t < end; t += step) {
      int c[3];
      const double f = t / length;
      if (CellOf(from[0] + f * d[0], from[1] + f * d[1], from[2] + f * d[2], c) && occupied_[Index(c)]) return true;
    }
    return false;
  }

 private:
  // Occupied voxels among the 26 around `c`.
  int Neighbours(const int c[3]) const {
    int count = 0;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int n[3] = {c[0] + dx, c[1] + dy, c[2] + dz};
          if ((dx == 0 && dy == 0 && dz == 0) || n[0] < 0 || n[1] < 0 || n[2] < 0 || n[0] >= dims_[0] ||
              n[1] >= dims_[1] || n[2] >= dims_[2])
            continue;
          count += occupied_[Index(n)];
        }
    return count;
  }
  bool CellOf(double x, double y, double z, int c[3]) const {
    const double q[3] = {x, y, z};
    for (int a = 0; a < 3; ++a) {
      const double f = (q[a] - lo_[a]) / voxel_;
      if (!(f >= 0) || f >= dims_[a]) return false;
      c[a] = int(f);
    }
    return true;
  }
  size_t Index(const int c[3]) const { return (size_t(c[2]) * dims_[1] + c[1]) * dims_[0] + c[0]; }

  double lo_[3] = {0, 0, 0};
  double voxel_ = 1;
  int dims_[3] = {1, 1, 1};
  std::vector<uint8_t> occupied_;
};

// The median of |v - median(v)| (upper middles); `v` is not empty.
double MedianAbsoluteDeviation(std::vector<double> v) {
  const size_t middle = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + middle, v.end());
  const double median = v[middle];
  for (double& x : v) x = std::fabs(x - median);
  std::nth_element(v.begin(), v.begin() + middle, v.end());
  return v[middle];
}

std::string Format(const char* format, auto... args) {
  char buf[512];
  std::snprintf(buf, sizeof buf, format, args...);
  return buf;
}

}  // namespace

Expected<LostStation> FindLostStation(const PointCloud& cloud, const LostStationOptions& options,
                                      const KnnIndex* points_index) {
  const size_t n = cloud.size();
  if (n < 100) return Status::Invalid("lost station: the cloud has fewer than 100 points");
  if (options.sample < 16 || options.grid_side < 8 || options.lattice < 2 || !(options.max_blocked >= 0) ||
      !(options.max_spread > 0) || !(options.min_clearance_m >= 0) || !std::isfinite(options.min_explained) ||
      !std::isfinite(Dot(options.up, options.up)))
    return Status::Invalid("lost station: an option is out of range");
  std::optional<KnnIndex> own_index;
  if (points_index == nullptr) {
    Expected<KnnIndex> built = KnnIndex::Build(cloud.positions);  // also rejects non-finite coordinates
    if (!built.ok()) return built.status();
    own_index = std::move(*built);
  }
  const KnnIndex* index = points_index != nullptr ? points_index : &*own_index;

  // The box: the points' robust box padded by half its longest side each
  // way (a wall scanned from across a street whose near side the scan lacks).
  Bounds box = RobustLocalBounds(cloud, 0.001);
  double extent = 0;
  for (int a = 0; a < 3; ++a) extent = std::max(extent, box.max_m[a] - box.min_m[a]);
  if (!(extent > 0)) return Status::Invalid("lost station: all the points lie at one place");
  for (int a = 0; a < 3; ++a) {
    box.min_m[a] -= kPadding * extent;
    box.max_m[a] += kPadding * extent;
  }
  const double padded = (1 + 2 * kPadding) * extent;

  // The sample: each point's local spacing (LocalSpacing's formula at k =
  // kNeighbours) and unoriented normal (the PCA of the same neighbours).
  const float* positions = cloud.positions.data();
  const size_t count = std::min(options.sample, n);
  std::vector<uint32_t> sample(count);
  for (size_t j = 0; j < count; ++j) sample[j] = uint32_t(j * n / count);
  std::vector<double> log_spacing(count), nearest(count);
  std::vector<Vec> normal(count);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 64), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<Neighbor> near(kNeighbours);
    for (size_t j = range.begin(); j < range.end(); ++j) {
      const int found = index->QueryPoint(sample[j], kNeighbours, near);  // n >= 100 > kNeighbours
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int k = 0; k < found; ++k) mean += PositionOf(positions, near[k].index);
      mean /= found;
      Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
      for (int k = 0; k < found; ++k) {
        const Eigen::Vector3d d = PositionOf(positions, near[k].index) - mean;
        covariance += d * d.transpose();
      }
      const Eigen::Vector3d e = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvectors().col(0);
      normal[j] = {e[0], e[1], e[2]};
      nearest[j] = std::sqrt(near[0].squared_distance_m2);
      // The k-th nearest's distance in the tangent plane: range noise as
      // large as the spacing (a dense scan) would otherwise inflate it. The
      // synthetic facade from one station at 5 * 10^6 points (2 mm noise,
      // spacing below it near the station) was found 0.36 m off with the
      // distance in space, 0.09 m with this.
      double farthest = 0;
      const Eigen::Vector3d at = PositionOf(positions, sample[j]);
      for (int k = 0; k < found; ++k) {
        const Eigen::Vector3d d = PositionOf(positions, near[k].index) - at;
        const double along = d.dot(e);
        farthest = std::max(farthest, d.squaredNorm() - along * along);
      }
      log_spacing[j] = std::log(SpacingOfKthNeighbour(farthest, kNeighbours) + 1e-12);
    }
  });
  std::vector<double> sorted = nearest;
  std::nth_element(sorted.begin(), sorted.begin() + count / 2, sorted.end());
  const SightGrid grid(cloud, box, std::max(padded / options.grid_side, sorted[count / 2]));

  // The misfit of a scanner at `place`: the median absolute deviation of
  // log(spacing) - log(r) + log(cos incidence) / 2 - log(cos elevation) / 2
  // over the sample (clamped at cosines of 0.05): a scanner's sweep sends a
  // ray every angular step in azimuth and elevation, so a surface r away,
  // at an incidence, at an elevation whose azimuth steps close up toward
  // the zenith, is sampled every r * sqrt(cos elevation / cos incidence)
  // steps. Without the elevation the synthetic stations came out 0.3-0.7 m
  // low or high; with it within 0.03-0.18 m.
  auto misfit = [&](const Vec& place, const Vec& up) {
    std::vector<double> residual(count);
    for (size_t j = 0; j < count; ++j) {
      const float* p = &positions[3 * sample[j]];
      const Vec d = {p[0] - place[0], p[1] - place[1], p[2] - place[2]};
      const double r = std::sqrt(Dot(d, d)) + 1e-12;
      const double incidence = std::max(kLeastCosine, std::fabs(Dot(d, normal[j])) / r);
      const double height = Dot(d, up) / r;
      const double level = std::max(kLeastCosine, std::sqrt(std::max(0.0, 1.0 - height * height)));
      residual[j] = log_spacing[j] - std::log(r) + 0.5 * std::log(incidence) - 0.5 * std::log(level);
    }
    return MedianAbsoluteDeviation(std::move(residual));
  };
  // The share of `rays` lines of sight from `place`, to sample points spread
  // over the sample, that cross surface.
  auto blocked = [&](const Vec& place, size_t rays) {
    size_t hits = 0;
    for (size_t r = 0; r < rays; ++r) hits += grid.Blocked(place, &positions[3 * sample[r * count / rays]]);
    return double(hits) / double(rays);
  };

  // The lattice.
  const int m = options.lattice;
  const size_t coarse_rays = std::min<size_t>(count, 512);
  const double cell = padded / m;
  std::vector<Vec> places;
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        const Vec q = {box.min_m[0] + (i + 0.5) * (box.max_m[0] - box.min_m[0]) / m,
                       box.min_m[1] + (j + 0.5) * (box.max_m[1] - box.min_m[1]) / m,
                       box.min_m[2] + (k + 0.5) * (box.max_m[2] - box.min_m[2]) / m};
        if (!grid.Crowded(q)) places.push_back(q);
      }
  // Every lattice place's blocked share (a few of the sample's lines of
  // sight); the search keeps to places that see nearly all points.
  std::vector<double> share(places.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, places.size(), 4), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t p = range.begin(); p < range.end(); ++p) share[p] = blocked(places[p], coarse_rays);
  });
  std::vector<size_t> seeing;
  for (size_t p = 0; p < places.size(); ++p)
    if (share[p] <= options.max_blocked) seeing.push_back(p);
  if (seeing.empty()) {
    LostStation result;
    size_t least = 0;
    for (size_t p = 1; p < places.size(); ++p) least = share[p] < share[least] ? p : least;
    result.blocked_share = places.empty() ? 1.0 : share[least];
    result.verdict = "no single place sees every point";
    result.figures = Format("from the best place %.0f %% of the lines of sight cross other surface",
                            100 * result.blocked_share);
    return result;
  }
  const double variation = MedianAbsoluteDeviation(log_spacing);

  // The search with the scanner's axis `up` (unit length).
  auto search = [&](const Vec& up) {
    std::vector<double> fit(places.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, seeing.size(), 4), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t k = range.begin(); k < range.end(); ++k) fit[seeing[k]] = misfit(places[seeing[k]], up);
    });
    std::vector<size_t> order = seeing;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return fit[a] < fit[b]; });
    LostStation result;
    result.up = up;
    // Pattern search from the best few, on the misfit, through places that
    // still see nearly every point (every sample ray). The starts lie apart
    // (farther than the spread allowed), so that two places that fit alike, a
    // wall's two sides, are both refined.
    std::vector<Vec> start;
    for (size_t p : order) {
      bool apart = true;
      for (const Vec& q : start) apart = apart && Distance(places[p], q) > options.max_spread * extent;
      if (apart) start.push_back(places[p]);
      if (start.size() == size_t(kStarts)) break;
    }
    const int starts = int(start.size());
    std::vector<std::pair<double, Vec>> refined(starts);
    tbb::parallel_for(0, starts, [&](int s) {
      Vec at = start[s];
      double best = misfit(at, up);
      for (double step = cell / 2; step >= grid.voxel(); step /= 2) {
        for (bool moved = true; moved;) {
          moved = false;
          for (int a = 0; a < 3 && !moved; ++a)
            for (double sign : {-1.0, 1.0}) {
              Vec next = at;
              next[a] += sign * step;
              // Within the box: on a flat patch the misfit falls without end
              // as the place goes away.
              if (!(next[a] >= box.min_m[a] && next[a] <= box.max_m[a]) || grid.Crowded(next)) continue;
              const double value = misfit(next, up);
              if (value < best && blocked(next, count) <= options.max_blocked) {
                best = value, at = next, moved = true;
                break;
              }
            }
        }
      }
      refined[s] = {best, at};
    });
    std::stable_sort(refined.begin(), refined.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const Vec at = refined[0].second;
    result.misfit = refined[0].first;
    result.blocked_share = blocked(at, count);
    for (int a = 0; a < 3; ++a) result.position[a] = at[a] + cloud.origin[a];

    // Places nearly as good, by both rules: how far they spread. Below the
    // sculpture's ground its mirror image fits the sampling within 1.25x,
    // but the ground hides a tenth of the points from it (the station: 0.6 %).
    double spread = 0;
    for (const auto& [value, place] : refined)
      if (value <= kNearlyAsGood * result.misfit && blocked(place, count) <= result.blocked_share + kAsBlocked)
        spread = std::max(spread, Distance(place, at));
    result.spread = spread / extent;

    // Clearance: to the kClearanceNeighbours-th nearest point, so that a
    // return in the air beside the scanner does not count.
    {
      const float q[3] = {float(at[0]), float(at[1]), float(at[2])};
      std::vector<Neighbor> nearest(kClearanceNeighbours);
      const int found = index->Query(q, kClearanceNeighbours, nearest);
      result.clearance_m = std::sqrt(nearest[size_t(found - 1)].squared_distance_m2);
    }
    // How much the spacing varies over the sample (the same median absolute
    // deviation, of log(spacing) alone), and the share of it the place explains.
    result.explained = variation > 0 ? std::max(0.0, 1.0 - result.misfit / variation) : 0.0;

    result.figures =
        Format("sampling misfit %.3f, %.1f %% of %zu lines of sight blocked, places as good within %.0f %% of the "
               "extent, 8th nearest point %.2f m away, %.0f %% of the spacing's variation explained",
               result.misfit, 100 * result.blocked_share, count, 100 * result.spread, result.clearance_m,
               100 * result.explained);
    if (result.misfit > options.max_misfit)
      result.verdict = "the sampling is not one scanner's";
    else if (result.explained < options.min_explained)
      result.verdict = "the sampling hardly varies, so no place explains it";
    else if (result.spread > options.max_spread)
      result.verdict = "the points are sampled as well from places far apart";
    else if (result.clearance_m < options.min_clearance_m)
      result.verdict = "the only place stands among the points, inside them";
    else {
      result.found = true;
      result.verdict = "the points are one scan's, taken from one place";
    }
    return result;
  };

  // With the axis given, that search; without, the best of the cloud's x, y
  // and z axes (a scan is written with its scanner's axis along one of them:
  // z, or y in a y-up export).
  if (Dot(options.up, options.up) > 0) {
    const double length = std::sqrt(Dot(options.up, options.up));
    return search({options.up[0] / length, options.up[1] / length, options.up[2] / length});
  }
  LostStation best;
  bool first = true;
  for (const Vec& axis : {Vec{0, 0, 1}, Vec{0, 1, 0}, Vec{1, 0, 0}}) {
    LostStation result = search(axis);
    if (first || (result.found && !best.found) || (result.found == best.found && result.misfit < best.misfit))
      best = std::move(result);
    first = false;
  }
  return best;
}

}  // namespace pb
