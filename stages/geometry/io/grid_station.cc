#include "stages/geometry/io/grid_station.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace pb {

void GridStationTest::Keep(Steps& steps, double step) {
  if (steps.seen++ % steps.stride != 0) return;
  steps.kept.push_back(static_cast<float>(step));
  if (steps.kept.size() < kKeep) return;
  // Every other kept step, and half the sampling from now on: the kept
  // steps stay an even sample of the scan, in bounded memory.
  size_t out = 0;
  for (size_t i = 0; i < steps.kept.size(); i += 2) steps.kept[out++] = steps.kept[i];
  steps.kept.resize(out);
  steps.stride *= 2;
}

void GridStationTest::Add(int64_t row, int64_t column, const double position[3]) {
  const double range =
      std::sqrt(position[0] * position[0] + position[1] * position[1] + position[2] * position[2]);
  if (!(range > 0) || !std::isfinite(range)) {
    Break();
    return;
  }
  const double direction[3] = {position[0] / range, position[1] / range, position[2] / range};
  if (have_previous_) {
    const int64_t rows = row - previous_row_, columns = column - previous_column_;
    const int64_t cells = std::abs(rows) + std::abs(columns);
    if ((rows == 0 || columns == 0) && cells >= 1 && cells <= 4) {
      const double* a = previous_direction_;
      const double cross[3] = {a[1] * direction[2] - a[2] * direction[1],
                               a[2] * direction[0] - a[0] * direction[2],
                               a[0] * direction[1] - a[1] * direction[0]};
      const double sine =
          std::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]);
      const double cosine = a[0] * direction[0] + a[1] * direction[1] + a[2] * direction[2];
      Keep(steps_[rows != 0 ? 0 : 1], std::atan2(sine, cosine) / double(cells));
    }
  }
  have_previous_ = true;
  previous_row_ = row;
  previous_column_ = column;
  std::copy(direction, direction + 3, previous_direction_);
}

GridStationTest::Verdict GridStationTest::Decide() const {
  Verdict verdict;
  verdict.regular = 1;
  for (const Steps& steps : steps_) {
    verdict.steps += steps.seen;
    if (steps.seen < kMinSteps) continue;
    std::vector<float> sorted = steps.kept;
    const size_t middle = sorted.size() / 2;
    std::nth_element(sorted.begin(), sorted.begin() + middle, sorted.end());
    const double median = sorted[middle];
    size_t regular = 0;
    if (median > 0) {
      for (float step : steps.kept) {
        regular += step >= median / kFactor && step <= median * kFactor;
      }
    }
    verdict.regular = std::min(verdict.regular, double(regular) / double(steps.kept.size()));
    verdict.decided = true;
  }
  if (!verdict.decided) verdict.regular = 0;
  verdict.at_origin = verdict.decided && verdict.regular >= kRegularFraction;
  return verdict;
}

std::string GridStationTest::Verdict::Describe() const {
  char text[200];
  if (!decided) {
    std::snprintf(text, sizeof text,
                  "%zu steps between neighbours of its row/column grid, too few to tell", steps);
  } else {
    std::snprintf(text, sizeof text,
                  "seen from there, %.1f %% of the %zu steps between neighbours of its row/column "
                  "grid are within %.1fx of their median angle; %.0f %% needed",
                  100 * regular, steps, kFactor, 100 * kRegularFraction);
  }
  return text;
}

}  // namespace pb
