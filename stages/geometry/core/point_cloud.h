// PointCloud: the `points` artifact in memory.
//
// Positions are float32 meters relative to a double-precision `origin`, so a
// georeferenced scan (coordinates in the 10^5..10^7 m range) keeps sub-
// millimeter precision: absolute = origin + position. Attributes are stored
// as flat arrays (structure of arrays), one entry per point, interleaved per
// attribute:
//   positions: 3 floats per point (x, y, z), meters, relative to origin
//   normals:   empty, or 3 floats per point (unit length)
//   colors:    empty, or 3 bytes per point (r, g, b; sRGB 0..255)
//   intensities: empty, or 1 float per point (scanner return strength,
//              normalized to [0, 1])
//   station_ids: empty, or 1 per point: index into `stations` of the scanner
//              position that saw the point (normals are oriented toward it)
//   stations:  scanner positions, absolute meters (not relative to origin)
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "base/status.h"

namespace pb {

struct PointCloud {
  std::array<double, 3> origin{};  // meters
  std::vector<float> positions;    // xyz interleaved, meters, relative to origin
  std::vector<float> normals;      // empty or 3 per point
  std::vector<uint8_t> colors;     // empty or rgb per point
  std::vector<float> intensities;  // empty or 1 per point, [0, 1]
  std::vector<uint16_t> station_ids;  // empty or 1 per point, index into stations
  std::vector<std::array<double, 3>> stations;  // absolute meters

  size_t size() const { return positions.size() / 3; }
  bool empty() const { return positions.empty(); }
  bool has_normals() const { return !normals.empty(); }
  bool has_colors() const { return !colors.empty(); }
  bool has_intensities() const { return !intensities.empty(); }
  bool has_stations() const { return !station_ids.empty(); }
};

// Axis-aligned bounds in meters. Empty bounds have min = +inf, max = -inf.
struct Bounds {
  std::array<double, 3> min_m{};
  std::array<double, 3> max_m{};
  bool empty() const { return min_m[0] > max_m[0]; }
  std::array<double, 3> center_m() const;
  std::array<double, 3> extent_m() const;  // max - min, zeros when empty
};

// Bounds of xyz-interleaved positions (3 floats per point), in the positions'
// own frame.
Bounds BoundsOf(std::span<const float> positions_xyz);
// Bounds relative to the cloud's origin / in absolute coordinates.
Bounds LocalBounds(const PointCloud& cloud);
Bounds AbsoluteBounds(const PointCloud& cloud);
// Robust bounds relative to the origin: per axis the `fraction` and
// 1 - `fraction` quantiles of the positions (the k = round(q (m - 1))-th
// smallest), over every step-th point so that at most ~10^6 are sorted, step
// = max(1, size / 10^6). Strays and a far field of a few points do not
// stretch them. Empty bounds for an empty cloud.
Bounds RobustLocalBounds(const PointCloud& cloud, double fraction);

// A cloud read in another length unit, in meters: origin, positions and
// stations times `meters_per_unit` (base/units.h); normals are directions
// and stay.
void ConvertToMeters(double meters_per_unit, PointCloud* cloud);

// Checks that attribute arrays agree with the point count; Status::Invalid
// naming the attribute otherwise.
Status Validate(const PointCloud& cloud);

// Status::Invalid "<what>: point N has a non-finite coordinate" for the first
// such point, for the steps that hand the cloud to a library that would not
// say which point (PCL, Open3D).
Status CheckFinitePositions(const PointCloud& cloud, std::string_view what);

// The points `indices` (each < cloud.size()) in that order, with every
// attribute; origin and stations copied.
PointCloud SelectPoints(const PointCloud& cloud, std::span<const uint32_t> indices);

}  // namespace pb
