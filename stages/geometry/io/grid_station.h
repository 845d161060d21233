// Where the scanner of a structured scan stood, when the file does not say.
//
// A terrestrial scanner sweeps a grid of directions: every record has a row
// and a column, and neighbouring cells are a fixed angle apart as seen from
// the scanner, whatever their ranges (the pump sample: 0.0012 rad down a
// column, 0.0039 rad along a row). Seen from anywhere else the angle between
// two neighbours' directions shrinks with their range and jumps at every
// depth edge. So when nearly all neighbour steps, seen from the scan's own
// origin, lie within a factor of 1.5 of their median, the grid was swept
// from there: the scanner stood at the origin of the scan's frame. A
// one-station E57 export often has no pose (the standard's identity), and
// then the scanner is exactly that origin; a scan whose registration was
// baked into its coordinates fails the test (its origin is somewhere else)
// and gets no station, as before.
//
// A camera's grid (an organized RGB-D frame) passes too: a pinhole's steps
// shrink toward the corners by cos^2 of the off-axis angle, 0.75 at 30
// degrees, inside the factor.
//
// What the stations give: normals oriented toward the scanner
// (points.normals), and lines of sight for mesh.decimate's holes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace pb {

class GridStationTest {
 public:
  // Neighbour steps below this count in both grid directions: no verdict.
  static constexpr size_t kMinSteps = 500;
  // A step counts as regular within [median / kFactor, median * kFactor] ...
  static constexpr double kFactor = 1.5;
  // ... and the origin is the scanner's when this fraction of the steps of
  // each direction with kMinSteps is regular (the pump: 99.9 % and 100 %;
  // 20 cm off its origin: 97 %; at its centroid: 50 %).
  static constexpr double kRegularFraction = 0.98;

  // The scan's records in file order: grid cell and position in the scan's
  // own frame (before any pose). Records two to four cells apart along a
  // row or a column count as that many steps.
  void Add(int64_t row, int64_t column, const double position[3]);
  // A record left out (invalid): the next one has no predecessor.
  void Break() { have_previous_ = false; }

  struct Verdict {
    bool decided = false;  // a direction had kMinSteps steps
    bool at_origin = false;
    size_t steps = 0;              // neighbour steps measured (both directions)
    double regular = 0;            // the lower regular fraction of the decided directions
    std::string Describe() const;  // "seen from there, 99.9 % of the 154190 steps ...", or too few
  };
  Verdict Decide() const;

 private:
  // Steps (radians per cell) down columns [0] and along rows [1]; above
  // kKeep a direction keeps every other step and halves its sampling.
  static constexpr size_t kKeep = size_t{1} << 20;
  struct Steps {
    std::vector<float> kept;
    uint64_t seen = 0;
    uint64_t stride = 1;
  };
  void Keep(Steps& steps, double step);

  Steps steps_[2];
  bool have_previous_ = false;
  int64_t previous_row_ = 0, previous_column_ = 0;
  double previous_direction_[3] = {0, 0, 0};
};

}  // namespace pb
