// Where the scanner of a structured scan stood, when the file does not say.
//
// A terrestrial scanner sweeps a grid of directions: every record has a row
// and a column, and seen from the scanner the angle between neighbouring
// cells is the same all along a row, and all along a column, whatever their
// ranges (along a row it is the azimuth step times the cosine of the row's
// elevation; down a column the elevation step). Seen from anywhere else it
// changes with the range and the slant of the surface, and jumps at every
// depth edge. So when nearly every step between neighbours, seen from the
// scan's own origin, is within a factor of 1.5 of the step before it in the
// same row or column, the grid was swept from there: the scanner stood at
// the origin of the scan's frame. A one-station E57 export often has no pose
// (the standard's identity), and then the scanner is exactly that origin; a
// scan whose registration was baked into its coordinates fails the test
// (its origin is somewhere else) and gets no station, as before.
//
// Measured on the pump sample (ranges 1-4 m, 1074 x 345 cells), the worse
// of its two directions: 99.9 % at its origin; 5 cm off 97.0 %; 20 cm off
// 92.9-96.3 %; 1.4 m off 87 %; at its centroid 57 %. The bar, 97 %, lets a
// scanner whose optical centre sits a few centimetres from its frame's
// origin through (a station that close orients normals and lines of sight
// as well) and refuses 20 cm. A camera's pixel grid passes too: a pinhole's
// step changes smoothly across the image.
//
// What the stations give: normals oriented toward the scanner
// (points.normals), and lines of sight for mesh.decimate's holes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <unordered_map>

namespace pb {

class GridStationTest {
 public:
  // Successive steps below this count in both grid directions: no verdict.
  static constexpr size_t kMinSteps = 500;
  // A step is regular within [previous / kFactor, previous * kFactor] ...
  static constexpr double kFactor = 1.5;
  // ... and the origin is the scanner's when this fraction of the steps of
  // each direction with kMinSteps is regular.
  static constexpr double kRegularFraction = 0.97;

  // The scan's valid records, in any order: grid cell and position in the
  // scan's own frame (before any pose). Each record is measured against the
  // last one added in its column and the last one in its row, when that is
  // one to four cells away (as many steps: a record the file left out, or
  // an invalid one not added, makes a longer step), and that step against
  // the line's previous one. A cell index that is not finite or beyond
  // 2^53, or a position at the origin, is ignored.
  void Add(double row, double column, const double position[3]);

  struct Verdict {
    bool decided = false;  // a direction had kMinSteps successive steps
    bool at_origin = false;
    size_t steps = 0;              // successive steps compared (both directions)
    double regular = 0;            // the lower regular fraction of the decided directions
    std::string Describe() const;  // "seen from there, 99.9 % of the 306000 ...", or too few
    // The verdict as the readers' warnings say it, for the `device` that
    // swept the grid ("scanner", "sensor"): "its scanner taken at its
    // frame's origin (...)", "its grid does not show its frame's origin as
    // its scanner's (...)" or "its grid cannot tell whether its frame's
    // origin is its scanner's (...)", the brackets Describe().
    std::string Finding(const std::string& device) const;
    // A one-grid file's warning: "<subject>: <finding>" when at the origin,
    // else "no <device> station: <subject>, and <finding>; io.read_points
    // `station` can declare where it stood".
    std::string Warning(const std::string& subject, const std::string& device) const;
  };
  Verdict Decide() const;

  // The angle between two unit directions, in radians. A scanner's steps
  // are small, and for a chord c = |a - b| below 0.1 the angle 2 asin(c / 2)
  // is c + c^3 / 24 to a relative 5e-7 at most (the next term, 3 c^5 / 640),
  // about what the directions' float rounding leaves of c; larger ones take
  // an arctangent, which per record and direction was most of a structured
  // PLY's read (bench/ply_read_bench).
  static double Angle(const float a[3], const float b[3]);

 private:
  // The last record of a row or column is remembered for at most this many
  // rows and columns (a grid has far fewer; garbage indices stop here).
  static constexpr size_t kMaxLines = size_t{1} << 21;
  struct Last {
    int64_t cell = 0;  // its column (in a row's entry) or row (in a column's)
    float step = 0;    // the line's last step (radians per cell), 0 before one
    float direction[3] = {0, 0, 0};
  };
  struct Count {
    uint64_t steps = 0;
    uint64_t regular = 0;
  };
  // Against the last record of one line (a row or column), then remembers
  // this one there.
  void Step(std::unordered_map<int64_t, Last>& lines, int64_t line, int64_t cell,
            const float direction[3], Count& count);

  Count counts_[2];  // down columns [0], along rows [1]
  std::unordered_map<int64_t, Last> last_in_column_, last_in_row_;
};

}  // namespace pb
