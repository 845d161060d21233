// Frames: the `frames` artifact, a set of named views of one scene (rendered
// by render.frames, compared by metrics.image). On disk, in one artifact:
//
//   frames.json
//     {
//       "format": "pointbake-frames",       <- signature
//       "version": 1,                       <- format version
//       "width": 1024, "height": 1024,      <- every image has this size
//       "frames": [
//         {"name": "door", "file": "door.png",
//          "eye": [x, y, z], "target": [x, y, z],   <- optional viewpoint
//          "up": [x, y, z], "fov_deg": 75,          <- (scene file units)
//          "depth": "door.depth.exr",               <- optional depth map
//          "samples": "door.samples.png"},          <- optional sample mask
//         ...
//       ]
//     }
//   door.png, ...   8-bit sRGB PNGs, RGB or RGBA, width x height each
//   door.depth.exr  optional: one float channel, width x height, the view
//                   depth in meters (distance along the camera's forward
//                   axis) of the nearest surface the pixel's samples hit; 0
//                   where nothing was hit (render.frames `depth: true`,
//                   render.splats). Readers of version 1 without this key
//                   ignore it.
//   door.samples.png optional: one 8-bit gray channel, width x height, 255
//                   where the centre of a sample of the drawn point cloud
//                   that no nearer surface hides projects into the pixel,
//                   0 elsewhere (render.splats): the pixels the scan has
//                   evidence of, as against its disks' interpolation
//                   (metrics.image counts hole pixels on them). Readers of
//                   version 1 without this key ignore it.
//
// Names are unique and non-empty; files are plain file names (no folder),
// ending in ".png", unique, not "frames.json". Alpha, when present, is 255
// where the renderer drew geometry and 0 on background; metrics.image
// ignores it and measures all pixels (docs/metrics.md says why). Readers
// ignore unknown keys, so later versions may add some without a new version.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "base/env.h"
#include "base/status.h"
#include "stages/geometry/core/image.h"

namespace pb {

inline constexpr const char* kFramesFormat = "pointbake-frames";
inline constexpr int kFramesVersion = 1;
inline constexpr const char* kFramesIndexFile = "frames.json";

// Where the view was taken from, as in a scene's `viewpoints:` entry.
struct FrameViewpoint {
  std::array<double, 3> eye{};
  std::array<double, 3> target{};
  std::optional<std::array<double, 3>> up;
  std::optional<double> fov_deg;
};

struct FrameEntry {
  std::string name;
  std::string file;  // PNG file name inside the artifact
  std::optional<FrameViewpoint> viewpoint;
  std::string depth_file;  // "" or the depth map's file name (plain, ending in .exr)
  std::string samples_file;  // "" or the sample mask's file name (plain, ending in .png)
};

struct FramesIndex {
  int width = 0;
  int height = 0;
  std::vector<FrameEntry> frames;
};

struct Frame {
  FrameEntry entry;
  Image image;  // kU8, 3 or 4 channels, width x height of the set
  Image depth;  // empty, or kF32 1 channel, width x height: with entry.depth_file
  Image samples;  // empty, or kU8 1 channel, width x height: with entry.samples_file
};

struct FrameSet {
  int width = 0;
  int height = 0;
  std::vector<Frame> frames;

  // The frame named `name`, or nullptr.
  const Frame* find(std::string_view name) const;
};

// Status::Invalid naming the problem (duplicate name, bad file name, size).
Status Validate(const FramesIndex& index);

std::string FramesIndexToJson(const FramesIndex& index);
// `source` names the text in errors (a path). Status::Corrupt for malformed
// JSON or a wrong signature, Status::Unsupported for a newer version,
// Status::Invalid for values that break the rules above.
Expected<FramesIndex> FramesIndexFromJson(std::string_view json_text, const std::string& source);

// Maps a file name of the artifact to its path (artifact files may live
// apart, e.g. in a content-addressed cache).
using FramesFilePath = std::function<std::string(const std::string& file_name)>;

// Reads frames.json at `index_path` and every image it names; `path_of`
// locates the images (default: the folder of `index_path`). Errors name the
// file: a missing PNG (Status::NotFound), one of the wrong size or pixel
// format (Status::Invalid).
Expected<FrameSet> ReadFrames(const std::string& index_path, const FramesFilePath& path_of = {});

// Writes every image and frames.json to `path_of(file)` as one durable set
// (WriteFilesAtomic, base/env.h; frames.json renamed last): a failed write
// leaves the earlier files as they were.
Status WriteFrames(const FrameSet& frames, const FramesFilePath& path_of, Env* env = Env::Default());
// The same into folder `dir` (which must exist).
Status WriteFrames(const std::string& dir, const FrameSet& frames, Env* env = Env::Default());

}  // namespace pb
