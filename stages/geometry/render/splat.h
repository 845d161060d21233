// Splat rendering of a colored point cloud: what the scanner saw, drawn from
// any viewpoint, as a reference for the workflows' frames that depends on no
// reconstruction (DESIGN.md, Evaluation: "for real scans, a render of the scan
// itself"). docs/render.md has the long form.
//
// Camera, sample grid, resolve and encoding are those of RenderMesh
// (render.h): the same RenderCamera, `supersample` x `supersample` samples per
// pixel at (x + (i + 0.5) / s, y + (j + 0.5) / s), the box average of the
// samples in linear light sRGB-encoded to 8 bits, alpha 255 where any sample
// was covered, else 0 (background samples count with the background color).
//
// Splats. Point i (absolute position origin + positions[i]) is a disk facing
// the camera (screen aligned) of radius radius_m[i] meters, centered on the
// point at its view depth z_i (distance along the view axis). It covers the
// samples within focal * radius_m[i] / z_i samples of its projected center,
// at most `max_radius_px` output pixels (a point just in front of the eye
// would otherwise cover the whole frame). Points nearer than kNearPlaneM, and
// radii that are not positive and finite, are skipped.
//
// Visibility with blending. Per sample, the front splat is the one of least
// depth (ties: the lower point index). Every splat covering the sample whose
// depth is at most the front depth + depth_tolerance * (the front splat's
// radius_m) contributes, weighted by w = 1 - (d / r)^2 + 1/16 with d the
// sample's distance from the splat center and r the splat's radius, both in
// samples (the 1/16 keeps the disk's rim from weighing nothing), so splats of
// one surface blend into a smooth color instead of fighting, while a surface
// farther behind than the tolerance is hidden. The sample's color is the
// weighted mean of the contributing points' colors in linear light (sRGB
// bytes decoded; no colors: kDefaultGray).
//
// Unlit: a scan's colors were lit by the site's light when it was scanned;
// shading them again would count the light twice. Compare splat frames with
// frames rendered `unlit` (render.frames lighting: unlit).
//
// Determinism: the image is cut into tiles of 64 x 64 samples; each tile
// draws the splats overlapping it in point-index order, alone, so the bytes
// are a function of the inputs only, for any TBB thread count (run inside a
// tbb::task_arena to limit threads).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "base/status.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/core/point_cloud.h"
#include "stages/geometry/render/render.h"

namespace pb {

struct SplatOptions {
  int supersample = 2;  // samples per pixel per axis, [1, 16]; size * supersample <= 16384
  // Splats within this many front-splat radii behind the front splat blend
  // with it; >= 0.
  double depth_tolerance = 2.0;
  double max_radius_px = 32;  // cap on a splat's radius on screen, output pixels, > 0
  std::array<uint8_t, 3> background{0, 0, 0};  // sRGB
};

struct SplatStats {
  size_t points = 0;           // points of the cloud
  size_t drawn = 0;            // points in front of the near plane, inside the frame
  size_t covered_samples = 0;  // samples covered by at least one splat
};

// An RGBA kU8 image of camera.size squared. `radius_m` holds one radius per
// point of `cloud` (meters). Status::Invalid for a bad camera (as RenderMesh),
// bad options, a cloud failing Validate, or radius_m of the wrong length.
// `depth_m` (optional): as RenderMesh's, the smallest front-splat depth of
// the pixel's samples (meters along the view axis), 0 where none.
Expected<Image> RenderSplats(const PointCloud& cloud, std::span<const float> radius_m,
                             const RenderCamera& camera, const SplatOptions& options,
                             SplatStats* stats = nullptr, Image* depth_m = nullptr);

}  // namespace pb
