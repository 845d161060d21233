// metrics.image: per-frame and mean image metrics of `frames` against
// `reference`, frames matched by name.
#include "stages/builtin.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <string>
#include <vector>

#include "stages/geometry/io/frames.h"
#include "stages/geometry/metrics/image_metrics.h"
#include "stages/geometry/core/table.h"
#include "stages/params.h"

namespace pb {
namespace {

constexpr const char* kId = "metrics.image";

// The table's columns after `frame`: whole-frame metrics (version 1's), then
// the same on pixels covered in both frames, then the coverage figures
// (image_metrics.h, CompareCovered).
constexpr const char* kColumns[] = {
    "psnr_db",         "ssim_luma",         "ssim_rgb",         "ms_ssim_luma",         "flip_mean",
    "covered_psnr_db", "covered_ssim_luma", "covered_ssim_rgb", "covered_ms_ssim_luma", "covered_flip_mean",
    "coverage_iou",    "hole_px",           "enclosed_hole_px", "hole_fraction",        "compared_px",
    "nearer_px",       "farther_px",        "nearer_fraction",  "farther_fraction",     "footprint_px",
    "splat_hole_px",   "splat_hole_fraction", "silhouette_hole_px"};

// The ppd default is FLIP's own (FlipDefaultPpd(), checked by a test).
constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
    "depth_tolerance": {
      "type": "number",
      "minimum": 0,
      "default": 0.05,
      "description": "When both sets carry depth maps (render.frames / render.splats `depth: true`): pixels covered in both whose depths differ by more than this fraction of the reference's depth are different surfaces (nearer_px: the tested surface in front, e.g. invented; farther_px: behind), counted apart and left out of the covered metrics."
    },
    "ppd": {
      "type": "number",
      "exclusiveMinimum": 0,
      "default": 67.02064514160156,
      "description": "FLIP's observer: pixels per degree of visual angle. The default is FLIP's, a 0.7 m wide 3840-pixel monitor seen from 0.7 m; a VR headset of ~1440 px over ~90 degrees is ~16."
    }
  }
})";

Expected<FrameSet> ReadFramesInput(StageContext& ctx, const char* port) {
  if (!ctx.has_input(port)) return Status::Invalid(std::string(kId) + ": input '" + port + "' is missing");
  const ArtifactView& input = ctx.input(port);
  auto index = input.files.find(kFramesIndexFile);
  if (index == input.files.end())
    return Status::Invalid(std::string(kId) + ": input '" + port + "' has no " + kFramesIndexFile +
                           " (not a frames artifact)");
  Expected<FrameSet> frames = ReadFrames(index->second, [&input](const std::string& file) {
    auto it = input.files.find(file);
    return it == input.files.end() ? std::string() : it->second;
  });
  if (!frames.ok()) return frames.status().WithContext(std::string(kId) + ": input '" + port + "'");
  return frames;
}

std::string ColorText(const std::array<uint8_t, 3>& color) {
  return std::to_string(color[0]) + "," + std::to_string(color[1]) + "," + std::to_string(color[2]);
}

// The two sets must hold the same names at the same size.
Status MatchFrames(const FrameSet& test, const FrameSet& reference) {
  for (const Frame& f : test.frames)
    if (!reference.find(f.entry.name))
      return Status::Invalid(std::string(kId) + ": frame '" + f.entry.name +
                             "' of 'frames' has no frame of that name in 'reference'");
  for (const Frame& f : reference.frames)
    if (!test.find(f.entry.name))
      return Status::Invalid(std::string(kId) + ": frame '" + f.entry.name +
                             "' of 'reference' has no frame of that name in 'frames'");
  if (test.width != reference.width || test.height != reference.height)
    return Status::Invalid(std::string(kId) + ": 'frames' are " + std::to_string(test.width) + "x" +
                           std::to_string(test.height) + ", 'reference' " +
                           std::to_string(reference.width) + "x" + std::to_string(reference.height));
  if (test.frames.empty()) return Status::Invalid(std::string(kId) + ": no frames to compare");
  return Status::Ok();
}

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const double ppd, NumberParam(ctx, kId, "ppd"));
  PB_ASSIGN_OR_RETURN(const double depth_tolerance, NumberParam(ctx, kId, "depth_tolerance"));
  if (!(depth_tolerance >= 0)) return Status::Invalid(std::string(kId) + ": depth_tolerance must be >= 0");
  if (!(ppd > 0)) return Status::Invalid(std::string(kId) + ": ppd must be positive");
  FrameSet test, reference;
  {
    PB_PHASE(ctx, "io");
    PB_ASSIGN_OR_RETURN(test, ReadFramesInput(ctx, "frames"));
    PB_ASSIGN_OR_RETURN(reference, ReadFramesInput(ctx, "reference"));
  }
  PB_RETURN_IF_ERROR(MatchFrames(test, reference));
  ctx.progress(0.1);

  // Frames are compared as drawn on black (BackgroundToBlack): frames drawn
  // on another background (render.frames `background`, set to see holes)
  // against a reference drawn on black would otherwise count every background
  // pixel as an error of the whole frame (and FLIP's filters carry the
  // background into the covered pixels next to it).
  for (const Frame& frame : test.frames) {
    const auto tested = DrawnBackground(frame.image);
    const auto drawn = DrawnBackground(reference.find(frame.entry.name)->image);
    if (tested && drawn && *tested != *drawn) {
      ctx.warning(std::string(kId) + ": 'frames' are drawn on background " + ColorText(*tested) +
                  " and 'reference' on " + ColorText(*drawn) +
                  "; the metrics count background pixels as black on both sides, but pixels on a "
                  "silhouette keep a blend of their own background, so the whole-frame figures are "
                  "approximate (draw both on one background for exact ones); hole and coverage counts do "
                  "not depend on it");
      break;
    }
  }

  Table table;
  table.columns = {"frame"};
  for (const char* name : kColumns) table.columns.push_back(name);
  FrameSet maps, covered_maps, coverage_maps;
  maps.width = covered_maps.width = coverage_maps.width = test.width;
  maps.height = covered_maps.height = coverage_maps.height = test.height;
  std::vector<double> sums(std::size(kColumns), 0.0);
  size_t sample_masks = 0;  // frames whose holes were counted on the reference's sample mask
  {
    PB_PHASE(ctx, "compute");
    tbb::task_arena arena(std::max(1, ctx.threads()));
    for (size_t i = 0; i < test.frames.size(); ++i) {
      const Frame& frame = test.frames[i];
      const Frame& ref = *reference.find(frame.entry.name);
      ImageMetricsOptions options;
      options.flip_ppd = ppd;
      options.depth_tolerance = depth_tolerance;
      const bool depth = frame.depth.width > 0 && ref.depth.width > 0;
      FlipResult flip, covered_flip;
      Image coverage_map;
      Expected<ImageMetrics> m = Status::Internal("not run");
      Expected<CoveredComparison> c = Status::Internal("not run");
      arena.execute([&] {
        const Image ref_image = BackgroundToBlack(ref.image), test_image = BackgroundToBlack(frame.image);
        m = CompareImages(ref_image, test_image, options, &flip);
        if (m.ok())
          c = CompareCovered(ref_image, test_image, options, &covered_flip, depth ? &ref.depth : nullptr,
                             depth ? &frame.depth : nullptr, ref.samples.width > 0 ? &ref.samples : nullptr,
                             &coverage_map);
      });
      if (!m.ok()) return m.status().WithContext(std::string(kId) + ": frame '" + frame.entry.name + "'");
      if (!c.ok()) return c.status().WithContext(std::string(kId) + ": frame '" + frame.entry.name + "'");
      const CoverageStats& cov = c->coverage;
      const double values[] = {m->psnr_db,
                               m->ssim_luma,
                               m->ssim_rgb,
                               m->ms_ssim_luma,
                               m->flip_mean,
                               c->metrics.psnr_db,
                               c->metrics.ssim_luma,
                               c->metrics.ssim_rgb,
                               c->metrics.ms_ssim_luma,
                               c->metrics.flip_mean,
                               cov.iou,
                               double(cov.hole_px),
                               double(cov.enclosed_hole_px),
                               cov.hole_fraction,
                               double(cov.compared_px),
                               cov.depth_checked ? double(cov.nearer_px) : std::nan(""),
                               cov.depth_checked ? double(cov.farther_px) : std::nan(""),
                               cov.depth_checked && cov.reference_px ? double(cov.nearer_px) / double(cov.reference_px)
                                                                     : std::nan(""),
                               cov.depth_checked && cov.reference_px ? double(cov.farther_px) / double(cov.reference_px)
                                                                     : std::nan(""),
                               double(cov.footprint_px),
                               double(cov.splat_hole_px),
                               cov.splat_hole_fraction,
                               double(cov.silhouette_hole_px)};
      sample_masks += cov.sample_mask ? 1 : 0;
      static_assert(std::size(values) == std::size(kColumns));
      std::vector<TableValue> row = {frame.entry.name};
      for (size_t k = 0; k < std::size(values); ++k) {
        row.emplace_back(values[k]);
        sums[k] += values[k];
      }
      table.rows.push_back(std::move(row));
      FrameEntry map_entry = frame.entry;
      map_entry.depth_file.clear();  // the maps are pictures of errors, without depth
      map_entry.samples_file.clear();
      maps.frames.push_back(Frame{map_entry, FlipErrorColorMap(flip), {}});
      covered_maps.frames.push_back(Frame{map_entry, FlipErrorColorMap(covered_flip), {}});
      coverage_maps.frames.push_back(Frame{map_entry, std::move(coverage_map), {}});
      ctx.progress(0.1 + 0.8 * double(i + 1) / double(test.frames.size()));
    }
  }
  const double n = double(test.frames.size());
  std::vector<TableValue> mean_row = {std::string("mean")};
  for (double s : sums) mean_row.emplace_back(s / n);
  table.rows.push_back(std::move(mean_row));

  ctx.counter("frames", n);
  ctx.counter("pixels_per_frame", double(test.width) * double(test.height));
  ctx.counter("sample_mask_frames", double(sample_masks));
  // An identical frame makes the mean PSNR infinite (and a frame with no
  // pixel covered in both makes the covered means NaN); the run record holds
  // finite numbers only, so such counters are left out.
  for (size_t k = 0; k < std::size(kColumns); ++k)
    if (std::isfinite(sums[k] / n)) ctx.counter(kColumns[k], sums[k] / n);
  {
    PB_PHASE(ctx, "io");
    PB_RETURN_IF_ERROR(WriteTable(ctx.output_path("table", "table.json"), table));
    PB_RETURN_IF_ERROR(WriteFrames(maps, [&ctx](const std::string& file) {
      return ctx.output_path("flip", file);
    }));
    PB_RETURN_IF_ERROR(WriteFrames(covered_maps, [&ctx](const std::string& file) {
      return ctx.output_path("flip_covered", file);
    }));
    PB_RETURN_IF_ERROR(WriteFrames(coverage_maps, [&ctx](const std::string& file) {
      return ctx.output_path("coverage", file);
    }));
  }
  ctx.set_output_meta("table", {{"kind", "image_metrics"},
                                {"ppd", ppd},
                                {"frames", n},
                                {"hole_footprint", sample_masks == test.frames.size() ? "samples"
                                                   : sample_masks == 0              ? "covered"
                                                                                    : "mixed"}});
  nlohmann::json flip_meta = ctx.input("frames").meta;
  if (!flip_meta.is_object()) flip_meta = nlohmann::json::object();
  flip_meta["kind"] = "flip_error_maps";
  flip_meta["ppd"] = ppd;
  ctx.set_output_meta("flip", flip_meta);
  flip_meta["kind"] = "flip_error_maps_covered";
  ctx.set_output_meta("flip_covered", flip_meta);
  flip_meta.erase("ppd");
  flip_meta["kind"] = "coverage_maps";
  ctx.set_output_meta("coverage", std::move(flip_meta));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType ImageMetricsStage() {
  StageType type;
  type.id = kId;
  type.version = 6;  // 6: output coverage (maps); 5: whole frames compared as drawn on black; 4: holes on the sample mask
  type.summary = "Image quality of rendered frames against reference frames: PSNR, SSIM, MS-SSIM, FLIP";
  type.doc =
      "Compares every frame of `frames` with the frame of the same name in `reference` (a frame "
      "missing on either side, or sets of different sizes, is an error naming it), twice: over the "
      "whole frame (all pixels count; version 1's columns) and on the pixels covered "
      "in both frames (alpha > 0), with the coverage reported apart, so that a silhouette "
      "difference or a hole is named as such instead of drowning the texture comparison. Pixels "
      "with alpha 0 count as black on both sides, so frames drawn on another `background` (render.frames, "
      "render.splats) compare as drawn on the default black (a warning says when the two sets' "
      "backgrounds differ: their silhouette pixels still blend their own). Metrics (docs/metrics.md): PSNR in dB over R, G, B "
      "(MAX 255; identical frames give infinity, written as null); SSIM (Wang et al. 2004, 11x11 "
      "Gaussian sigma 1.5, K1 0.01, K2 0.03, valid-region mean) on luma Y = 0.299 R + 0.587 G + "
      "0.114 B (`ssim_luma`) and as the mean of R, G, B (`ssim_rgb`); MS-SSIM on luma (5 scales, "
      "weights 0.0448 0.2856 0.3001 0.2363 0.1333; null below 176 px); FLIP (Andersson et al. "
      "2020, LDR, NVIDIA FLIP v1.6) at `ppd` pixels per degree. The paper's HDR-VDP-2 is not "
      "computed.\n\n"
      "Covered pixels (docs/metrics.md): `compared_px` are the pixels covered in both frames whose "
      "4 neighbours are too (supersampled edge pixels blend with the background); PSNR is their MSE; "
      "for SSIM, MS-SSIM and FLIP the tested frame takes the reference's pixels outside them, the "
      "maps are computed on the full frame and averaged over them only (null when there are none). "
      "`coverage_iou`: covered in both / covered in either. `hole_px`: pixels of the reference's "
      "footprint where the tested frame shows background; the footprint (`footprint_px`) is the "
      "reference frame's sample mask when it has one (render.splats `samples`: the pixels into which "
      "a visible scan point's center projects, what the scanner has evidence of), else its covered "
      "pixels; `enclosed_hole_px`: those of them inside the tested frame's "
      "own silhouette (its background not connected to the frame's border: background seen through "
      "the surface); `silhouette_hole_px`: those of the others that touch (8-neighbourhood) a pixel "
      "the tested frame covers (its outline a pixel short of the footprint, as a low-poly chord "
      "across a curved silhouette; the rest are missing parts); `hole_fraction` = hole_px / footprint_px. `splat_hole_px` / "
      "`splat_hole_fraction`: the same against all the reference's covered pixels (a splat "
      "reference's disks reach a local spacing past their points, several pixels at a sparse border; "
      "version 3's hole_px). When both frames "
      "carry depth maps, `nearer_px` / `farther_px` count the pixels covered in both where the "
      "tested surface lies in front of / behind the reference's by more than `depth_tolerance` x "
      "its depth (invented surface in front; missing surface seen through); they are geometry, "
      "left out of the covered metrics with their 4 neighbours (null without depth maps); "
      "`nearer_fraction` / `farther_fraction`: the same over the reference's covered pixels.\n\n"
      "Output `table` columns: `frame`, `psnr_db`, `ssim_luma`, `ssim_rgb`, `ms_ssim_luma`, "
      "`flip_mean` (whole frame), `covered_psnr_db`, `covered_ssim_luma`, `covered_ssim_rgb`, "
      "`covered_ms_ssim_luma`, `covered_flip_mean`, `coverage_iou`, `hole_px`, `enclosed_hole_px`, "
      "`hole_fraction`, `compared_px`, `nearer_px`, `farther_px`, `nearer_fraction`, "
      "`farther_fraction`, `footprint_px`, `splat_hole_px`, `splat_hole_fraction`, `silhouette_hole_px`; one row per frame in the order of `frames`, then a row `mean` "
      "with the arithmetic mean of each column. Output `flip`: the whole-frame FLIP error map of "
      "every frame, magma color-mapped, same names and files; `flip_covered`: the map of the "
      "covered-pixel comparison; `coverage`: per frame a map of where the figures come from "
      "(8-bit RGB): a gray of the frame's luma where both cover and agree in depth; magenta where "
      "the frame's surface lies in front of the reference's (invented), cyan behind; blue where "
      "only the frame covers, dark gray where only the reference's disks do; the hole pixels red "
      "at the frame's outline, orange when open and deeper, yellow when the frame encloses them; "
      "black where neither covers (image_metrics.h, kCoverageMap*).\n\n"
      "Counters: `frames`, `pixels_per_frame`, `sample_mask_frames` (frames whose holes were counted "
      "on the reference's sample mask), and the mean of every column (left out when not "
      "finite: identical frames give an infinite PSNR). Phases: `io`, `compute`.";
  type.params_schema = kSchema;
  type.inputs = {{"frames", "frames", "The frames to evaluate (frames.json + PNGs).", false},
                 {"reference", "frames",
                  "Reference frames of the same names and size (HPM or ground-truth renders).",
                  false}};
  type.outputs = {
      {"table", "table", "Per-frame and mean PSNR, SSIM, MS-SSIM and FLIP, whole-frame and on covered pixels, and coverage.", false},
      {"flip", "frames", "FLIP error maps (magma colormap), one per frame.", false},
      {"flip_covered", "frames", "FLIP error maps of the covered-pixel comparison, one per frame.", false},
      {"coverage", "frames", "Coverage maps: holes, invented and missing surface, one per frame.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
