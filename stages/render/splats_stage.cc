// render.splats: draws the colored scan itself from the scene's viewpoints
// (stages/geometry/render/splat.h), splat radii from the local point spacing
// (stages/geometry/points/spacing.h), and writes a `frames` artifact like
// render.frames: the reference of what the scanner saw.
#include <tbb/task_arena.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "engine/stage.h"
#include "stages/builtin.h"
#include "stages/geometry/io/frames.h"
#include "stages/geometry/points/knn.h"
#include "stages/geometry/points/strays.h"
#include "stages/geometry/points/surfels.h"
#include "stages/geometry/render/splat.h"
#include "stages/params.h"
#include "stages/points_io.h"
#include "stages/render/viewpoints.h"

namespace pb {
namespace {

constexpr const char* kId = "render.splats";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "required": ["viewpoints"],
  "properties": {
    "viewpoints": VIEWPOINTS_SCHEMA,
    "depth": {
      "type": "boolean",
      "default": false,
      "description": "Also write each frame's depth map (<frame>.depth.exr: per pixel the view depth in meters of the nearest surface hit, 0 where none), so metrics.image can tell a surface in front of or behind the reference's apart from a texture difference."
    },
    "samples": {
      "type": "boolean",
      "default": true,
      "description": "Also write each frame's sample mask (<frame>.samples.png, 8-bit gray: 255 in the pixels into which the center of a scan point projects that no nearer splat hides, by the same depth tolerance as the blending, counted with supersample >= 2 only inside the hull of the pixel's sample centers, so that a frame whose surface reaches the point covers a sample of that pixel; 0 elsewhere): the pixels the scan has evidence of, on which metrics.image counts hole pixels, as against the pixels the disks interpolate (a disk reaches a local spacing around its point, more at a sparse border or corner)."
    },
    "samples_on_surface": {
      "type": "boolean",
      "default": true,
      "description": "With `samples`: a point enters the sample mask where it lies once moved onto its local surface, the quadric fitted to it and its `surfel_k` neighbours (one moving-least-squares projection, points/surfels.h), rather than where it was measured. Range noise scatters the measured points across the surface, so along every silhouette about half of them stand outside the surface's outline, each a pixel of 'evidence' no surface, the true one included, covers; the projection leaves about sqrt(6 / (surfel_k + 1)) of that noise and moves a noise-free point by third-order terms only. Every point is projected, at corners and thin parts too (gated by `max_surface_variation` the noisy points of a noisy scan, whose neighbourhoods are no plane either, kept their noise); a point the quadric would move by more than the distance to its `surfel_k`-th neighbour keeps its measured position. false: the measured positions (version 3's mask)."
    },
    "size": {
      "type": "integer",
      "minimum": 16,
      "maximum": 8192,
      "default": 1024,
      "description": "Width and height of every frame, pixels (use render.frames' size to compare with its frames)."
    },
    "supersample": {
      "type": "integer",
      "minimum": 1,
      "maximum": 8,
      "default": 2,
      "description": "Samples per pixel along each axis, box-averaged in linear light, as render.frames."
    },
    "k": {
      "type": "integer",
      "minimum": 1,
      "maximum": 64,
      "default": 8,
      "description": "Local spacing of a point: r_k sqrt(pi / k), r_k the distance to its k-th nearest other point (points/spacing.h; mesh.trim and metrics.geometry use the same). 8 reaches the diagonal neighbours of a structured scan's grid, so the spacing follows the grid's sparser direction too (0.886 steps of a square grid)."
    },
    "radius_scale": {
      "type": "number",
      "exclusiveMinimum": 0,
      "default": 1.2,
      "description": "Splat radius = radius_scale * local spacing, meters. 1.2 spacings = 1.06 steps of a square grid, which a grid needs 0.71 of to be covered without gaps, with little blur; larger closes sparser scans and blurs more."
    },
    "orient": {
      "type": "boolean",
      "default": true,
      "description": "Disks lie in each point's tangent plane (the plane fitted to its `surfel_k` nearest points), as in surface splatting, instead of facing the camera: a camera-facing disk at the silhouette of a curved surface seen from another viewpoint stands out past the surface by its whole radius."
    },
    "surfel_k": {
      "type": "integer",
      "minimum": 3,
      "maximum": 64,
      "default": 16,
      "description": "Neighbours of a point's plane fit and of its border test (points/surfels.h)."
    },
    "widen_dense": {
      "type": "boolean",
      "default": true,
      "description": "A point whose `surfel_k` nearest lie closer together than a typical point's (the cloud's median distance to the `surfel_k`-th nearest) takes its nearest points out to that distance for its plane fit, border test and sample projection instead (as many as the density of its `surfel_k` nearest puts within it, at most 32 `surfel_k`), as points.normals does: where a scanner's lines converge (the ceiling above a station) the nearest lie on one arc across the lines, the fitted plane stood on edge and the disks left the scan's render full of gaps there. false: always the nearest (version 8)."
    },
    "max_surface_variation": {
      "type": "number",
      "minimum": 0,
      "default": 0.05,
      "description": "With `orient`: a point whose neighbourhood is no plane (surface variation, the smallest PCA eigenvalue over their sum, above this; points/surfels.h) keeps a camera-facing disk, uncut: on a thin part (a cable, a rod a few spacings thick, whose neighbourhood wraps around it: 0.067 for a 4 mm cable sampled every 2 mm) or a corner the fitted plane means little, and a disk in it could be seen edge-on and leave the part uncovered, hiding a hole of the model there."
    },
    "border_clip_spacings": {
      "type": "number",
      "minimum": 0,
      "default": 1,
      "description": "With `orient`: a point on the border of the scanned surface (half-disc criterion, points/surfels.h) has its disk cut by a line across the outward direction this many local spacings from the point. The surface ends somewhere between the last sample and where the next one would have been, about a spacing out (had it reached that far, that sample would have hit it): 1 is the most the sampling justifies, so the cut never opens a hole the scan does not show. An uncut disk reaches its radius (1.2 spacings) out, or more where the spacing is capped."
    },
    "clip_border": {
      "type": "boolean",
      "default": true,
      "description": "With `orient`: cut the disks of border points (`border_clip_spacings`); false draws whole disks."
    },
    "max_radius_spacings": {
      "type": "number",
      "exclusiveMinimum": 0,
      "default": 4,
      "description": "Largest local spacing a splat takes, in medians of the cloud's local spacings: an isolated point (a flying pixel at a depth edge, a stray return) has a huge k-NN distance and would be drawn as a large disk of surface nobody saw. 4 leaves a one-station scan's far field (spacing grows with range) its size."
    },
    "stray_cluster_points": {
      "type": "integer",
      "minimum": 0,
      "default": 50,
      "description": "Points of a cluster of fewer samples are strays and left out (not drawn, not in the sample masks, hiding nothing): a cluster links each point to those of its k nearest that lie within 2 of the smaller of their local spacings (points/strays.h). A stray return in the air or a floating speck of dust is no surface a model should have, and drawn as the scan it charged every model with its pixels as holes; a one-station scan's sparse far field, a border or a wire of samples are clusters of their own size and stay. 0 keeps every point."
    },
    "stray_spacing_ratio": {
      "type": "number",
      "minimum": 1,
      "default": 3,
      "description": "Two neighbours link within 2 of the larger of their local spacings when those differ by at most this factor, else within 2 of the smaller (points/strays.h): a sparse row beside denser sampling (a wall's top seen at grazing angle, the ceiling above a tripod scanner) stays, a return far off a surface, whose spacing is its distance to it, does not. 1: the smaller always."
    },
    "depth_tolerance": {
      "type": "number",
      "minimum": 0,
      "default": 2,
      "description": "Splats up to this many radii (of the front splat at the sample) behind the front splat blend with it; farther ones are hidden. Large enough for one surface seen obliquely, small against the distance between surfaces."
    },
    "max_radius_px": {
      "type": "number",
      "exclusiveMinimum": 0,
      "default": 32,
      "description": "Largest splat radius on screen, output pixels (points just in front of the eye would otherwise cover the frame)."
    },
    "background": {
      "anyOf": [
        { "type": "array", "items": { "type": "integer", "minimum": 0, "maximum": 255 }, "minItems": 3, "maxItems": 3 },
        { "type": "string", "pattern": "^[0-9]{1,3},[0-9]{1,3},[0-9]{1,3}$" }
      ],
      "default": [0, 0, 0],
      "description": "sRGB color where no splat is (alpha 0 there). [R, G, B] or \"R,G,B\" (the form --set and a campaign's set: can give). A non-black background tells missing faces from dark texels."
    }
  }
})";

struct Options {
  SplatOptions splat;
  bool depth = false;
  bool samples = true;
  bool samples_on_surface = true;
  bool orient = true;
  bool clip_border = true;
  int surfel_k = 16;
  bool widen_dense = true;
  double border_clip_spacings = 1;
  double max_surface_variation = 0.05;
  double max_radius_spacings = 0;
  int64_t stray_cluster_points = 0;
  double stray_spacing_ratio = 3;
  int size = 0;
  int k = 0;
  double radius_scale = 0;
};

Expected<Options> ReadOptions(const StageContext& ctx) {
  Options options;
  PB_ASSIGN_OR_RETURN(const int64_t size, IntegerParam(ctx, kId, "size", {16, 8192}));
  PB_ASSIGN_OR_RETURN(const int64_t supersample, IntegerParam(ctx, kId, "supersample", {1, 8}));
  PB_ASSIGN_OR_RETURN(const int64_t k, IntegerParam(ctx, kId, "k", {1, 64}));
  PB_ASSIGN_OR_RETURN(options.depth, BoolParam(ctx, kId, "depth"));
  PB_ASSIGN_OR_RETURN(options.samples, BoolParam(ctx, kId, "samples"));
  PB_ASSIGN_OR_RETURN(options.samples_on_surface, BoolParam(ctx, kId, "samples_on_surface"));
  PB_ASSIGN_OR_RETURN(options.orient, BoolParam(ctx, kId, "orient"));
  PB_ASSIGN_OR_RETURN(options.clip_border, BoolParam(ctx, kId, "clip_border"));
  PB_ASSIGN_OR_RETURN(const int64_t surfel_k, IntegerParam(ctx, kId, "surfel_k", {3, 64}));
  options.surfel_k = int(surfel_k);
  PB_ASSIGN_OR_RETURN(options.widen_dense, BoolParam(ctx, kId, "widen_dense"));
  PB_ASSIGN_OR_RETURN(options.border_clip_spacings, NumberParam(ctx, kId, "border_clip_spacings"));
  PB_ASSIGN_OR_RETURN(options.max_surface_variation, NumberParam(ctx, kId, "max_surface_variation"));
  if (!(options.max_surface_variation >= 0))
    return Status::Invalid(std::string(kId) + ": 'max_surface_variation' must be >= 0");
  if (!(options.border_clip_spacings >= 0))
    return Status::Invalid(std::string(kId) + ": 'border_clip_spacings' must be >= 0");
  PB_ASSIGN_OR_RETURN(options.radius_scale, NumberParam(ctx, kId, "radius_scale"));
  PB_ASSIGN_OR_RETURN(options.max_radius_spacings, NumberParam(ctx, kId, "max_radius_spacings"));
  if (!(options.max_radius_spacings > 0))
    return Status::Invalid(std::string(kId) + ": 'max_radius_spacings' must be > 0");
  PB_ASSIGN_OR_RETURN(options.stray_cluster_points, IntegerParam(ctx, kId, "stray_cluster_points", {0}));
  PB_ASSIGN_OR_RETURN(options.stray_spacing_ratio, NumberParam(ctx, kId, "stray_spacing_ratio"));
  if (!(options.stray_spacing_ratio >= 1))
    return Status::Invalid(std::string(kId) + ": 'stray_spacing_ratio' must be >= 1");
  PB_ASSIGN_OR_RETURN(options.splat.depth_tolerance, NumberParam(ctx, kId, "depth_tolerance"));
  PB_ASSIGN_OR_RETURN(options.splat.max_radius_px, NumberParam(ctx, kId, "max_radius_px"));
  if (!(options.radius_scale > 0)) return Status::Invalid(std::string(kId) + ": 'radius_scale' must be > 0");
  if (!(options.splat.depth_tolerance >= 0))
    return Status::Invalid(std::string(kId) + ": 'depth_tolerance' must be >= 0");
  if (!(options.splat.max_radius_px > 0)) return Status::Invalid(std::string(kId) + ": 'max_radius_px' must be > 0");
  PB_RETURN_IF_ERROR(ReadBackground(ctx, kId, &options.splat.background));
  options.size = int(size);
  options.splat.supersample = int(supersample);
  options.k = int(k);
  return options;
}

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const Options options, ReadOptions(ctx));
  PB_ASSIGN_OR_RETURN(const std::vector<View> views, ReadViewpoints(ctx, kId, options.size));
  PB_ASSIGN_OR_RETURN(const InputPoints input, ReadInputPoints(ctx, kId, 0.2));

  tbb::task_arena arena(std::max(1, ctx.threads()));
  std::vector<float> radius, spacing;
  size_t capped = 0, strays = 0, air_points = 0, seen_through = 0;
  PointCloud kept;  // the cloud without its stray points, when it has some
  // The whole cloud's index, kept for the surfels when no point is a stray
  // (they index the same positions then; with strays they index `kept`),
  // and freed before the frames are drawn.
  Expected<KnnIndex> index = Status::Internal("not run");
  const auto free_index = [&] { index = Status::Internal("freed"); };
  {
    PB_PHASE(ctx, "spacing");
    const std::string where = std::string(kId) + ": input 'points' (" + input.path + ")";
    Expected<SpacingAndStrays> local = Status::Internal("not run");
    arena.execute([&] {
      index = KnnIndex::Build(input.cloud.positions);
      if (!index.ok()) return;
      local = LocalSpacingAndStrays(*index, {.k = options.k,
                                             .max_spacing_ratio = options.stray_spacing_ratio,
                                             .min_cluster_points = size_t(options.stray_cluster_points)},
                                    &input.cloud);
    });
    if (!index.ok()) return index.status().WithContext(where);
    if (!local.ok()) return local.status().WithContext(where);
    std::vector<uint32_t> keep;
    for (size_t i = 0; i < local->stray.size(); ++i) {
      if (local->stray[i]) continue;
      keep.push_back(uint32_t(i));
      spacing.push_back(local->spacing[i]);
    }
    strays = local->stray.size() - keep.size();
    air_points = local->air;
    seen_through = local->seen_through;
    if (strays > 0) {
      kept = SelectPoints(input.cloud, keep);
      free_index();
    }
    if (keep.empty())
      return Status::Invalid(where + ": every point is a stray (clusters of fewer than " +
                             std::to_string(options.stray_cluster_points) +
                             " points); lower `stray_cluster_points` or set it to 0");
    radius = spacing;
    std::vector<float> sorted = radius;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double cap = options.max_radius_spacings * double(sorted[sorted.size() / 2]);
    for (float& r : radius) {
      if (double(r) > cap) {
        r = float(cap);
        ++capped;
      }
      r = float(r * options.radius_scale);
    }
  }
  const PointCloud& cloud = strays > 0 ? kept : input.cloud;
  Surfels surfels;
  std::vector<float> clip;
  size_t oriented_points = 0, projected_points = 0;
  double mean_projection_m = 0;
  const bool project = options.samples && options.samples_on_surface;
  if (options.orient || project) {
    PB_PHASE(ctx, "surfels");
    Expected<Surfels> estimated = Status::Internal("not run");
    const KnnIndex* same_points = strays == 0 ? &*index : nullptr;
    arena.execute([&] {
      estimated = EstimateSurfels(
          cloud, {.k = options.surfel_k, .project = project, .widen_dense = options.widen_dense}, same_points);
    });
    if (!estimated.ok())
      return estimated.status().WithContext(std::string(kId) + ": input 'points' (" + input.path + ")");
    surfels = std::move(*estimated);
  }
  free_index();
  if (project) {
    double total = 0;
    for (size_t i = 0; i < cloud.size(); ++i) {
      const float* q = &surfels.on_surface[i * 3];
      const float* p = &cloud.positions[i * 3];
      const double d[3] = {double(q[0]) - p[0], double(q[1]) - p[1], double(q[2]) - p[2]};
      const double moved = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      if (moved > 0) ++projected_points;
      total += moved;
    }
    mean_projection_m = cloud.size() > 0 ? total / double(cloud.size()) : 0;
  }
  if (options.orient) {
    for (size_t i = 0; i < cloud.size(); ++i) {
      if (surfels.variation[i] <= options.max_surface_variation) {
        ++oriented_points;
        continue;
      }
      for (int c = 0; c < 3; ++c) surfels.normal[i * 3 + c] = surfels.outward[i * 3 + c] = 0.0f;
    }
    if (options.clip_border) {
      // The clip line of a border point, border_clip_spacings of its own
      // spacing out (not the capped one: the cap only keeps stray points small).
      clip.assign(cloud.size() * 4, 0.0f);
      for (size_t i = 0; i < cloud.size(); ++i) {
        for (int c = 0; c < 3; ++c) clip[i * 4 + c] = surfels.outward[i * 3 + c];
        clip[i * 4 + 3] = float(options.border_clip_spacings * spacing[i]);
      }
    }
  }
  const SplatShapes shapes{radius, options.orient ? std::span<const float>(surfels.normal) : std::span<const float>(),
                           clip, project ? std::span<const float>(surfels.on_surface) : std::span<const float>()};
  ctx.progress(0.35);

  FrameSet frames;
  frames.width = frames.height = options.size;
  size_t covered_samples = 0, drawn = 0, sample_pixels = 0;
  {
    PB_PHASE(ctx, "compute");
    for (size_t i = 0; i < views.size(); ++i) {
      Expected<Image> image = Status::Internal("not run");
      SplatStats stats;
      Image depth, samples;
      arena.execute([&] {
        image = RenderSplats(cloud, shapes, views[i].camera, options.splat, &stats, options.depth ? &depth : nullptr,
                             options.samples ? &samples : nullptr);
      });
      if (!image.ok())
        return image.status().WithContext(std::string(kId) + ": viewpoint '" + views[i].entry.name + "'");
      covered_samples += stats.covered_samples;
      drawn += stats.drawn;
      sample_pixels += stats.sample_pixels;
      FrameEntry entry = views[i].entry;
      if (options.depth) entry.depth_file = DepthFileName(entry.file);
      if (options.samples) entry.samples_file = SamplesFileName(entry.file);
      frames.frames.push_back(Frame{std::move(entry), std::move(*image), std::move(depth), std::move(samples)});
      ctx.progress(0.35 + 0.55 * double(i + 1) / double(views.size()));
    }
  }
  PB_RETURN_IF_ERROR(WriteFramesOutput(ctx, frames));
  std::vector<float> sorted = radius;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double median_radius_m = sorted[sorted.size() / 2];
  const double pixels = double(views.size()) * options.size * options.size;
  const int ss = options.splat.supersample;
  nlohmann::json meta = ctx.input("points").meta;
  if (!meta.is_object()) meta = nlohmann::json::object();
  meta["kind"] = "frames";
  meta["render"] = {{"source", "splats"},
                    {"size", options.size},
                    {"supersample", ss},
                    {"lighting", "unlit"},
                    {"k", options.k},
                    {"radius_scale", options.radius_scale},
                    {"orient", options.orient},
                    {"border_points", options.orient ? surfels.border_points : size_t{0}},
                    {"median_radius_m", median_radius_m},
                    {"stray_points", strays},
                    {"coverage", covered_samples / (pixels * ss * ss)}};
  if (options.samples) {
    meta["render"]["sample_coverage"] = double(sample_pixels) / pixels;
    meta["render"]["samples_on_surface"] = project;
  }
  ctx.set_output_meta("frames", std::move(meta));
  ctx.counter("frames", double(views.size()));
  ctx.counter("points", double(input.cloud.size()));
  ctx.counter("stray_points", double(strays));
  ctx.counter("air_points", double(air_points));
  ctx.counter("seen_through_points", double(seen_through));
  ctx.counter("splats_drawn", double(drawn));
  ctx.counter("radii_capped", double(capped));
  ctx.counter("border_points", options.orient ? double(surfels.border_points) : 0.0);
  ctx.counter("oriented_points", double(oriented_points));
  if (options.widen_dense && (options.orient || project)) {
    ctx.counter("widened_points", double(surfels.widened));
    ctx.counter("widen_to_m", surfels.widen_to_m);
  }
  ctx.counter("median_radius_m", median_radius_m);
  ctx.counter("pixels", pixels);
  if (options.samples) ctx.counter("sample_pixels", double(sample_pixels));
  if (project) {
    ctx.counter("projected_points", double(projected_points));
    ctx.counter("mean_projection_m", mean_projection_m);
  }
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType SplatsStage() {
  StageType type;
  type.id = kId;
  // 2: tangent disks, clip lines at the border, spacing r_k sqrt(pi / k);
  // 3: the sample masks (`samples`), frames' PNGs unchanged;
  // 4: the sample masks of the points moved onto their local surface
  // (`samples_on_surface`), frames' PNGs unchanged; 5: stray points left
  // out (`stray_cluster_points`); 6: points in the air are strays too
  // (points/strays.h, AirPoints); 7: their plane test allows the scan's
  // noise (AirOptions::noise_tolerance): a sparse, noisy surface is drawn;
  // 8: the points another station saw through are strays too
  // (points/seen_through.h: a person or a clump one station recorded);
  // 9: the surfels' neighbourhoods are no smaller than a typical one
  // (`widen_dense`, knn.h WidenNeighborhood).
  type.version = 9;
  type.summary = "Renders the colored scan itself as splats from the scene's viewpoints: what the scanner saw";
  type.doc =
      "Leaves out the stray points (clusters of fewer than `stray_cluster_points` linked samples, "
      "points/strays.h: a return in the air, floating dust; and, version 6, the points in the air: sparser than 4 median spacings and on no plane or line with half their 16 nearest; and, version 8, in a scan of several stations, the points another station saw through, as `points.outliers` method `air` leaves them out of the meshes), then draws every point of `points` as a disk of radius `radius_scale` * its local spacing "
      "(r_k sqrt(pi / k), r_k the distance to its `k`-th nearest other point, at most "
      "`max_radius_spacings` medians of the cloud's local spacings: isolated points stay small), "
      "lying in the point's tangent plane (`orient`; else facing the camera), a border point's disk "
      "cut `border_clip_spacings` past the point (`clip_border`), with the camera, sample grid, "
      "resolve and encoding of render.frames (docs/render.md): `supersample`^2 samples per pixel "
      "averaged in linear light, 8-bit sRGB RGBA, alpha 255 where a splat covers any sample of the "
      "pixel, 0 elsewhere. Per sample the nearest splat wins, and every splat within "
      "`depth_tolerance` radii behind it blends with it (weight 1 - (d/r)^2 + 1/16), so one surface "
      "gives a smooth color while a surface behind it stays hidden. Unlit: the scan's colors were "
      "lit when it was scanned; compare these frames with render.frames at `lighting: unlit`. "
      "Points without colors are gray (180). The bytes are the same for any thread count.\n\n"
      "Output `frames`: frames.json and one PNG per viewpoint (name or view<N>), the same names and "
      "files as render.frames with the same viewpoints, so metrics.image compares them; with "
      "`depth`, also <name>.depth.exr (the front splats' view depth in meters, 0 on background); with "
      "`samples` (default), also <name>.samples.png (8-bit gray, 255 where the center of a point no "
      "nearer splat hides projects into the pixel, inside the hull of the pixel's sample centers: the "
      "pixels the scan has evidence of; metrics.image counts hole pixels on them), each point taken "
      "where it lies once moved onto the quadric fitted to its neighbourhood (`samples_on_surface`), "
      "so that range noise scattering points past a silhouette does not count as evidence.\n\n"
      "Counters: `frames`, `points`, `stray_points` (left out), `air_points` (of them, points in the air), `seen_through_points` (of those, points another station saw through), `splats_drawn` (over all frames), "
      "`radii_capped`, `border_points`, `widened_points` and `widen_to_m` (with `widen_dense`: the "
      "points whose surfel neighbourhood was widened, and to what radius), "
      "`median_radius_m`, `pixels`, `sample_pixels` (over all frames, with `samples`), `projected_points`, "
      "`mean_projection_m` (with `samples_on_surface`: points moved, mean distance over all points). "
      "Phases: `io`, `spacing`, `surfels`, `compute`.";
  type.params_schema = WithViewpointsSchema(kSchema);
  type.inputs = {{"points", "points", "The colored scan (points.ply).", false}};
  type.outputs = {{"frames", "frames", "One 8-bit sRGB RGBA PNG per viewpoint, and frames.json.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
