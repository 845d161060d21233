// points.normals: k-NN PCA normals with orientation (stages/geometry/points/normals.h).
#include <cstddef>
#include <cstdio>
#include <string>
#include <utility>

#include "stages/geometry/points/normals.h"
#include "stages/params.h"
#include "stages/points_io.h"
#include "stages/builtin.h"

namespace pb {
namespace {

constexpr const char* kId = "points.normals";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "k": {
      "type": "integer",
      "minimum": 3,
      "maximum": 100,
      "default": 16,
      "description": "Points in each PCA neighbourhood, the point itself included. Larger is smoother and slower; 16 suits scans with about 2 mm spacing and sub-millimeter noise."
    },
    "widen_dense": {
      "type": "boolean",
      "default": true,
      "description": "With implementation 'own': a point whose k nearest lie closer together than a typical point's (the cloud's median distance to the k-th nearest) takes its nearest points out to that distance instead (as many as the density of its k nearest puts within it, at most 32k), so that no neighbourhood is smaller than a typical one. Where a scanner's lines converge (the ceiling above a station) the k nearest lie on one short arc across the lines and the range noise stands the fitted plane on edge; a typical neighbourhood spans several lines. false: always the k nearest (version 4)."
    },
    "orientation": {
      "type": "string",
      "enum": ["auto", "stations", "input", "propagate", "none"],
      "default": "auto",
      "description": "How each normal's sign is chosen: 'stations' faces the scanner that saw the point; 'input' takes the side of the normal the point came with (a file's own normals, e.g. a scanner's or a fusion's software's); 'propagate' spreads a consistent sign over the neighbour graph (Hoppe 1992) from the point farthest from the centroid, facing outward; 'auto' uses stations when the cloud has them, else the input normals when every point has a usable one, else propagate; 'none' keeps the solver's arbitrary sign."
    },
    "interior": {
      "type": "string",
      "enum": ["auto", "yes", "no"],
      "default": "auto",
      "description": "For 'propagate': whether the scan is an interior seen from inside, whose normals face the space it encloses (a room merged into one file without its scanner stations would otherwise come out inside-out). 'auto' looks for free space the scan closes around, openings up to 1.5 m wide closed, at least 1 m3 once 0.75 m from the scan: a room's, not an object's inside; failing that and a lost station (find_station), since version 7 for free space the scan nearly closes around, at least 1.5 m3 once 0.375 m from the scan, from which at least 85 % of the lines of sight meet it and which is not a cup (open across one side: an object's inside seen from its unscanned underside): a corridor open at its ends, a room with a doorway wider than 1.5 m, a cell too small for the first test; 'no' always faces outward (version 2); 'yes' faces inward, toward the centroid, for an interior both tests miss (open across a whole side, an apse, a dead-end passage)."
    },
    "find_station": {
      "type": "boolean",
      "default": true,
      "description": "With orientation 'auto' and interior 'auto', a cloud without stations, usable normals of its own or enclosed space (at least 1,000 points): look for where one scanner would have stood, the one place whose sweep explains the points' spacing and from which nearly every point is seen (stages/geometry/points/lost_station.h, the scanner's axis the cloud's x, y or z). Found, every normal faces it and a warning says where it is. One scan exported without its position is otherwise oriented by propagation, which picks a side per part (version 6). false: propagation (version 5)."
    },
    "implementation": {
      "type": "string",
      "enum": ["own", "pcl", "open3d"],
      "default": "own",
      "description": "Whose code fits the planes: 'own' (exact kd-tree, the same result for any thread count), 'pcl' (PCL 1.13's NormalEstimationOMP, in pointbake-pcl.so) or 'open3d' (Open3D 0.16's EstimateNormals with a k-NN search, in pointbake-poisson-open3d.so). The same k points and the same orientation step for all three. docs/implementations.md compares them."
    }
  }
})";

// The value named `value` of the choice parameter `name`, or Status::Invalid
// listing the names.
template <typename T, size_t N>
Expected<T> Choice(const char* name, const std::string& value,
                   const std::pair<const char*, T> (&choices)[N]) {
  std::string names;
  for (const auto& [text, choice] : choices) {
    if (value == text) return choice;
    names += (names.empty() ? "" : ", ") + std::string(text);
  }
  return Status::Invalid(std::string(kId) + ": parameter '" + name + "' must be one of " + names +
                         "; got '" + value + "'");
}

// The orientation parameter's names, for parsing and for the output's meta.
constexpr std::pair<const char*, NormalOrientation> kOrientations[] = {
    {"auto", NormalOrientation::kAuto},
    {"stations", NormalOrientation::kStations},
    {"input", NormalOrientation::kInput},
    {"propagate", NormalOrientation::kPropagate},
    {"none", NormalOrientation::kNone}};

const char* OrientationName(NormalOrientation orientation) {
  for (const auto& [name, value] : kOrientations) {
    if (value == orientation) return name;
  }
  return "none";
}

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const int64_t k, IntegerParam(ctx, kId, "k", {3, 100}));
  PB_ASSIGN_OR_RETURN(const bool widen_dense, BoolParam(ctx, kId, "widen_dense"));
  PB_ASSIGN_OR_RETURN(const std::string orientation_name, StringParam(ctx, kId, "orientation"));
  PB_ASSIGN_OR_RETURN(const NormalOrientation orientation,
                      Choice<NormalOrientation>("orientation", orientation_name, kOrientations));
  PB_ASSIGN_OR_RETURN(const std::string interior_name, StringParam(ctx, kId, "interior"));
  PB_ASSIGN_OR_RETURN(const NormalInterior interior,
                      Choice<NormalInterior>("interior", interior_name,
                                             {{"auto", NormalInterior::kAuto},
                                              {"yes", NormalInterior::kYes},
                                              {"no", NormalInterior::kNo}}));
  PB_ASSIGN_OR_RETURN(const bool find_station, BoolParam(ctx, kId, "find_station"));
  PB_ASSIGN_OR_RETURN(const std::string implementation, StringParam(ctx, kId, "implementation"));
  PB_ASSIGN_OR_RETURN(const NormalImplementation solver,
                      Choice<NormalImplementation>("implementation", implementation,
                                                   {{"own", NormalImplementation::kOwn},
                                                    {"pcl", NormalImplementation::kPcl},
                                                    {"open3d", NormalImplementation::kOpen3d}}));
  PB_ASSIGN_OR_RETURN(InputPoints input, ReadInputPoints(ctx, kId, 0.3));
  PointCloud& cloud = input.cloud;
  NormalReport report;
  {
    PB_PHASE(ctx, "compute");
    NormalOptions options;
    options.k = static_cast<int>(k);
    options.widen_dense = widen_dense && solver == NormalImplementation::kOwn;
    options.orientation = orientation;
    options.interior = interior;
    options.find_station = find_station;
    options.implementation = solver;
    options.threads = ctx.threads();
    options.progress = [&ctx](double fraction) { ctx.progress(0.3 + 0.5 * fraction); };
    PB_RETURN_IF_ERROR(EstimateNormals(cloud, options, &report).WithContext(input.path));
  }
  if (report.input_sides_checked && report.input_sides_disagree > kMaxInputSidesDisagree) {
    char share[32];
    std::snprintf(share, sizeof share, "%.1f", 100.0 * report.input_sides_disagree);
    ctx.warning(std::string(kId) + ": the normals the points came with (the scan file's own) "
                "face inconsistent sides (" + share +
                " % of neighbouring pairs on one smooth surface disagree, over 5 %: a tool computed "
                "them without orienting them); oriented by propagation instead (orientation: input "
                "keeps their sides)");
  }
  if (report.station_found) {
    char at[160];
    std::snprintf(at, sizeof at, "%.3f, %.3f, %.3f", report.station[0], report.station[1], report.station[2]);
    ctx.warning(std::string(kId) + ": the points carry no scanner station, but " + report.station_verdict +
                ": the scanner stood at " + at +
                " m (the cloud's coordinates, in meters), and the normals face it. If that is wrong, declare "
                "the station (io.read_points `station`) or set find_station: false (docs/real-scans.md, \"A "
                "lost station\")");
  }
  if (report.enclosure_open) {
    char volume[32];
    std::snprintf(volume, sizeof volume, "%.1f", report.enclosed_volume_m3);
    ctx.warning(std::string(kId) + ": the points enclose no room, but nearly enclose " + volume +
                " m3 of free space from which most lines of sight meet them (a corridor open at its ends, a "
                "room with a wide doorway, a small room; stages/geometry/points/enclosure.h), and the "
                "normals face it. If the scan is an object seen from outside, set interior: no");
  }
  if (report.input_sides_checked) ctx.counter("input_sides_disagree", report.input_sides_disagree);
  if (report.station_searched) ctx.counter("station_found", report.station_found ? 1.0 : 0.0);
  ctx.counter("points", static_cast<double>(report.points));
  ctx.counter("flipped", static_cast<double>(report.flipped));
  if (widen_dense && solver == NormalImplementation::kOwn) {
    ctx.counter("widened", static_cast<double>(report.widened));
    ctx.counter("widen_to_m", report.widen_to_m);
  }
  if (report.orientation_used == NormalOrientation::kPropagate && interior == NormalInterior::kAuto) {
    ctx.counter("enclosed_volume_m3", report.enclosed_volume_m3);
    ctx.counter("enclosure_open", report.enclosure_open ? 1.0 : 0.0);
    ctx.counter("facing_enclosure", static_cast<double>(report.facing_enclosure));
    ctx.counter("facing_rays", static_cast<double>(report.facing_rays));
  }
  nlohmann::json meta =
      InputPointsMetaWith(ctx, {{"points", cloud.size()},
                                {"has_normals", true},
                                {"normals_k", static_cast<int>(k)},
                                {"normals_orientation", OrientationName(report.orientation_used)},
                                {"normals_implementation", implementation}});
  if (report.station_found)
    meta["normals_station_found"] = {report.station[0], report.station[1], report.station[2]};
  PB_RETURN_IF_ERROR(WriteOutputPoints(ctx, cloud, meta));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType NormalsStage() {
  StageType type;
  type.id = kId;
  // 6: find_station (a lost station, found in the points of one scan).
  // 7: interior auto also faces a space the points nearly enclose (FindOpen).
  type.version = 7;
  type.summary = "k-NN PCA normals, oriented toward the scanner, like the file's own, or by propagation";
  type.doc =
      "Estimates a unit normal per point: the eigenvector of the smallest eigenvalue of the "
      "covariance of the point's `k` nearest points (itself included), found with an exact "
      "kd-tree search. `orientation` then picks each sign: toward the point's scanner station "
      "(`stations`, needs per-point station ids), by minimum-spanning-tree propagation over the "
      "neighbour graph seeded outward from the point farthest from the centroid (`propagate`, "
      "Hoppe et al. 1992; right for closed objects; with `interior: auto`, version 3, where the "
      "scan encloses free space, a room's, the points beside it face it and the propagation "
      "starts from them, so that a room merged without its stations is not meshed inside-out "
      "(version 7: also one the scan only nearly encloses, a corridor open at its ends, a room "
      "with a wide doorway, a small room, when no lost station was found; a warning says so); "
      "elsewhere, version 4, rays decide the points whose outside they see, open ahead and "
      "closed behind, where their nearest probed points agree, and the propagation starts from "
      "them, so that a plinth standing on its ground is not turned inside out through it), "
      "like the normals the points came with "
      "(`input`: a file's own normals, whose software knew the sensor; propagation can flip "
      "whole thin parts), `auto` (stations if present, else the input normals if every point "
      "has a usable one, else propagate; version 2, which added `input`) or `none`. Existing "
      "normals are replaced (only their sides are used); other attributes pass through. The "
      "result does not depend on the thread count. `implementation` swaps the plane fit for "
      "PCL's NormalEstimationOMP or Open3D's EstimateNormals (modules loaded on first use), "
      "for campaigns that compare implementations.\n\n"
      "Meta added: `has_normals`, `normals_k`, `normals_orientation` (the method used), "
      "`normals_implementation`, and `normals_station_found` (the place, absolute meters) when "
      "`find_station` (default true, version 6) found where one scanner stood in a cloud without "
      "stations, usable normals of its own or enclosed space: the one place whose sweep explains "
      "the points' spacing and from which nearly every point is seen "
      "(stages/geometry/points/lost_station.h); the normals then face it, `normals_orientation` "
      "says `stations` and a warning says where it is. "
      "Since version 5 (`widen_dense`, default true), a point whose `k` nearest lie closer "
      "together than a typical point's takes its nearest points out to the typical radius instead "
      "(at most 32k): where a scanner's lines converge, above a station, the k nearest lie on one "
      "short arc and the range noise stood their plane on edge. "
      "Counters: `points`, `flipped` (normals whose sign orientation reversed), with "
      "`widen_dense` `widened` (points whose neighbourhood was widened) and `widen_to_m` (the "
      "typical radius); with "
      "propagation and `interior: auto`, `enclosed_volume_m3` (the enclosed space found, 0 for "
      "none; stages/geometry/points/enclosure.h), `enclosure_open` (1 when it was only nearly "
      "enclosed, version 7: a warning says so) and `facing_enclosure` (points oriented to face "
      "it; the rest by propagation from them) and `facing_rays` (points whose side rays decided, "
      "when no enclosed space was found), or `station_found` (1 when the lost station was found, "
      "else 0, when `find_station` looked); with `auto` and a file's own normals, "
      "`input_sides_disagree` (the share of neighbouring pairs on one smooth surface whose file "
      "sides disagree; over 0.05, version 4, the sides were not oriented, a warning says so and "
      "propagation orients instead).";
  type.params_schema = kSchema;
  type.inputs = {{"points", "points", "The points to estimate normals for.", false}};
  type.outputs = {{"points", "points", "The same points with unit normals.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
