// Scene survey: what a scene file needs that can be read off a scan, for a
// user who brings a scan and has no viewpoints or meshing parameters yet
// (`pointbake scene SCAN`, docs/real-scans.md "Your own scan").
//
// Parameters, in the proportions of the shipped scenes (configs/scenes):
//   faces_high  one face per 2.5 points (the pump: 155,201 points, 60,000;
//               the office wall 254,456 / 100,000; the synthetic room
//               10^6 / 400,000), rounded to 2 significant digits, within
//               [kMinFacesHigh, kMaxFacesHigh]: the HPM is the
//               full-detail model, but past 5·10^6 faces neither the bake
//               nor a viewer gains from it on a laptop.
//   faces_low   a tenth of faces_high, at most kMaxFacesLow (the paper's
//               240,000-face LPM, what a mobile headset draws at 60 FPS).
//   depth_high  the screened-Poisson octree depth whose cell is about the
//               median spacing over the robust extent (the 1st to 99th
//               percentile box's longest side), in [8, 11]: finer cells than
//               the samples only fit their noise (the pump: 3.9 m / 4.6 mm,
//               depth 10; the office wall 9, the living room 8, as their
//               hand-written scenes).
//   depth_low   depth_high - 1 below depth 10, else depth_high - 2; at
//               least 7 (the LPM's coarse solve, then decimated to
//               faces_low; the shipped scenes: pump 10 / 8, office wall
//               9 / 8, living room 8 / 7, synthetic room 9 / 8). Two depths
//               below a depth-9 HPM left the office wall's LPM so coarse
//               that Remeshing kept 2.2x its boundary edges.
//   texture     the power of two whose square holds about 256 texels per
//               low face, in [1024, 8192] (pump 6,000 faces: 2048; paper
//               240,000: 8192).
//   frame_size  512 below 10^5 points, else 1024 (the shipped real scenes:
//               the bunny's 36,000 points 512, the living room's 114,000
//               1024; a one-pixel outline weighs less on a larger frame).
//
// Viewpoints (what render.frames and render.splats draw; every workflow of a
// scene is compared in them):
//   * A scan with scanner stations (E57 poses, PTX headers, a PCD VIEWPOINT,
//     PLY comments): one view from each of the (at most
//     `max_station_views`) stations that saw the most points, looking at the
//     part of its scan it saw most of: the 60°-wide sector of azimuths
//     around `up` holding the most of its points, at their median elevation
//     and distance. The eye is raised above the station by 5 % of that
//     distance, so that the depth steps the scanner saw straight on open a
//     little (where a model invents or loses surface). Then one oblique
//     view: the first station's view turned 40° about its target and raised,
//     which shows what the scanner did not see (the sides Poisson closes).
//   * A scan without stations that encloses free space (enclosure.h: a
//     room merged into one file, seen from inside; else FindOpen's space,
//     a corridor open at its ends, a cell too small for Find): three level views from
//     the enclosed place farthest from the scan, toward the 60° sector of
//     azimuths whose points lie farthest (median distance, of the sectors
//     holding at least 1 % of them: down the room's length, walls, floor
//     and ceiling in the frame), then toward the farthest at least 120°
//     from it and the farthest at least 90° from both.
//   * Any other scan without stations (a merged or photogrammetric cloud, an
//     object): a front view face-on to its main plane (the principal axis
//     of least variance of the points, from the side their normals face if
//     their mean leans at least 0.1 along it, else from above the horizon),
//     then that view turned 40° to the left and to the right about the
//     camera's up and raised 15°; each as far as frames 98 % of the points
//     (their reach across the view, plus the nearest of them toward the
//     eye). Face-on,
//     a wall or a relief fills the frame instead of being seen edge-on,
//     where the outline's pixels would outweigh the surface's.
// All in absolute meters (the cloud's origin added), `up` as given (z by
// default, the scanners' convention).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

inline constexpr int64_t kMinFacesHigh = 40000;
inline constexpr int64_t kMaxFacesHigh = 5000000;
inline constexpr int64_t kMaxFacesLow = 240000;

struct SceneSurveyOptions {
  std::array<double, 3> up = {0.0, 0.0, 1.0};  // the scan's vertical (need not be unit length)
  double fov_deg = 60.0;                       // every view's vertical field of view
  int max_station_views = 2;                   // views from stations, before the oblique one
  size_t spacing_sample = 100000;  // points whose nearest neighbour is measured (spacing.h)
};

struct SurveyViewpoint {
  std::string name;             // "station1", "oblique"; "front", "left", "right"
  std::array<double, 3> eye{};  // absolute meters
  std::array<double, 3> target{};
  std::array<double, 3> up{};  // unit length
  double fov_deg = 60.0;
  std::string why;  // one line for the scene file's comment
};

struct SceneSurvey {
  size_t points = 0;
  double spacing_m = 0.0;  // median nearest-neighbour distance (MedianSpacing)
  Bounds robust_bounds;    // absolute; per axis the 1st..99th percentile of the points
  size_t stations = 0;     // stations with at least one point
  double enclosed_volume_m3 = 0.0;  // without stations: the free space enclosed (enclosure.h)
  bool enclosure_open = false;      // that space found by FindOpen: open on a side, or small
  int depth_high = 0, depth_low = 0;
  int64_t faces_high = 0, faces_low = 0;
  int texture = 0, frame_size = 0;
  std::vector<SurveyViewpoint> viewpoints;
  std::vector<std::string> warnings;  // e.g. a station that saw mostly below it: up may be wrong
};

// The workflow parameters of the header for `points` points, `spacing_m`
// apart, over a robust extent whose longest side is `extent_m` (all > 0).
void ChooseSceneParams(size_t points, double spacing_m, double extent_m, SceneSurvey* survey);

// Surveys `cloud` (meters). Status::Invalid when it has fewer than 10 points,
// a non-finite coordinate (naming the point), `up` of zero length or a field
// of view outside (0, 180); all its points at one place.
Expected<SceneSurvey> SurveyScene(const PointCloud& cloud, const SceneSurveyOptions& options = {});

}  // namespace pb
