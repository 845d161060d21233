#include "stages/geometry/io/grid_station.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace pb {

double GridStationTest::Angle(const float a[3], const float b[3]) {
  const double d[3] = {double(a[0]) - b[0], double(a[1]) - b[1], double(a[2]) - b[2]};
  const double chord = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (chord < 0.1) return chord + chord * chord * chord / 24;
  const double cross[3] = {double(a[1]) * b[2] - double(a[2]) * b[1],
                           double(a[2]) * b[0] - double(a[0]) * b[2],
                           double(a[0]) * b[1] - double(a[1]) * b[0]};
  const double sine = std::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]);
  const double cosine = double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2];
  return std::atan2(sine, cosine);
}

void GridStationTest::Step(std::unordered_map<int64_t, Last>& lines, int64_t line, int64_t cell,
                           const float direction[3], Count& count) {
  auto found = lines.find(line);
  if (found == lines.end()) {
    if (lines.size() >= kMaxLines) return;
    found = lines.emplace(line, Last{}).first;
    found->second.cell = cell;
    std::copy(direction, direction + 3, found->second.direction);
    return;
  }
  Last& last = found->second;
  const int64_t cells = std::abs(cell - last.cell);
  float step = 0;
  if (cells >= 1 && cells <= 4) {
    step = static_cast<float>(Angle(last.direction, direction) / double(cells));
    if (last.step > 0) {
      ++count.steps;
      count.regular += step >= last.step / kFactor && step <= last.step * kFactor;
    }
  }
  last.cell = cell;
  last.step = step;  // 0 after a jump of more than four cells: the next step starts afresh
  std::copy(direction, direction + 3, last.direction);
}

void GridStationTest::Add(double row, double column, const double position[3]) {
  constexpr double kLimit = 9007199254740992.0;  // 2^53: exact in a double and an int64
  if (!(std::abs(row) < kLimit) || !(std::abs(column) < kLimit)) return;
  const double range =
      std::sqrt(position[0] * position[0] + position[1] * position[1] + position[2] * position[2]);
  if (!(range > 0) || !std::isfinite(range)) return;
  const float direction[3] = {float(position[0] / range), float(position[1] / range),
                              float(position[2] / range)};
  const auto r = static_cast<int64_t>(row), c = static_cast<int64_t>(column);
  Step(last_in_column_, c, r, direction, counts_[0]);  // down its column
  Step(last_in_row_, r, c, direction, counts_[1]);     // along its row
}

GridStationTest::Verdict GridStationTest::Decide() const {
  Verdict verdict;
  verdict.regular = 1;
  for (const Count& count : counts_) {
    verdict.steps += count.steps;
    if (count.steps < kMinSteps) continue;
    verdict.regular = std::min(verdict.regular, double(count.regular) / double(count.steps));
    verdict.decided = true;
  }
  if (!verdict.decided) verdict.regular = 0;
  verdict.at_origin = verdict.decided && verdict.regular >= kRegularFraction;
  return verdict;
}

std::string GridStationTest::Verdict::Describe() const {
  char text[220];
  if (!decided) {
    std::snprintf(text, sizeof text,
                  "%zu successive steps between neighbours of its row/column grid, too few to tell",
                  steps);
  } else {
    std::snprintf(text, sizeof text,
                  "seen from there, %.1f %% of the %zu steps between neighbours of its row/column "
                  "grid are within %.1fx of the step before them; %.0f %% needed",
                  100 * regular, steps, kFactor, 100 * kRegularFraction);
  }
  return text;
}

std::string GridStationTest::Verdict::Finding(const std::string& device) const {
  if (at_origin) return "its " + device + " taken at its frame's origin (" + Describe() + ")";
  return (decided ? "its grid does not show its frame's origin as its " + device + "'s ("
                  : "its grid cannot tell whether its frame's origin is its " + device + "'s (") +
         Describe() + ")";
}

std::string GridStationTest::Verdict::Warning(const std::string& subject,
                                              const std::string& device) const {
  if (at_origin) return subject + ": " + Finding(device);
  return "no " + device + " station: " + subject + ", and " + Finding(device) +
         "; io.read_points `station` can declare where it stood";
}

}  // namespace pb
