// Typed access to a stage's effective parameters.
//
// The engine validates `with:` against the stage's schema and fills defaults
// before a stage runs, so these lookups normally just read; a missing or
// mistyped value still becomes a Status naming the stage and the parameter,
// never an exception.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "base/status.h"
#include "engine/stage.h"
#include "stages/geometry/core/image.h"

namespace pb {

// `fallback` is used when the parameter is absent; without one, absence is
// Status::Invalid.
Expected<std::string> StringParam(const StageContext& ctx, std::string_view stage_id, const char* name,
                                  std::optional<std::string> fallback = std::nullopt);
Expected<double> NumberParam(const StageContext& ctx, std::string_view stage_id, const char* name,
                             std::optional<double> fallback = std::nullopt);
Expected<bool> BoolParam(const StageContext& ctx, std::string_view stage_id, const char* name,
                         std::optional<bool> fallback = std::nullopt);

// A whole number in [min, max] (JSON has one number type, so 16.0 counts as
// 16); without `max`, any whole number >= min up to 2^53. Out of range or
// fractional is Status::Invalid naming the range.
Expected<int64_t> IntegerParam(const StageContext& ctx, std::string_view stage_id, const char* name,
                               std::optional<int64_t> fallback, int64_t min,
                               std::optional<int64_t> max = std::nullopt);

// The file of input `port`: `preferred_file` when the artifact has one of that
// name (synth.scan's truth is mesh.ply + scene.json), else its first file;
// Status::Invalid if the input is missing or empty.
Expected<std::string> InputFilePath(const StageContext& ctx, std::string_view stage_id,
                                    std::string_view port, std::string_view preferred_file = "");

// The artifact's own name of input file `path` (e.g. "color.png"): in the
// cache, files are stored under their content digest without an extension,
// so formats must be decided from this name, not from the path.
std::string InputFileName(const StageContext& ctx, std::string_view port, const std::string& path);

// Reads input `port`'s image (PNG or OpenEXR, by the artifact's file name);
// errors name the stage and port.
Expected<Image> ReadInputImage(const StageContext& ctx, std::string_view stage_id,
                               std::string_view port);

}  // namespace pb
