#include "stages/geometry/points/scene_survey.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <optional>
#include <string>

#include "stages/geometry/core/vec3.h"
#include "stages/geometry/points/enclosure.h"
#include "stages/geometry/points/spacing.h"

namespace pb {
namespace {

using Vec3 = vec3::V3;
using vec3::Add;
using vec3::Cross;
using vec3::Dot;
using vec3::Scale;
using vec3::Sub;

Vec3 Normalized(const Vec3& a) { return Scale(a, 1.0 / std::sqrt(Dot(a, a))); }

// The point's direction (unit, in the frame e1, e2, up) at azimuth and elevation.
Vec3 Direction(const Vec3& e1, const Vec3& e2, const Vec3& up, double azimuth, double elevation) {
  return Add(Add(Scale(e1, std::cos(elevation) * std::cos(azimuth)),
                 Scale(e2, std::cos(elevation) * std::sin(azimuth))),
             Scale(up, std::sin(elevation)));
}

// Rounds to two significant digits (60,123 -> 60,000; 4,352,296 -> 4,400,000).
int64_t TwoSignificantDigits(double v) {
  if (v < 100) return int64_t(std::lround(v));
  const double unit = std::pow(10.0, std::floor(std::log10(v)) - 1);
  return int64_t(std::lround(v / unit) * unit);
}

// The q-quantile (q in [0, 1]) of `values`, which it reorders.
double Quantile(std::vector<double>& values, double q) {
  const size_t k = std::min(values.size() - 1, size_t(q * double(values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

// The points around an eye, binned by azimuth about up (10° bins), for the
// densest 60° sectors of them.
class Panorama {
 public:
  struct Sector {
    double azimuth = 0, elevation = 0, distance = 0;  // center; the points' medians
    double share = 0;                                 // of the points looked at
  };
  // The points `select(i)` picks, every step-th of them so that at most
  // ~200,000 are looked at.
  template <typename Select>
  Panorama(const PointCloud& cloud, const Vec3& eye, const Vec3& up, const Vec3& e1, const Vec3& e2,
           size_t selected, Select select) {
    const size_t step = std::max<size_t>(1, selected / 200000);
    size_t seen = 0;
    for (size_t i = 0; i < cloud.size(); ++i) {
      if (!select(i) || seen++ % step != 0) continue;
      const Vec3 p = {cloud.origin[0] + cloud.positions[3 * i],
                      cloud.origin[1] + cloud.positions[3 * i + 1],
                      cloud.origin[2] + cloud.positions[3 * i + 2]};
      const Vec3 v = Sub(p, eye);
      const double h1 = Dot(v, e1), h2 = Dot(v, e2), vertical = Dot(v, up);
      const double horizontal = std::hypot(h1, h2);
      if (horizontal == 0 && vertical == 0) continue;
      azimuth_.push_back(std::atan2(h2, h1));
      elevation_.push_back(std::atan2(vertical, horizontal));
      distance_.push_back(std::sqrt(Dot(v, v)));
      ++histogram_[BinOf(azimuth_.back())];
    }
  }

  // The densest sector (kMostPoints), or the one whose points lie farthest
  // (kFarthest: the largest median distance, of the sectors holding at
  // least 1 % of the points), whose center lies at least `apart_deg` in
  // azimuth from each of `others`; nothing if no such sector has a point.
  enum Rank { kMostPoints, kFarthest };
  std::optional<Sector> Best(Rank rank, const std::vector<Sector>& others = {},
                             double apart_deg = 0) const {
    std::optional<Sector> best;
    int most_first = -1;
    size_t most_count = 0;
    for (int first = 0; first < kBins; ++first) {
      const double center = CenterOf(first);
      const bool near_other = std::any_of(others.begin(), others.end(), [&](const Sector& other) {
        return std::abs(std::remainder(center - other.azimuth, 2 * M_PI)) <
               apart_deg * M_PI / 180 - 1e-9;
      });
      if (near_other) continue;
      size_t count = 0;
      for (int k = 0; k < kSectorBins; ++k) count += histogram_[(first + k) % kBins];
      if (count == 0) continue;
      if (rank == kMostPoints) {
        if (count > most_count) most_count = count, most_first = first;
        continue;
      }
      if (count * 100 < azimuth_.size()) continue;
      const Sector sector = SectorAt(first, count);
      if (!best || sector.distance > best->distance) best = sector;
    }
    if (most_first >= 0) best = SectorAt(most_first, most_count);
    return best;
  }

 private:
  static constexpr int kBins = 36;       // 10° each
  static constexpr int kSectorBins = 6;  // 60°
  // The sector of kSectorBins bins from `first`, holding `count` points.
  Sector SectorAt(int first, size_t count) const {
    std::vector<double> elevation, distance;
    for (size_t j = 0; j < azimuth_.size(); ++j) {
      const int offset = (BinOf(azimuth_[j]) - first + kBins) % kBins;
      if (offset < kSectorBins) elevation.push_back(elevation_[j]), distance.push_back(distance_[j]);
    }
    Sector sector;
    sector.azimuth = CenterOf(first);
    sector.elevation = Quantile(elevation, 0.5);
    sector.distance = Quantile(distance, 0.5);
    sector.share = double(count) / double(azimuth_.size());
    return sector;
  }
  static int BinOf(double a) { return std::min(kBins - 1, int((a + M_PI) / (2 * M_PI) * kBins)); }
  static double CenterOf(int first) { return -M_PI + (first + kSectorBins / 2.0) * 2 * M_PI / kBins; }
  std::array<size_t, kBins> histogram_{};
  std::vector<double> azimuth_, elevation_, distance_;
};

// A view from `eye`, raised by `raise` times the sector's distance, toward
// the sector.
SurveyViewpoint ViewToward(const Vec3& eye, double raise, const Panorama::Sector& sector,
                           const Vec3& up, const Vec3& e1, const Vec3& e2, double fov_deg) {
  const Vec3 look = Direction(e1, e2, up, sector.azimuth, sector.elevation);
  SurveyViewpoint view;
  view.eye = Add(eye, Scale(up, raise * sector.distance));
  view.target = Add(eye, Scale(look, sector.distance));
  // Looking (nearly) along up, the camera's up is the sector's horizontal.
  view.up = std::abs(Dot(look, up)) < 0.95 ? up : Direction(e1, e2, up, sector.azimuth, 0.0);
  view.fov_deg = fov_deg;
  return view;
}

std::string Percent(double share) { return std::to_string(int(std::lround(100.0 * share))); }

std::string Meters(double m) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f m", m);
  return text;
}

// The station views: from each of the stations that saw the most points,
// toward the densest 60° sector of azimuths around up.
void StationViews(const PointCloud& cloud, const Vec3& up, const Vec3& e1, const Vec3& e2,
                  const SceneSurveyOptions& options, SceneSurvey* survey) {
  const size_t n = cloud.size();
  std::vector<size_t> counts(cloud.stations.size(), 0);
  if (cloud.has_stations()) {
    for (uint16_t id : cloud.station_ids)
      if (id < counts.size()) ++counts[id];
  } else {
    counts[0] = n;  // one station, no per-point ids: it saw them all
  }
  std::vector<size_t> order(counts.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return counts[a] > counts[b]; });
  survey->stations =
      size_t(std::count_if(counts.begin(), counts.end(), [](size_t c) { return c > 0; }));

  int made = 0;
  for (size_t station : order) {
    if (made == options.max_station_views || counts[station] == 0) break;
    const Vec3& s = cloud.stations[station];
    const Panorama panorama(cloud, s, up, e1, e2, counts[station], [&](size_t i) {
      return !cloud.has_stations() || cloud.station_ids[i] == station;
    });
    const std::optional<Panorama::Sector> sector = panorama.Best(Panorama::kMostPoints);
    if (!sector) continue;
    if (std::abs(sector->elevation) > 60.0 * M_PI / 180)
      survey->warnings.push_back(
          "most points of station " + std::to_string(station) + " lie " +
          std::to_string(int(std::lround(std::abs(sector->elevation) * 180 / M_PI))) +
          " degrees " + (sector->elevation > 0 ? "above" : "below") +
          " its horizon: is the up direction right? (a camera frame's is often -y)");
    SurveyViewpoint view = ViewToward(s, 0.05, *sector, up, e1, e2, options.fov_deg);
    view.name = "station" + std::to_string(made + 1);
    view.why = "from scanner station " + std::to_string(station) + " (" +
               std::to_string(counts[station]) +
               " points), toward the 60-degree sector it saw most of (" + Percent(sector->share) +
               " % of its points), raised 5 % of the distance";
    survey->viewpoints.push_back(view);
    ++made;
  }
  if (survey->viewpoints.empty()) return;
  // The oblique view: the first station view turned 40° about its target, raised 15°.
  const SurveyViewpoint& first = survey->viewpoints.front();
  const Vec3 back = Sub(first.eye, first.target);
  const double radius = std::sqrt(Dot(back, back));
  const double h1 = Dot(back, e1), h2 = Dot(back, e2);
  const double azimuth = std::atan2(h2, h1) + 40.0 * M_PI / 180;
  const double elevation = std::atan2(Dot(back, up), std::hypot(h1, h2)) + 15.0 * M_PI / 180;
  SurveyViewpoint oblique = first;
  oblique.name = "oblique";
  oblique.eye =
      Add(first.target,
          Scale(Direction(e1, e2, up, azimuth, std::min(elevation, 75.0 * M_PI / 180)), radius));
  oblique.why =
      first.name +
      "'s view turned 40 degrees about its target and raised 15: what the scanner did not see";
  survey->viewpoints.push_back(oblique);
}

// Three level views from the place deepest in the space a scan without
// stations encloses (a room merged into one file): toward the 60° sector
// whose points lie farthest, then the farthest at least 120° from it, then
// the farthest at least 90° from both.
void InteriorViews(const PointCloud& cloud, const EnclosedSpace& space, const Vec3& up,
                   const Vec3& e1, const Vec3& e2, const SceneSurveyOptions& options,
                   SceneSurvey* survey) {
  const std::array<double, 3> deepest = space.Deepest();
  const Vec3 eye = Add(cloud.origin, deepest);
  const Panorama panorama(cloud, eye, up, e1, e2, cloud.size(), [](size_t) { return true; });
  std::vector<Panorama::Sector> sectors;
  for (int k = 0; k < 3; ++k) {
    // 120° apart leaves room for a third view only when the first two are
    // about 120° apart too; the third keeps 90°.
    std::optional<Panorama::Sector> sector =
        panorama.Best(Panorama::kFarthest, sectors, k < 2 ? 120.0 : 90.0);
    if (!sector) break;
    sectors.push_back(*sector);
    sector->elevation = 0;  // level: walls, floor and ceiling in one frame
    SurveyViewpoint view = ViewToward(eye, 0.0, *sector, up, e1, e2, options.fov_deg);
    view.name = "inside" + std::to_string(k + 1);
    view.why = (k == 0 ? std::string("from the place deepest in the free space the scan ") +
                             (space.open() ? "nearly encloses (no stations: a room open on a side, or "
                                             "small, merged into one file)"
                                           : "encloses (no stations: a room merged into one file)") +
                             ", level, toward the 60-degree sector whose points lie farthest ("
                       : "from there, level, toward the farthest sector at least " +
                             std::string(k < 2 ? "120" : "90") + " degrees from the views before (") +
               Percent(sector->share) + " % of the points, their median " +
               Meters(sector->distance) + " away)";
    survey->viewpoints.push_back(view);
  }
}

// Three views of a scan without stations: face-on to its main plane (the
// principal axis of least variance, from the side its normals face), then
// that view turned 40° either way about the camera's up and raised 15°, each
// at the distance that frames 98 % of the points. When the main plane is
// level and something stands on it (a statue on its paving: the ground
// holds most points), face-on is straight down onto the object's top; the
// views then look as a visitor does, 30° down toward the scan's broad side
// and turned 40° either way 45° down.
void FaceOnViews(const PointCloud& cloud, const Vec3& up, const Vec3& e1, const Vec3& e2,
                 const SceneSurveyOptions& options, SceneSurvey* survey) {
  const size_t n = cloud.size();
  const size_t step = std::max<size_t>(1, n / 1000000);
  const Vec3 center = survey->robust_bounds.center_m();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  Vec3 normal_sum = {0, 0, 0};
  size_t used = 0;
  auto point = [&](size_t i) {
    return Vec3{cloud.origin[0] + cloud.positions[3 * i] - center[0],
                cloud.origin[1] + cloud.positions[3 * i + 1] - center[1],
                cloud.origin[2] + cloud.positions[3 * i + 2] - center[2]};
  };
  for (size_t i = 0; i < n; i += step, ++used) {
    const Vec3 p = point(i);
    const Eigen::Vector3d v(p[0], p[1], p[2]);
    covariance += v * v.transpose();
    if (cloud.has_normals())
      for (int c = 0; c < 3; ++c) normal_sum[c] += cloud.normals[3 * i + c];
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance / double(used));
  const Eigen::Vector3d least = solver.eigenvectors().col(0);  // eigenvalues ascending
  Vec3 toward_eye = {least[0], least[1], least[2]};
  const Vec3 mean_normal = Scale(normal_sum, 1.0 / double(used));
  std::string side;
  if (cloud.has_normals() && std::abs(Dot(mean_normal, toward_eye)) >= 0.1) {
    if (Dot(mean_normal, toward_eye) < 0) toward_eye = Scale(toward_eye, -1);
    side = "from the side its normals face";
  } else {
    // No side to prefer (no normals, or they face both ways: an object
    // scanned all round): the side above the horizon, else e1's.
    const double lean =
        std::abs(Dot(toward_eye, up)) > 1e-3 ? Dot(toward_eye, up) : Dot(toward_eye, e1);
    if (lean < 0) toward_eye = Scale(toward_eye, -1);
    side = cloud.has_normals() ? "its normals face all sides"
                               : "no normals to say which side is its front";
  }
  // A level main plane (within 30° of it) seen from above, with something
  // standing on it at least a fifth as tall as the plane is wide: looked at
  // from the side. (Normals facing down along up: a ceiling, or an up
  // written wrong, keep the face-on view from the side they face.)
  bool level_ground = false;
  if (Dot(toward_eye, up) > std::cos(30 * M_PI / 180)) {
    // Extents from the 1st to the 99th percentile along up, e1 and e2.
    std::vector<double> along[3];
    for (size_t i = 0; i < n; i += step) {
      const Vec3 p = point(i);
      along[0].push_back(Dot(p, up));
      along[1].push_back(Dot(p, e1));
      along[2].push_back(Dot(p, e2));
    }
    double extent[3];
    for (int c = 0; c < 3; ++c) extent[c] = Quantile(along[c], 0.99) - Quantile(along[c], 0.01);
    level_ground = extent[0] >= 0.2 * std::max(extent[1], extent[2]);
  }
  // The camera's up: `up` across the view, or, looking along it, the
  // principal axis of most variance.
  Vec3 camera_up = Sub(up, Scale(toward_eye, Dot(up, toward_eye)));
  if (level_ground) {
    // The heading: the level axis of least variance (the broad side faces
    // the camera), on the side the normals lean to, if they do.
    const Eigen::Vector3d a(e1[0], e1[1], e1[2]), b(e2[0], e2[1], e2[2]);
    Eigen::Matrix2d level;
    level << a.dot(covariance * a), a.dot(covariance * b), b.dot(covariance * a), b.dot(covariance * b);
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> level_solver(level);
    const Eigen::Vector2d narrow = level_solver.eigenvectors().col(0);
    Vec3 heading = Normalized(Add(Scale(e1, narrow[0]), Scale(e2, narrow[1])));
    const double lean = cloud.has_normals() && std::abs(Dot(mean_normal, heading)) >= 0.1
                            ? Dot(mean_normal, heading)
                            : Dot(heading, std::abs(Dot(heading, e1)) > 1e-3 ? e1 : e2);
    if (lean < 0) heading = Scale(heading, -1);
    toward_eye = heading;
    camera_up = up;
    side = "something stands on it";
  } else if (Dot(camera_up, camera_up) < 0.01) {
    const Eigen::Vector3d most = solver.eigenvectors().col(2);
    camera_up = Sub(Vec3{most[0], most[1], most[2]},
                    Scale(toward_eye, Dot(Vec3{most[0], most[1], most[2]}, toward_eye)));
  }
  camera_up = Normalized(camera_up);
  const double tan_half = std::tan(0.5 * options.fov_deg * M_PI / 180);
  const double turns[3] = {0.0, -40.0, 40.0};
  const double raise_front = level_ground ? 30.0 : 0.0;
  for (int k = 0; k < 3; ++k) {
    // toward_eye turned about camera_up, then raised toward it.
    const Vec3 side_axis = Cross(camera_up, toward_eye);
    const double a = turns[k] * M_PI / 180, b = (raise_front + (k == 0 ? 0.0 : 15.0)) * M_PI / 180;
    const Vec3 turned = Add(Scale(toward_eye, std::cos(a)), Scale(side_axis, std::sin(a)));
    const Vec3 direction =
        Normalized(Add(Scale(turned, std::cos(b)), Scale(camera_up, std::sin(b))));
    // Frame 98 % of the points: their reach across the view, and their
    // nearest half toward the eye so the camera stays outside them.
    std::vector<double> across, toward;
    for (size_t i = 0; i < n; i += step) {
      const Vec3 p = point(i);
      const double depth = Dot(p, direction);
      across.push_back(std::sqrt(std::max(0.0, Dot(p, p) - depth * depth)));
      toward.push_back(depth);
    }
    const double reach = Quantile(across, 0.98), front = std::max(0.0, Quantile(toward, 0.98));
    const double distance = front + 1.05 * reach / tan_half;
    SurveyViewpoint view;
    view.name = k == 0 ? "front" : (k == 1 ? "left" : "right");
    view.eye = Add(center, Scale(direction, distance));
    view.target = center;
    // The scan's up where it is not near the line of sight (files read
    // better), else the one across the view.
    view.up = std::abs(Dot(up, direction)) < 0.95
                  ? up
                  : Normalized(Sub(camera_up, Scale(direction, Dot(camera_up, direction))));
    view.fov_deg = options.fov_deg;
    if (level_ground) {
      view.why = k == 0 ? "30 degrees down toward the scan's broad side (no scanner stations; its "
                          "main plane is level, " + side + "), framing 98 % of its points"
                        : "the front view turned " + std::to_string(int(std::abs(turns[k]))) +
                              " degrees to the " + view.name + " about the up axis, 45 degrees down";
    } else {
      view.why = k == 0 ? "face-on to the scan's main plane (no scanner stations; " + side +
                              "), framing 98 % of its points"
                        : "the front view turned " + std::to_string(int(std::abs(turns[k]))) +
                              " degrees to the " + view.name + " and raised 15";
    }
    survey->viewpoints.push_back(view);
  }
}

}  // namespace

void ChooseSceneParams(size_t points, double spacing_m, double extent_m, SceneSurvey* survey) {
  survey->faces_high =
      std::clamp(TwoSignificantDigits(double(points) / 2.5), kMinFacesHigh, kMaxFacesHigh);
  survey->faces_low = std::min(survey->faces_high / 10, kMaxFacesLow);
  const double cells = extent_m / spacing_m;
  survey->depth_high = std::clamp(int(std::lround(std::log2(std::max(cells, 1.0)))), 8, 11);
  survey->depth_low = std::max(7, survey->depth_high - (survey->depth_high >= 10 ? 2 : 1));
  const double texels = std::sqrt(256.0 * double(survey->faces_low));
  survey->texture = std::clamp(1 << int(std::ceil(std::log2(std::max(texels, 1.0)))), 1024, 8192);
  survey->frame_size = points < 100000 ? 512 : 1024;
}

Expected<SceneSurvey> SurveyScene(const PointCloud& cloud, const SceneSurveyOptions& options) {
  if (cloud.size() < 10)
    return Status::Invalid("the scan has " + std::to_string(cloud.size()) +
                           " points; a scene needs at least 10");
  if (!(Dot(options.up, options.up) > 0) || !std::isfinite(Dot(options.up, options.up)))
    return Status::Invalid("the up direction has no length");
  if (!(options.fov_deg > 0 && options.fov_deg < 180))
    return Status::Invalid("the field of view must be in (0, 180) degrees");
  PB_RETURN_IF_ERROR(CheckFinitePositions(cloud, "the scan"));
  SceneSurvey survey;
  survey.points = cloud.size();
  SpacingOptions spacing_options;
  spacing_options.sample = options.spacing_sample;
  PB_ASSIGN_OR_RETURN(survey.spacing_m, MedianSpacing(cloud, spacing_options));

  // The robust box: per axis the 1st and 99th percentiles.
  const size_t n = cloud.size();
  survey.robust_bounds = RobustLocalBounds(cloud, 0.01);
  for (int axis = 0; axis < 3; ++axis) {
    survey.robust_bounds.min_m[axis] += cloud.origin[axis];
    survey.robust_bounds.max_m[axis] += cloud.origin[axis];
  }
  const Vec3 extent = survey.robust_bounds.extent_m();
  const double longest = std::max({extent[0], extent[1], extent[2]});
  if (!(longest > 0)) return Status::Invalid("the scan's points all lie at one place");
  // A spacing of 0 (more than half the points duplicated) would make no depth.
  ChooseSceneParams(n, std::max(survey.spacing_m, longest * 1e-6), longest, &survey);

  const Vec3 up = Normalized(options.up);
  // e1: the axis least aligned with up, made perpendicular to it.
  Vec3 axis = {1, 0, 0};
  if (std::abs(up[0]) > 0.9) axis = {0, 1, 0};
  const Vec3 e1 = Normalized(Sub(axis, Scale(up, Dot(axis, up))));
  const Vec3 e2 = Cross(up, e1);
  if (!cloud.stations.empty()) StationViews(cloud, up, e1, e2, options, &survey);
  if (survey.viewpoints.empty()) {
    // No stations: a room merged into one file is seen from inside.
    PB_ASSIGN_OR_RETURN(EnclosedSpace space, EnclosedSpace::Find(cloud));
    // Or a room open on a side, or small: a corridor, a cell.
    if (space.empty()) {
      PB_ASSIGN_OR_RETURN(space, EnclosedSpace::FindOpen(cloud));
    }
    survey.enclosed_volume_m3 = space.volume_m3();
    survey.enclosure_open = space.open() && !space.empty();
    if (!space.empty()) InteriorViews(cloud, space, up, e1, e2, options, &survey);
  }
  if (survey.viewpoints.empty()) FaceOnViews(cloud, up, e1, e2, options, &survey);
  return survey;
}

}  // namespace pb
