// io.read_points: reads a scan file into the `points` artifact.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "base/units.h"
#include "stages/builtin.h"
#include "stages/geometry/io/scan_read.h"
#include "stages/geometry/points/knn.h"
#include "stages/params.h"
#include "stages/points_io.h"

namespace pb {
namespace {

constexpr const char* kId = "io.read_points";

// The sRGB grey of a scan that has neither colors nor intensities: light
// stone, so that the normal maps' shading shows on the renders.
constexpr uint8_t kUniformGrey = 180;

// Paints an uncolored cloud grey (`uncolored`): by its intensities,
// stretched linearly between their 1st and 99th percentiles (scanners'
// intensities crowd a narrow band, like CloudCompare's default scale), or
// uniformly. Returns what the colors came from, for the meta.
std::string PaintUncolored(const std::string& mode, PointCloud* points) {
  if (points->has_colors()) return "file";
  if (mode == "none" || points->empty()) return "none";
  points->colors.assign(3 * points->size(), kUniformGrey);
  if (mode != "intensity" || !points->has_intensities()) return "uniform grey";
  // Finite intensities only (a NaN would break the ordering); a point
  // without one gets the middle grey.
  std::vector<float> sorted;
  sorted.reserve(points->intensities.size());
  for (float v : points->intensities) {
    if (std::isfinite(v)) sorted.push_back(v);
  }
  if (sorted.empty()) return "uniform grey";
  const size_t n = points->intensities.size(), m = sorted.size();
  auto quantile = [&](double q) {
    const size_t k = std::min(m - 1, size_t(q * double(m - 1)));
    std::nth_element(sorted.begin(), sorted.begin() + k, sorted.end());
    return double(sorted[k]);
  };
  const double lo = quantile(0.01), hi = quantile(0.99);
  if (!(hi > lo)) return "uniform grey";  // all intensities (nearly) equal
  for (size_t i = 0; i < n; ++i) {
    const double v = points->intensities[i];
    const double t = std::isfinite(v) ? std::clamp((v - lo) / (hi - lo), 0.0, 1.0) : 0.5;
    const auto grey = uint8_t(std::lround(255.0 * t));
    for (int c = 0; c < 3; ++c) points->colors[3 * i + c] = grey;
  }
  return "intensity";
}

// Gives each point of `invalid` (ascending indices) the `width` values of
// `values` of its nearest point not in `invalid`: the file marked its own
// as no measurement (E57 isColorInvalid: a point no photo covered, whose
// stored color is typically black).
enum class Filled { kFilled, kNoneValid, kTooMany };
template <typename T>
Expected<Filled> FillFromNearest(const PointCloud& points, const std::vector<size_t>& invalid,
                                 int width, std::vector<T>* values) {
  if (invalid.empty()) return Filled::kFilled;
  // The kd-tree holds under 2^32 points.
  if (points.size() > std::numeric_limits<uint32_t>::max()) return Filled::kTooMany;
  if (invalid.size() >= points.size()) return Filled::kNoneValid;
  std::vector<float> valid_xyz;
  std::vector<uint32_t> valid_index;
  valid_xyz.reserve(3 * (points.size() - invalid.size()));
  valid_index.reserve(points.size() - invalid.size());
  size_t next = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (next < invalid.size() && invalid[next] == i) {
      ++next;
      continue;
    }
    valid_xyz.insert(valid_xyz.end(), &points.positions[3 * i], &points.positions[3 * i] + 3);
    valid_index.push_back(static_cast<uint32_t>(i));
  }
  PB_ASSIGN_OR_RETURN(const KnnIndex index, KnnIndex::Build(valid_xyz));
  std::vector<float>().swap(valid_xyz);  // the index keeps its own copy
  Neighbor nearest[1];
  for (size_t i : invalid) {
    index.Query(&points.positions[3 * i], 1, nearest);
    const size_t from = valid_index[nearest[0].index];
    std::copy_n(values->begin() + width * from, width, values->begin() + width * i);
  }
  return Filled::kFilled;
}

// The colors and intensities the file marks as no measurement, from the
// nearest valid ones (none valid: the attribute is dropped), with a warning.
Status FillUnmeasured(const ScanReadResult& outcome, const std::string& path, StageContext& ctx,
                      PointCloud* points) {
  const auto fill = [&]<typename T>(const std::vector<size_t>& invalid, int width,
                                    std::vector<T>* values, const char* what,
                                    const char* field) -> Status {
    if (values->empty() || invalid.empty()) return Status::Ok();
    PB_ASSIGN_OR_RETURN(const Filled filled, FillFromNearest(*points, invalid, width, values));
    char text[240];
    switch (filled) {
      case Filled::kFilled:
        std::snprintf(text, sizeof text,
                      ": %zu points (%.2f %%) have no valid %s in the file (E57 %s): each took "
                      "its nearest valid point's",
                      invalid.size(), 100.0 * double(invalid.size()) / double(points->size()), what,
                      field);
        break;
      case Filled::kNoneValid:
        values->clear();
        std::snprintf(text, sizeof text, ": no point has a valid %s (E57 %s): %ss dropped", what,
                      field, what);
        break;
      case Filled::kTooMany:
        std::snprintf(text, sizeof text,
                      ": %zu points have no valid %s in the file (E57 %s), kept as stored: a "
                      "cloud of 2^32 points or more is not filled",
                      invalid.size(), what, field);
        break;
    }
    ctx.warning(path + text);
    return Status::Ok();
  };
  PB_RETURN_IF_ERROR(fill(outcome.colorless_points, 3, &points->colors, "color", "isColorInvalid"));
  return fill(outcome.intensityless_points, 1, &points->intensities, "intensity",
              "isIntensityInvalid");
}

// `station` as a string: 'file', 'none' or "x,y,z" (decimal numbers).
constexpr const char* kStationPattern =
    "^(file|none|[-+]?[0-9.eE+-]+,[-+]?[0-9.eE+-]+,[-+]?[0-9.eE+-]+)$";

// The `station` parameter: absent (the file's), none, or a position in the
// frame of the points as read (after the file's own pose) and its units.
struct StationChoice {
  enum class Kind { kFile, kNone, kDeclared } kind = Kind::kFile;
  std::array<double, 3> position{};
};

Expected<StationChoice> ReadStation(const StageContext& ctx) {
  StationChoice choice;
  if (!ctx.params().contains("station")) return choice;
  const nlohmann::json& value = ctx.params()["station"];
  const Status bad = Status::Invalid(std::string(kId) +
                                     ": parameter 'station' must be 'file', 'none', [x, y, z] or "
                                     "\"x,y,z\" with finite numbers, got " +
                                     value.dump());
  std::array<double, 3> position{};
  if (value.is_string()) {
    const std::string text = value.get<std::string>();
    if (text == "file") return choice;
    if (text == "none") {
      choice.kind = StationChoice::Kind::kNone;
      return choice;
    }
    size_t start = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const size_t end = axis < 2 ? text.find(',', start) : text.size();
      if (end == std::string::npos) return bad;
      const std::string number = text.substr(start, end - start);
      char* stop = nullptr;
      position[axis] = std::strtod(number.c_str(), &stop);
      if (number.empty() || stop != number.c_str() + number.size()) return bad;
      start = end + 1;
    }
  } else if (value.is_array() && value.size() == 3) {
    for (int axis = 0; axis < 3; ++axis) {
      if (!value[axis].is_number()) return bad;
      position[axis] = value[axis].get<double>();
    }
  } else {
    return bad;
  }
  for (double c : position) {
    if (!std::isfinite(c)) return bad;
  }
  choice.kind = StationChoice::Kind::kDeclared;
  choice.position = position;
  return choice;
}

// Applies `choice` to the cloud as read (file units); returns what the
// stations came from, for the meta, and warns when a declared station
// replaces the file's or lies far from the scan (a wrong frame or unit).
std::string ApplyStation(const StationChoice& choice, const std::string& path, StageContext& ctx,
                         PointCloud* points) {
  switch (choice.kind) {
    case StationChoice::Kind::kFile:
      return points->has_stations() ? "file" : "none";
    case StationChoice::Kind::kNone:
      points->stations.clear();
      points->station_ids.clear();
      return "none";
    case StationChoice::Kind::kDeclared:
      break;
  }
  for (const std::string& warning : DeclareStation(choice.position, points)) ctx.warning(path + ": " + warning);
  return "declared";
}

std::string ParamsSchema() {
  nlohmann::json formats = nlohmann::json::array({"auto"});
  for (const ScanFormat& format : ScanFormats()) formats.push_back(std::string(format.name));
  nlohmann::json units = nlohmann::json::array();
  for (const auto& [name, meters] : kLengthUnits) units.push_back(std::string(name));
  const nlohmann::json schema = {
      {"type", "object"},
      {"additionalProperties", false},
      {"required", {"path"}},
      {"properties",
       {
           {"path",
            {{"type", "string"},
             {"x-path", true},
             {"description",
              "The scan file, relative to the file that names it. Keyed by content, so "
              "renaming or moving it keeps the cache."}}},
           {"units",
            {{"type", "string"},
             {"enum", units},
             {"default", "m"},
             {"description",
              "The length unit of the file's coordinates; the points are converted to meters, "
              "in which the project computes and glTF is written. A scene's `units:` sets it "
              "for its `source:` (docs/campaigns.md, Units)."}}},
           {"format",
            {{"type", "string"},
             {"enum", formats},
             {"default", "auto"},
             {"description", "File format; 'auto' decides by the file extension: " +
                                 SupportedScanFormats() + "."}}},
           {"drop_invalid",
            {{"type", "boolean"},
             {"default", false},
             {"description",
              "Drop points with NaN or infinite coordinates (counted as dropped_points) "
              "instead of failing on the first one. (PTX 0,0,0 points, NaN points of "
              "organized PCD clouds and E57 invalid states are grid cells without a return: "
              "always left out, counted as no_return_points, no warning.)"}}},
           {"columns",
            {{"type", "string"},
             {"default", ""},
             {"description",
              "XYZ/TXT/PTS only: column names in order, e.g. \"x y z r g b\" or "
              "\"x y z i r g b nx ny nz\"; \"_\" skips a column. Empty: the format's default "
              "(PTS: x y z i r g b) or detected from the first data line."}}},
           {"station",
            {{"anyOf",
              {{{"type", "string"}, {"pattern", kStationPattern}},
               {{"type", "array"},
                {"items", {{"type", "number"}}},
                {"minItems", 3},
                {"maxItems", 3}}}},
             {"default", "file"},
             {"description",
              "Where the scanner stood, which orients normals toward it (points.normals) and "
              "gives mesh.decimate its lines of sight: 'file' takes the file's stations (poses, "
              "VIEWPOINT, PTX positions, PLY station comments; an unposed E57 grid, a PLY's "
              "row/col grid or an organized PCD swept from its origin has it there); 'none' "
              "drops them; [x, y, z] (or \"x,y,z\", the form --set gives) declares one station "
              "for every point, in the coordinates of the points as the file gives them (after "
              "its own pose, e.g. a PCD VIEWPOINT) and in `units`, replacing the file's: a "
              "one-station scan exported without its pose (PTS, XYZ, PLY, LAS). With 'none' or "
              "a position the file's grid is not tested and its stations are not warned "
              "about."}}},
           {"uncolored",
            {{"type", "string"},
             {"enum", {"intensity", "grey", "none"}},
             {"default", "intensity"},
             {"description",
              "What a scan without colors gets (a file with colors keeps them): 'intensity' "
              "paints each point grey by its intensity, stretched between the 1st and 99th "
              "percentiles, or a uniform light grey (sRGB 180) when the file has no "
              "intensities either; 'grey' always the uniform grey; 'none' leaves the points "
              "uncolored (the bake stages then refuse them: they need colors)."}}},
       }},
  };
  return schema.dump();
}

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const std::string path, StringParam(ctx, kId, "path"));
  PB_ASSIGN_OR_RETURN(const std::string format_name, StringParam(ctx, kId, "format"));
  PB_ASSIGN_OR_RETURN(const bool drop_invalid, BoolParam(ctx, kId, "drop_invalid"));
  Expected<const ScanFormat*> found = FindScanFormat(path, format_name);
  if (!found.ok()) return found.status().WithContext(kId);
  const ScanFormat* format = *found;

  PB_ASSIGN_OR_RETURN(const std::string columns, StringParam(ctx, kId, "columns"));
  PB_ASSIGN_OR_RETURN(const std::string uncolored, StringParam(ctx, kId, "uncolored"));
  PB_ASSIGN_OR_RETURN(const std::string unit, StringParam(ctx, kId, "units"));
  const std::optional<double> meters = MetersPerUnit(unit);
  if (!meters) return Status::Invalid(std::string(kId) + ": unknown units '" + unit + "'");
  PB_ASSIGN_OR_RETURN(const StationChoice station, ReadStation(ctx));

  ScanReadOptions options;
  options.drop_invalid_points = drop_invalid;
  options.columns = columns;
  // A declared or dropped station replaces whatever the file's grid shows.
  options.infer_stations = station.kind == StationChoice::Kind::kFile;
  options.progress = [&ctx](double fraction) { ctx.progress(0.9 * fraction); };
  ctx.begin_phase("read");
  Expected<ScanReadResult> read = format->read(path, options);
  ctx.end_phase("read");
  if (!read.ok()) return read.status();
  ScanReadResult& outcome = *read;
  PB_RETURN_IF_ERROR(FillUnmeasured(outcome, path, ctx, &outcome.points));
  const std::string stations_from = ApplyStation(station, path, ctx, &outcome.points);
  ConvertToMeters(*meters, &outcome.points);
  const std::string colors_from = PaintUncolored(uncolored, &outcome.points);
  const PointCloud& points = outcome.points;
  // The readers' warnings name the file (some readers put it first already).
  for (const std::string& warning : outcome.warnings)
    ctx.warning(warning.rfind(path, 0) == 0 ? warning : path + ": " + warning);
  if (outcome.dropped_points > 0)
    ctx.warning(path + ": dropped " + std::to_string(outcome.dropped_points) +
                " points with NaN or infinite coordinates (drop_invalid)");
  if (colors_from == "intensity" || colors_from == "uniform grey") {
    ctx.warning(path + ": the scan has no colors: its points are painted " +
                (colors_from == "intensity" ? std::string("grey by their intensities")
                                            : std::string("a uniform grey (no intensities)")) +
                " (io.read_points `uncolored`)");
  }

  PB_RETURN_IF_ERROR(WriteOutputPoints(
      ctx, points,
      {{"origin", points.origin},
       {"points", points.size()},
       {"has_normals", points.has_normals()},
       {"has_colors", points.has_colors()},
       {"has_intensities", points.has_intensities()},
       {"colors_from", colors_from},
       {"file_units", unit},
       {"stations", points.stations.size()},
       {"stations_from", stations_from},
       {"source_format", outcome.format.empty() ? std::string(format->name) : outcome.format}},
      "write"));
  ctx.counter("points", static_cast<double>(points.size()));
  ctx.counter("dropped_points", static_cast<double>(outcome.dropped_points));
  ctx.counter("no_return_points", static_cast<double>(outcome.no_return_points));
  ctx.counter("warnings", static_cast<double>(outcome.warnings.size()));
  const bool painted = colors_from == "intensity" || colors_from == "uniform grey";
  ctx.counter("painted_points", painted ? static_cast<double>(points.size()) : 0.0);
  ctx.counter("uniform_grey", colors_from == "uniform grey" ? 1.0 : 0.0);
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType ReadPointsStage() {
  StageType type;
  type.id = kId;
  type.version = 7;  // 4: units; 5: stations of unposed grids (grid_station.h), `station`, E57
                     // invalid colors filled; 6: the same for a PLY's row/col grid, and
                     // the grid test's angles from the chord's series; 7: a declared
                     // `station` skips the grid test and its warnings, and the E57, PCD
                     // and PLY readers word its verdict alike (the same points)
  type.summary = "Read a scan file (PLY, PCD, XYZ/TXT/PTS, PTX, E57, LAS/LAZ) into points";
  type.doc =
      "Reads a colored laser scan into the `points` artifact: positions in meters (a file in "
      "millimeters, centimeters, feet or inches says so with `units`), and normals "
      "and 8-bit sRGB colors, intensities and scanner stations when the file has them.\n\n"
      "Formats (chosen by extension, or `format:`): PLY (ascii, binary little and big endian; "
      "any scalar types; unknown elements and properties ignored; a structured scan's `row` and "
      "`col` per point, with no station in the file, put its scanner at the origin when its grid "
      "was swept from there, as for an E57 without a pose); PCD v0.6/0.7 (ascii, binary, "
      "binary_compressed; VIEWPOINT applied and kept as the station; an organized cloud without "
      "a VIEWPOINT pose has its sensor at the origin when its pixel grid was swept from there); "
      "XYZ/TXT/CSV/PTS (columns "
      "declared with `columns:` or detected); PTX (several scans; each scan's 4x4 transform "
      "applied, its scanner position kept as a station, 0,0,0 points dropped); E57 (ASTM E2807: "
      "CRC-32C checked, bitPackCodec, float/scaled-integer/integer fields, cartesian or "
      "spherical, poses, several scans, color and intensity; a scan without a pose has its scanner "
      "at its frame's origin when it is spherical, or when its row/column grid was swept from "
      "there: a station for normal orientation and lines of sight); LAS 1.0-1.4, point formats "
      "0-10, "
      "and LAZ (LASzip-compressed LAS, COPC included: point formats 0-3 and 6-8, decoded in "
      "parallel over chunks; docs/laz.md).\n\n"
      "Double-precision (e.g. georeferenced) coordinates are stored as float32 offsets from an "
      "origin at the scan's bounding-box center rounded to 1 m, which keeps float32 precision "
      "(about 1e-7 of the scan's extent) for any location on Earth; the "
      "origin travels in the artifact.\n\n"
      "Scanner stations come from the file (or, for an unposed structured E57 scan, a PLY "
      "with a row and column per point and no station, or an organized PCD frame, from its "
      "grid); `station` declares one where the file does not say "
      "(a one-station PTS/XYZ/PLY/LAS export) or drops them; the meta's `stations_from` says "
      "`file`, `declared` or `none`.\n\n"
      "A scan without colors is painted grey (`uncolored`: by intensity, else uniformly) so "
      "that every workflow runs on it, with a warning; the meta's `colors_from` says `file`, "
      "`intensity`, `uniform grey` or `none`.\n\n"
      "Counters: `points` (points kept), `dropped_points` (non-finite coordinates, with "
      "drop_invalid), `no_return_points` (grid cells the file marks as measuring nothing: "
      "PTX 0 0 0, organized PCD NaN, E57 invalid states), `painted_points` (points painted grey by `uncolored`), `uniform_grey` "
      "(1 when they all got the same grey: the scan's texture comparisons then say nothing).";
  type.params_schema = ParamsSchema();
  type.outputs = {{"points", "points", "The scan's points (binary PLY with origin).", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
