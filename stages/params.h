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

// Defaults are stated once, in the stage's parameter schema: the engine fills
// them in before a stage runs (ApplyDefaults, engine/schema.h), so these read
// what is there and an absent parameter is Status::Invalid (a parameter
// without a default, which may be left out, is looked up only when given).
Expected<std::string> StringParam(const StageContext& ctx, std::string_view stage_id, const char* name);
Expected<double> NumberParam(const StageContext& ctx, std::string_view stage_id, const char* name);
Expected<bool> BoolParam(const StageContext& ctx, std::string_view stage_id, const char* name);

// The whole numbers an integer parameter may take: [min, max], or without
// `max` any whole number >= min up to 2^53.
struct IntegerRange {
  int64_t min = 0;
  std::optional<int64_t> max;
};
// A whole number in `range` (JSON has one number type, so 16.0 counts as 16).
// Out of range or fractional is Status::Invalid naming the range.
Expected<int64_t> IntegerParam(const StageContext& ctx, std::string_view stage_id, const char* name,
                               IntegerRange range);

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
