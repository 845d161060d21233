// Length units of scene files and scan files: the names a scene's `units:`
// and io.read_points' `units` accept, and meters per unit of each. The
// project computes in meters; a scan in another unit is converted when it is
// read, and the scene's viewpoints with it (engine/workflow.h, LoadScene).
#pragma once

#include <array>
#include <optional>
#include <string_view>
#include <utility>

namespace pb {

inline constexpr std::array<std::pair<std::string_view, double>, 5> kLengthUnits = {{
    {"m", 1.0},
    {"mm", 0.001},
    {"cm", 0.01},
    {"ft", 0.3048},   // international foot
    {"in", 0.0254},   // international inch
}};

// Meters per `unit`, or nullopt for a name not in kLengthUnits.
inline std::optional<double> MetersPerUnit(std::string_view unit) {
  for (const auto& [name, meters] : kLengthUnits)
    if (name == unit) return meters;
  return std::nullopt;
}

}  // namespace pb
