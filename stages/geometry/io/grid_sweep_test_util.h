// Grid-station test support, for tests only (no production code includes
// it): one terrestrial scanner's sweep, the records a structured scan keeps
// as (row, column, position). Used by grid_station_test.cc and by the E57
// and PLY readers' tests, which write the same sweep into their formats.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

namespace pb::testing {

// A scene of boxes at different depths: the range of grid cell (row,
// column) jumps every few cells, as at the edges of real objects.
inline double SweepRange(int64_t row, int64_t column) {
  return 2.0 + 2.5 * double((row / 10 + column / 15) % 3) + 0.01 * std::sin(0.3 * double(row));
}

// The position of record (row, column) of a sweep from `station`: a
// vertical line of records per azimuth step, 0.01 rad down a column from
// 0.4 rad, `azimuth_step` rad along a row; relative to the frame's origin.
inline std::array<double, 3> SweptPoint(const double station[3], int64_t row, int64_t column,
                                        double azimuth_step = 0.02) {
  const double elevation = 0.4 - 0.01 * double(row), azimuth = azimuth_step * double(column);
  const double r = SweepRange(row, column);
  return {station[0] + r * std::cos(elevation) * std::cos(azimuth),
          station[1] + r * std::cos(elevation) * std::sin(azimuth),
          station[2] + r * std::sin(elevation)};
}

}  // namespace pb::testing
