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
// Splats. Point i (absolute position origin + positions[i]) is a disk of
// radius radius_m[i] meters centered on the point, at most `max_radius_px`
// output pixels on screen at the point's view depth z_i (distance along the
// view axis; a point just in front of the eye would otherwise cover the whole
// frame). Points nearer than kNearPlaneM, and radii that are not positive and
// finite, are skipped.
//  * Without normals the disk faces the camera (screen aligned): it covers
//    the samples within focal * radius_m[i] / z_i samples of its projected
//    center, all at depth z_i.
//  * With normals (SplatShapes::normal) the disk lies in the point's tangent
//    plane, as in surface splatting: a sample is covered when its ray meets
//    the plane within the radius of the point, at the depth where it meets
//    it. Seen obliquely a disk is an ellipse, and at the silhouette of a
//    curved surface it is seen edge-on, so it does not stand out past the
//    surface as a camera-facing disk does (by a whole radius). A disk whose
//    bounding square reaches behind the near plane is skipped.
//  * A clip line (SplatShapes::clip; Zwicker, Pauly, Knoll and Gross 2002,
//    "Pointshop 3D", SIGGRAPH, clip lines for sharp edges) cuts the disk:
//    it keeps the points x of the disk with (x - center) . direction <=
//    distance. For the border of a scanned surface: the surface ends
//    somewhere between the last sample and where the next one would have
//    been, so the disk should not reach farther out than that.
//
// Visibility with blending. Per sample, the front splat is the one of least
// depth (ties: the lower point index). Every splat covering the sample whose
// depth at the sample is at most the front depth + depth_tolerance * (the
// front splat's radius_m) contributes, weighted by w = 1 - (d / r)^2 + 1/16 with d the
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
  size_t sample_pixels = 0;    // pixels of the sample mask (when asked for)
};

// The splats' shapes, per point of the cloud, in the cloud's frame.
struct SplatShapes {
  std::span<const float> radius_m;  // one per point, meters
  // 3 per point (unit), or empty: disks face the camera; a point whose
  // normal is 0 faces the camera too.
  std::span<const float> normal;
  // 4 per point, or empty: a unit direction in the disk's plane and a
  // distance in meters (the clip line); direction 0: the whole disk. Needs
  // normals.
  std::span<const float> clip;
  // 3 per point (the cloud's frame), or empty: where the sample mask takes
  // each point to be (its depth and pixel), e.g. the point moved onto its
  // local surface so that range noise does not count as evidence past the
  // surface's outline; the splats are drawn where the points are.
  std::span<const float> sample_at;
};

// An RGBA kU8 image of camera.size squared. Status::Invalid for a bad camera
// (as RenderMesh), bad options, a cloud failing Validate, or shapes of the
// wrong length.
// `depth_m` (optional): as RenderMesh's, the smallest front-splat depth of
// the pixel's samples (meters along the view axis), 0 where none.
// `samples` (optional): the sample mask, a one-channel kU8 image of
// camera.size squared, 255 in the pixels into which the center of a visible
// point projects, 0 elsewhere: the pixels the scan has evidence of, as
// against the pixels its disks interpolate (a disk covers a whole local
// spacing around its point, more where the spacing is inflated at a border
// or a sparse corner). A point is drawn as a splat would be (in front of the
// near plane, a positive finite radius) and visible when its view depth is
// at most the front depth of the sample its center falls in + depth_tolerance
// x the front splat's radius, the rule by which splats blend (a point whose
// own disk does not cover that sample, e.g. seen edge-on, and that no other
// splat covers, is visible). With supersample >= 2 a point counts only when
// its center falls inside the hull of its pixel's sample centers (the middle
// (s - 1) / s of the pixel per axis): a frame of the same sample grid whose
// surface reaches the point (its outline, locally a line, through the point
// or beyond it) then covers at least one of those samples, so the pixel
// never reads as background by the quantization of an outline that passes
// the point in the pixel's outer margin (a quarter of the pixels an exact
// model's outline crosses would otherwise count as holes). The mask thereby
// samples the evidence (1 - 1/s)^2 of it: uniformly, so fractions measured
// on it are unbiased. Counted in `stats->sample_pixels`.
Expected<Image> RenderSplats(const PointCloud& cloud, const SplatShapes& shapes,
                             const RenderCamera& camera, const SplatOptions& options,
                             SplatStats* stats = nullptr, Image* depth_m = nullptr, Image* samples = nullptr);

}  // namespace pb
