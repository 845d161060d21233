#include "stages/geometry/io/scan_read.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "stages/geometry/core/text_parse.h"
#include "stages/geometry/io/e57.h"
#include "stages/geometry/io/las.h"
#include "stages/geometry/io/pcd.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/io/ptx.h"
#include "stages/geometry/io/xyz.h"

namespace pb {
namespace {

// PLY's reader also reads meshes, so it has its own result type.
Expected<ScanReadResult> ReadPlyScan(const std::string& path, const ScanReadOptions& options) {
  PlyReadOptions ply_options;
  ply_options.drop_invalid_points = options.drop_invalid_points;
  ply_options.progress = options.progress;
  ply_options.infer_stations = options.infer_stations;
  PB_ASSIGN_OR_RETURN(PlyPoints ply, ReadPlyPoints(path, ply_options));
  ScanReadResult result;
  result.points = std::move(ply.points);
  result.dropped_points = ply.report.dropped_points;
  result.format = "ply " + ply.report.format;
  result.warnings = std::move(ply.report.warnings);
  return result;
}

constexpr ScanFormat kScanFormats[] = {
    {"ply", ".ply", &ReadPlyScan},
    {"pcd", ".pcd", &ReadPcd},
    {"xyz", ".xyz .txt .pts .csv", &ReadXyz},
    {"ptx", ".ptx", &ReadPtx},
    {"e57", ".e57", &ReadE57},
    // LAZ is LAS with compressed records: the LAS reader reads both (laz.h).
    {"las", ".las .laz", &ReadLas},
};

bool HasExtension(const ScanFormat& format, std::string_view extension) {
  std::string_view list = format.extensions;
  while (!list.empty()) {
    const size_t space = list.find(' ');
    if (list.substr(0, space) == extension) return true;
    if (space == std::string_view::npos) break;
    list.remove_prefix(space + 1);
  }
  return false;
}

}  // namespace

std::span<const ScanFormat> ScanFormats() { return kScanFormats; }

std::string SupportedScanFormats() {
  std::string list;
  for (const ScanFormat& format : kScanFormats) {
    list += (list.empty() ? "" : ", ") + std::string(format.name) + " (" +
            std::string(format.extensions) + ")";
  }
  return list;
}

Expected<const ScanFormat*> FindScanFormat(const std::string& path, std::string_view name) {
  if (name != "auto") {
    for (const ScanFormat& format : kScanFormats) {
      if (format.name == name) return &format;
    }
    return Status::Unsupported(path + ": unknown format '" + std::string(name) +
                               "'; supported: auto, " + SupportedScanFormats());
  }
  const std::string extension = LowerExtension(path);
  for (const ScanFormat& format : kScanFormats) {
    if (HasExtension(format, extension)) return &format;
  }
  return Status::Unsupported("cannot read '" + path + "': " +
                             (extension.empty() ? std::string("no file extension")
                                                : "unsupported extension '" + extension + "'") +
                             "; formats supported now: " + SupportedScanFormats());
}

Expected<ScanReadResult> ReadScan(const std::string& path, std::string_view format,
                                  const ScanReadOptions& options) {
  PB_ASSIGN_OR_RETURN(const ScanFormat* chosen, FindScanFormat(path, format));
  return chosen->read(path, options);
}

std::vector<std::string> DeclareStation(const std::array<double, 3>& position, PointCloud* points) {
  std::vector<std::string> warnings;
  if (points->has_stations())
    warnings.push_back("the file's " + std::to_string(points->stations.size()) +
                       " station(s) replaced by the declared `station`");
  points->stations = {position};
  points->station_ids.assign(points->size(), 0);
  if (!points->empty()) {
    // The scanner stands among what it scanned: farther from the scan's
    // bounding box than its diagonal is a frame or unit mistake, most likely.
    const Bounds bounds = AbsoluteBounds(*points);
    double outside = 0, diagonal = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const double c = position[axis];
      const double gap = std::max({bounds.min_m[axis] - c, c - bounds.max_m[axis], 0.0});
      outside += gap * gap;
      const double extent = bounds.max_m[axis] - bounds.min_m[axis];
      diagonal += extent * extent;
    }
    if (std::sqrt(outside) > std::sqrt(diagonal)) {
      char text[200];
      std::snprintf(text, sizeof text,
                    "the declared station lies %.3g from the scan's bounding box, farther than its "
                    "diagonal (%.3g, file units): another frame or unit?",
                    std::sqrt(outside), std::sqrt(diagonal));
      warnings.emplace_back(text);
    }
  }
  return warnings;
}

}  // namespace pb
