// The common shape of scan-file readers (PLY, PCD, PTS/XYZ, PTX, E57, LAS):
// each format's header declares
//   Expected<ScanReadResult> Read<Format>(const std::string& path,
//                                         const ScanReadOptions& options);
// and the one dispatch table below (ScanFormats) picks one by name or by
// extension, for io.read_points and its parameter schema.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "stages/geometry/core/point_cloud.h"

namespace pb {

struct ScanReadOptions {
  // Drop points with NaN/Inf coordinates (counted) instead of failing on the
  // first one. Formats with a validity convention (PTX 0,0,0; PCD NaN in
  // organized clouds; E57 invalidState) drop those always and count them.
  bool drop_invalid_points = false;
  // Fraction done in [0, 1], called every few MB; may be empty.
  std::function<void(double)> progress;
  // XYZ/TXT/PTS only: column names in order, e.g. "x y z r g b" or
  // "x y z i r g b nx ny nz"; empty = the format's default / auto-detect.
  std::string columns;
  // False when the caller sets the stations itself (io.read_points
  // `station: none` or a declared position): the readers then skip the grid
  // test that finds an unposed scan's scanner (grid_station.h) and say
  // nothing about stations. A file's poses still move its points.
  bool infer_stations = true;
};

struct ScanReadResult {
  PointCloud points;
  uint64_t dropped_points = 0;        // points with NaN/Inf coordinates dropped (drop_invalid_points)
  // Cells of a scan grid the file marks as measuring nothing (PTX 0 0 0, a
  // NaN in an organized PCD, E57 invalidState 1 or 2): always left out, not
  // an error and not in dropped_points; a structured scan has many (sky,
  // windows, out of range).
  uint64_t no_return_points = 0;
  std::vector<std::string> warnings;  // shown to the user, e.g. "3 scans merged"
  std::string format;                 // e.g. "pcd binary_compressed", "e57"
  // Points (ascending indices) whose color / intensity the file marks as no
  // measurement (E57 isColorInvalid / isIntensityInvalid); their values in
  // `points` are whatever the file held. io.read_points fills them from
  // their nearest valid neighbours.
  std::vector<size_t> colorless_points;
  std::vector<size_t> intensityless_points;
};

// One row of the dispatch table: a new scan format is a reader and a row.
struct ScanFormat {
  std::string_view name;        // the `format:` value, e.g. "xyz"
  std::string_view extensions;  // lower case, with the dot, space separated
  Expected<ScanReadResult> (*read)(const std::string& path, const ScanReadOptions& options);
};

// Every scan format, in the order messages list them.
std::span<const ScanFormat> ScanFormats();

// "ply (.ply), pcd (.pcd), xyz (.xyz .txt .pts .csv), ..." for messages.
std::string SupportedScanFormats();

// The format called `name`, or for "auto" the one whose extensions hold
// `path`'s (case-insensitive). Status::Unsupported naming the file, the
// unknown name or extension, and the supported formats otherwise.
Expected<const ScanFormat*> FindScanFormat(const std::string& path, std::string_view name);

// Declares one scanner station at `position` (the points' own coordinates
// and units, as read) for every point of `points`, replacing the file's (a
// one-station scan exported without its pose). Returns what to warn of,
// without the file's name: that the file's stations were replaced, and that
// the position lies farther from the scan's bounding box than its diagonal
// (another frame or unit, most likely). io.read_points `station` and
// `pointbake scene --station` both declare through it.
std::vector<std::string> DeclareStation(const std::array<double, 3>& position, PointCloud* points);

// Reads `path` with FindScanFormat(path, format)'s reader.
Expected<ScanReadResult> ReadScan(const std::string& path, std::string_view format,
                                  const ScanReadOptions& options);

}  // namespace pb
