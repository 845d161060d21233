// Render: the deterministic CPU reference renderer behind render.frames. It
// draws a mesh (vertex colors, or a color map and a tangent-space normal
// map) the way a mobile GPU would, and draws the analytic ground truth of a
// synthetic scene (synth_scene.h) with the same camera, samples, light and
// encoding. docs/render.md is the long form.
//
// Camera (RenderCamera). Absolute scene coordinates, meters, double: the
// eye looks at `target`; `up` (default +z) fixes the roll; `fov_deg` is the
// vertical field of view of a square image of `size` x `size` pixels. Camera
// frame: right = normalize(cross(forward, up)), up' = cross(right, forward).
// Image: x = column to the right, y = row downward, row 0 at the top.
//
// Samples. Every pixel holds supersample x supersample samples on a regular
// grid: pixel (x, y) has samples at (x + (i + 0.5) / s, y + (j + 0.5) / s),
// i, j in [0, s). A pixel's color is the box average of its samples in
// linear light, then sRGB-encoded to 8 bits (round to nearest). Alpha is 255
// when any sample hit geometry, else 0; background samples count with the
// background color.
//
// Rasterization. Vertices go to the camera frame in double (the camera is
// first moved into mesh-local coordinates: eye - Mesh::origin), triangles
// are clipped at the near plane (kNearPlaneM in front of the eye) and
// covered samples are found with edge functions evaluated in the
// antisymmetric form orient(a, b, p) = (a - p) x (b - p), so two triangles
// sharing an edge cover the samples on it with no gap. Both faces are drawn
// (no culling: rooms are seen from inside); RenderStats counts the samples
// that see a face's back, which a viewer culling back faces would not show.
// Visibility: each sample keeps the minimum of (float view depth, triangle
// index) as one 64-bit key, so equal depths go to the lower triangle index
// and the picture does not depend on the order or thread that drew the
// triangles.
//
// Attributes are interpolated perspective-correctly with barycentrics from
// the exact ray-plane intersection of the sample's ray with the (unclipped)
// triangle. UV derivatives: the same for rays one output pixel to the right
// and below (a pixel's footprint, as 4x MSAA on a GPU; not one sample's).
//
// Textures (MipTexture). Color maps are sRGB-decoded to linear float; the
// mip chain halves each axis (floor, at least 1) with 2x2 box averages in
// linear light (an odd level's last row / column is dropped; an axis of 1
// averages its one texel with itself).
// Sampling: clamp to edge, bilinear within a level, linear between levels
// (trilinear); LOD = log2 of the longer of the two pixel-step UV derivatives
// in level-0 texels, clamped to [0, levels - 1]. Texel space (s, t) =
// (u * w - 0.5, (1 - v) * h - 0.5): v up, row 0 at the top (bake_raster.h).
// Interpolation uses a + (b - a) * f, which returns a constant exactly.
//
// Normal maps hold the tangent-space normal (N.t, N.b, N.n) with the mesh's
// frames (tangents.h, bake_raster.h; green = +v = image up). 8-bit decoding
// makes 128 exactly 0: c = (byte - 128) / 127 for byte >= 128, (byte - 128) /
// 128 below (255 -> 1, 0 -> -1); 16-bit likewise around 32768; float maps
// are taken as they are. With per-pixel n = normalize(interpolated normal),
// t = the interpolated tangent made orthogonal to n (Gram-Schmidt), w = the
// sign of the interpolated handedness, b = w * cross(n, t): N =
// normalize(c.x t + c.y b + c.z n). A flat map (128, 128, 255) gives
// N = normalize(n) bit for bit, the same as no normal map.
//
// Shading in linear light. Albedo: the color map at the UV; else the
// vertex colors (sRGB bytes, decoded per vertex); else kDefaultGray.
// `unlit`: the albedo. `lambert`: albedo * (ambient + diffuse * max(0, N.L))
// with L the unit direction toward a light fixed to the viewer (a headlight:
// `light_camera` in the camera frame, default slightly above and left of the
// eye, behind it). Two-sided: when the sample sees a face's back
// (the geometric normal points away from the eye), N is negated.
// Normals: the mesh's vertex normals interpolated, else the face normal.
//
// Ground truth (RenderSynthScene): the same camera and sample grid (with its
// own supersample count), rays from the eye through each sample hit the
// analytic scene (Intersect); albedo HitAlbedo (sRGB [0,1], decoded exactly),
// normal = SampleSurface(hit point).normal (the true normal, relief
// included), the same lighting and encoding. Rays through openings are
// background.
//
// Determinism: the output bytes are a function of the inputs only, for any
// TBB thread count (run inside a tbb::task_arena to limit threads). Build
// flags pin floating point (no FMA contraction, no fast-math). The only
// transcendental functions (pow for sRGB, log2 for the LOD) are glibc's.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/core/mesh.h"
#include "stages/geometry/synth/scene.h"

namespace pb {

inline constexpr double kNearPlaneM = 0.001;  // near clipping distance, meters
inline constexpr uint8_t kDefaultGray = 180;  // sRGB albedo without colors

struct RenderCamera {
  std::array<double, 3> eye{};     // meters, absolute
  std::array<double, 3> target{};  // meters, absolute
  std::array<double, 3> up{0, 0, 1};
  double fov_deg = 60;  // vertical field of view, (0, 180)
  int size = 1024;      // width = height, pixels
};

enum class RenderLighting { kLambert, kUnlit };

struct RenderOptions {
  int supersample = 2;  // samples per pixel per axis, [1, 16]; size * supersample <= 16384
  RenderLighting lighting = RenderLighting::kLambert;
  double ambient = 0.25;  // lambert: albedo * (ambient + diffuse * max(0, N.L))
  double diffuse = 0.75;
  // Direction toward the light in the camera frame (x right, y up, z
  // forward); need not be unit. Default: from behind the viewer, 16 degrees
  // off the view axis, up and to the left.
  std::array<double, 3> light_camera{-0.15, 0.25, -1.0};
  std::array<uint8_t, 3> background{0, 0, 0};  // sRGB
};

// A texture and its mip chain: linear float RGB (3 floats per texel, row 0
// at the top). Level 0 of an 8-bit image stays bytes (3 per texel), decoded
// per fetch through `byte_value` (the same floats as decoding it up front,
// at a quarter of the memory: 8192^2 takes 201 MB + 268 MB of mips);
// levels[0].rgb is empty then.
struct MipTexture {
  struct Level {
    int width = 0;
    int height = 0;
    std::vector<float> rgb;
  };
  std::vector<Level> levels;
  std::vector<uint8_t> level0_bytes;
  std::array<float, 256> byte_value{};
};

// Color map: kU8 / kU16 are sRGB-decoded, kF32 taken as linear; gray is
// replicated, alpha ignored. Status::Invalid for an empty image.
Expected<MipTexture> BuildColorTexture(const Image& image);
// Normal map: decoded to [-1, 1] as described above (not sRGB).
Expected<MipTexture> BuildNormalTexture(const Image& image);

// What a mesh is drawn with. `color` needs mesh uvs; `normal` needs `color`'s
// uvs and mesh tangents (Status::Invalid otherwise).
struct RenderMaterial {
  const MipTexture* color = nullptr;
  const MipTexture* normal = nullptr;
};

struct RenderStats {
  size_t triangles = 0;        // faces submitted
  size_t clipped = 0;          // faces cut by the near plane
  size_t covered_samples = 0;  // samples that hit geometry
  // Of those, the samples whose nearest face shows its back (its geometric
  // normal, by the counter-clockwise winding, points away from the eye).
  // Drawn here (both sides), but a viewer that culls back faces, as glTF's
  // single-sided materials make every headset and Unity do, shows whatever
  // lies behind there, often nothing. RenderMesh only.
  size_t back_samples = 0;
};

// An RGBA kU8 image of camera.size squared. Status::Invalid for a bad camera
// (eye == target, up parallel to the view, fov or size out of range), bad
// options, a mesh failing Validate, or a material the mesh cannot carry.
//
// `depth_m` (optional) receives a one-channel kF32 image of the same size:
// per pixel the smallest view depth (meters along the camera's forward axis)
// of its samples that hit geometry, 0 where none did.
Expected<Image> RenderMesh(const Mesh& mesh, const RenderMaterial& material, const RenderCamera& camera,
                           const RenderOptions& options, RenderStats* stats = nullptr,
                           Image* depth_m = nullptr);

// The analytic scene, ray cast (see above); options.supersample is the
// truth's own sample count per axis.
Expected<Image> RenderSynthScene(const SynthScene& scene, const RenderCamera& camera,
                                 const RenderOptions& options, RenderStats* stats = nullptr);

// sRGB transfer (IEC 61966-2-1), for tests and tools: byte -> linear [0, 1]
// (table), and linear -> byte (round to nearest, via thresholds).
float SrgbByteToLinear(uint8_t value);
uint8_t LinearToSrgbByte(double linear);

}  // namespace pb
