// io.read_points: reads a scan file into the `points` artifact.
#include <cctype>
#include <string>
#include <string_view>

#include "stages/geometry/ply.h"
#include "stages/io/io_stages.h"
#include "stages/params.h"

namespace pb {
namespace {

constexpr const char* kId = "io.read_points";

struct ReadRequest {
  bool drop_invalid = false;
  std::function<void(double)> progress;
};

struct ReadOutcome {
  PointCloud points;
  uint64_t dropped_points = 0;
};

Expected<ReadOutcome> ReadPly(const std::string& path, const ReadRequest& request) {
  PlyReadOptions options;
  options.drop_invalid_points = request.drop_invalid;
  options.progress = request.progress;
  PB_ASSIGN_OR_RETURN(PlyPoints ply, ReadPlyPoints(path, options));
  return ReadOutcome{std::move(ply.points), ply.report.dropped_points};
}

// The scan formats this stage reads, by name; `auto` matches the extension.
struct ScanFormat {
  std::string_view name;
  std::string_view extension;  // lower case, with the dot
  Expected<ReadOutcome> (*read)(const std::string& path, const ReadRequest& request);
};
constexpr ScanFormat kScanFormats[] = {
    {"ply", ".ply", &ReadPly},
};

std::string SupportedFormats() {
  std::string list;
  for (const ScanFormat& format : kScanFormats) {
    list += (list.empty() ? "" : ", ") + std::string(format.name) + " (" + std::string(format.extension) + ")";
  }
  return list;
}

std::string LowerExtension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string extension = path.substr(dot);
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

Expected<const ScanFormat*> ChooseFormat(const std::string& path, const std::string& name) {
  if (name != "auto") {
    for (const ScanFormat& format : kScanFormats) {
      if (format.name == name) return &format;
    }
    return Status::Unsupported(std::string(kId) + ": unknown format '" + name +
                               "'; supported now: auto, " + SupportedFormats());
  }
  const std::string extension = LowerExtension(path);
  for (const ScanFormat& format : kScanFormats) {
    if (format.extension == extension) return &format;
  }
  return Status::Unsupported(std::string(kId) + ": cannot read '" + path + "': " +
                             (extension.empty() ? std::string("no file extension")
                                                : "unsupported extension '" + extension + "'") +
                             "; formats supported now: " + SupportedFormats());
}

std::string ParamsSchema() {
  nlohmann::json formats = nlohmann::json::array({"auto"});
  for (const ScanFormat& format : kScanFormats) formats.push_back(std::string(format.name));
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
              "The scan file, relative to the file that names it. Coordinates in meters. "
              "Keyed by content, so renaming or moving it keeps the cache."}}},
           {"format",
            {{"type", "string"},
             {"enum", formats},
             {"default", "auto"},
             {"description", "File format; 'auto' decides by the file extension."}}},
           {"drop_invalid",
            {{"type", "boolean"},
             {"default", false},
             {"description",
              "Drop points with NaN or infinite coordinates (counted as dropped_points) "
              "instead of failing on the first one."}}},
       }},
  };
  return schema.dump();
}

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const std::string path, StringParam(ctx, kId, "path"));
  PB_ASSIGN_OR_RETURN(const std::string format_name, StringParam(ctx, kId, "format", "auto"));
  PB_ASSIGN_OR_RETURN(const bool drop_invalid, BoolParam(ctx, kId, "drop_invalid", false));
  PB_ASSIGN_OR_RETURN(const ScanFormat* format, ChooseFormat(path, format_name));

  PB_PHASE(ctx, "io");
  ReadRequest request;
  request.drop_invalid = drop_invalid;
  request.progress = [&ctx](double fraction) { ctx.progress(0.9 * fraction); };
  PB_ASSIGN_OR_RETURN(ReadOutcome outcome, format->read(path, request));
  const PointCloud& points = outcome.points;

  PB_RETURN_IF_ERROR(WritePlyPoints(ctx.output_path("points", "points.ply"), points));
  ctx.set_output_meta("points", {{"origin", points.origin},
                                 {"points", points.size()},
                                 {"has_normals", points.has_normals()},
                                 {"has_colors", points.has_colors()},
                                 {"source_format", std::string(format->name)}});
  ctx.counter("points", static_cast<double>(points.size()));
  ctx.counter("dropped_points", static_cast<double>(outcome.dropped_points));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType ReadPointsStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Read a scan file (PLY) into points";
  type.doc =
      "Reads a colored laser scan into the `points` artifact: positions in meters, and normals "
      "and 8-bit sRGB colors when the file has them. Supported now: PLY (ascii, binary little "
      "and big endian; any scalar types; unknown elements and properties are ignored).\n\n"
      "Double-precision (e.g. georeferenced) coordinates are stored as float32 offsets from an "
      "origin at the scan's bounding-box center rounded to 1 m, which keeps float32 precision "
      "(about 1e-7 of the scan's extent) for any location on Earth; the "
      "origin travels in the artifact.\n\n"
      "Counters: `points` (points kept), `dropped_points` (non-finite coordinates, with "
      "drop_invalid).";
  type.params_schema = ParamsSchema();
  type.outputs = {{"points", "points", "The scan's points (binary PLY with origin).", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
