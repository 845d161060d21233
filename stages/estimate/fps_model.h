// Frame-rate model: how fast a headset draws a textured mesh, from its
// triangle count, and whether its texture maps fit the headset's memory.
//
// The model (docs/fps.md has the calibration and what it ignores):
//
//   fps = min(refresh_hz, triangles_per_s / triangles)
//
// where `triangles` is every triangle of the mesh (no culling) and
// `triangles_per_s` is the device's throughput counting each triangle once
// per displayed frame (the frame shows both eyes, so the per-eye cost is in
// the constant). Texture memory is the maps' texels, with their full mip
// chains when the device profile says mips are used, times the bytes per
// texel of the GPU format the profile assumes.
//
// Device profiles (configs/devices/*.yaml) are YAML mappings:
//
//   name: oculus-go                    string, required
//   description: "..."                 string, optional
//   triangles_per_s: 66700000          number > 0, required
//   refresh_hz: 60                     number > 0, required
//   texture_budget_bytes: 1073741824   integer >= 0, required
//   texture_bytes_per_texel: 4         number > 0, default 4 (RGBA8)
//   mipmaps: true                      boolean, default true
//
// Unknown keys are errors (a typo would otherwise silently keep a default).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "base/status.h"

namespace pb {

struct DeviceProfile {
  std::string name;
  std::string description;
  double triangles_per_s = 0;  // mesh triangles per second, one stereo frame counts once
  double refresh_hz = 0;       // the display's cap, frames per second
  int64_t texture_budget_bytes = 0;    // GPU memory the model's textures may take
  double texture_bytes_per_texel = 4;  // of the assumed GPU format (RGBA8 = 4, ASTC 4x4 = 1)
  bool mipmaps = true;                 // maps carry full mip chains
};

// Parses a device profile. `source` names the text in errors, which read
// `source:line:column: ...` (or `source: ...` for a missing key). Values are checked:
// throughput and refresh > 0, budget >= 0, bytes per texel > 0.
Expected<DeviceProfile> ParseDeviceProfile(std::string_view text, const std::string& source);
// Reads and parses the file at `path` (Status::NotFound if it is missing).
Expected<DeviceProfile> ReadDeviceProfile(const std::string& path);

// The size of one texture map, in texels.
struct TextureSize {
  int width = 0;
  int height = 0;
};

// Texels of a width x height map, plus its mip chain (each level halves both
// sides, rounding down, at least 1, down to 1x1) when `mipmaps`.
uint64_t TextureTexels(TextureSize size, bool mipmaps);

// GPU memory of `maps` on `device`, bytes: the sum over maps of their texels
// (with mips per the profile) times texture_bytes_per_texel, rounded up.
uint64_t TextureBytes(const DeviceProfile& device, std::span<const TextureSize> maps);

// min(refresh_hz, triangles_per_s / triangles); refresh_hz for 0 triangles.
double EstimateFps(const DeviceProfile& device, uint64_t triangles);

struct FpsEstimate {
  uint64_t triangles = 0;
  int texture_width = 0;   // the largest width of the maps (0 without maps)
  int texture_height = 0;  // the largest height of the maps (0 without maps)
  uint64_t texture_bytes = 0;
  bool fits_texture_budget = true;  // texture_bytes <= texture_budget_bytes
  double fps = 0;
};

// A map already in a GPU block format (a KTX2 map of the exported model):
// its GPU bytes are known from the file (all its stored mip levels,
// stages/geometry/io/ktx2.h), not from the profile's bytes per texel.
struct CompressedMap {
  TextureSize size;
  uint64_t gpu_bytes = 0;
};

// texture_bytes = TextureBytes(device, maps) + the compressed maps' gpu_bytes;
// the largest width and height over both.
FpsEstimate EstimateFrameRate(const DeviceProfile& device, uint64_t triangles,
                              std::span<const TextureSize> maps,
                              std::span<const CompressedMap> compressed = {});

}  // namespace pb
