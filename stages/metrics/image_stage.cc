// metrics.image: per-frame and mean image metrics of `frames` against
// `reference`, frames matched by name.
#include "stages/builtin.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>

#include "stages/geometry/io/frames.h"
#include "stages/geometry/metrics/image_metrics.h"
#include "stages/geometry/core/table.h"
#include "stages/params.h"

namespace pb {
namespace {

constexpr const char* kId = "metrics.image";

// The ppd default is FLIP's own (FlipDefaultPpd(), checked by a test).
constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "properties": {
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
  if (!(ppd > 0)) return Status::Invalid(std::string(kId) + ": ppd must be positive");
  FrameSet test, reference;
  {
    PB_PHASE(ctx, "io");
    PB_ASSIGN_OR_RETURN(test, ReadFramesInput(ctx, "frames"));
    PB_ASSIGN_OR_RETURN(reference, ReadFramesInput(ctx, "reference"));
  }
  PB_RETURN_IF_ERROR(MatchFrames(test, reference));
  ctx.progress(0.1);

  Table table;
  table.columns = {"frame", "psnr_db", "ssim_luma", "ssim_rgb", "ms_ssim_luma", "flip_mean"};
  FrameSet maps;
  maps.width = test.width;
  maps.height = test.height;
  double sums[5] = {0, 0, 0, 0, 0};
  {
    PB_PHASE(ctx, "compute");
    tbb::task_arena arena(std::max(1, ctx.threads()));
    for (size_t i = 0; i < test.frames.size(); ++i) {
      const Frame& frame = test.frames[i];
      const Frame& ref = *reference.find(frame.entry.name);
      ImageMetricsOptions options;
      options.flip_ppd = ppd;
      FlipResult flip;
      Expected<ImageMetrics> m = Status::Internal("not run");
      arena.execute([&] { m = CompareImages(ref.image, frame.image, options, &flip); });
      if (!m.ok()) return m.status().WithContext(std::string(kId) + ": frame '" + frame.entry.name + "'");
      const double values[5] = {m->psnr_db, m->ssim_luma, m->ssim_rgb, m->ms_ssim_luma, m->flip_mean};
      std::vector<TableValue> row = {frame.entry.name};
      for (int k = 0; k < 5; ++k) {
        row.emplace_back(values[k]);
        sums[k] += values[k];
      }
      table.rows.push_back(std::move(row));
      maps.frames.push_back(Frame{frame.entry, FlipErrorColorMap(flip)});
      ctx.progress(0.1 + 0.8 * double(i + 1) / double(test.frames.size()));
    }
  }
  const double n = double(test.frames.size());
  std::vector<TableValue> mean_row = {std::string("mean")};
  for (double s : sums) mean_row.emplace_back(s / n);
  table.rows.push_back(std::move(mean_row));

  ctx.counter("frames", n);
  ctx.counter("pixels_per_frame", double(test.width) * double(test.height));
  // An identical frame makes the mean PSNR infinite; the run record holds
  // finite numbers only, so that counter is left out then.
  if (std::isfinite(sums[0] / n)) ctx.counter("psnr_db", sums[0] / n);
  const char* names[5] = {"psnr_db", "ssim_luma", "ssim_rgb", "ms_ssim_luma", "flip_mean"};
  for (int k = 1; k < 5; ++k)
    if (std::isfinite(sums[k] / n)) ctx.counter(names[k], sums[k] / n);
  {
    PB_PHASE(ctx, "io");
    PB_RETURN_IF_ERROR(WriteTable(ctx.output_path("table", "table.json"), table));
    PB_RETURN_IF_ERROR(WriteFrames(maps, [&ctx](const std::string& file) {
      return ctx.output_path("flip", file);
    }));
  }
  ctx.set_output_meta("table", {{"kind", "image_metrics"}, {"ppd", ppd}, {"frames", n}});
  nlohmann::json flip_meta = ctx.input("frames").meta;
  if (!flip_meta.is_object()) flip_meta = nlohmann::json::object();
  flip_meta["kind"] = "flip_error_maps";
  flip_meta["ppd"] = ppd;
  ctx.set_output_meta("flip", std::move(flip_meta));
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType ImageMetricsStage() {
  StageType type;
  type.id = kId;
  type.version = 1;
  type.summary = "Image quality of rendered frames against reference frames: PSNR, SSIM, MS-SSIM, FLIP";
  type.doc =
      "Compares every frame of `frames` with the frame of the same name in `reference` (a frame "
      "missing on either side, or sets of different sizes, is an error naming it). All pixels "
      "count; an alpha channel is ignored. Metrics (docs/metrics.md): PSNR in dB over R, G, B "
      "(MAX 255; identical frames give infinity, written as null); SSIM (Wang et al. 2004, 11x11 "
      "Gaussian sigma 1.5, K1 0.01, K2 0.03, valid-region mean) on luma Y = 0.299 R + 0.587 G + "
      "0.114 B (`ssim_luma`) and as the mean of R, G, B (`ssim_rgb`); MS-SSIM on luma (5 scales, "
      "weights 0.0448 0.2856 0.3001 0.2363 0.1333; null below 176 px); FLIP (Andersson et al. "
      "2020, LDR, NVIDIA FLIP v1.6) at `ppd` pixels per degree. The paper's HDR-VDP-2 is not "
      "computed.\n\n"
      "Output `table` columns: `frame`, `psnr_db`, `ssim_luma`, `ssim_rgb`, `ms_ssim_luma`, "
      "`flip_mean`; one row per frame in the order of `frames`, then a row `mean` with the "
      "arithmetic mean of each column. Output `flip`: the FLIP error map of every frame, magma "
      "color-mapped, same names and files.\n\n"
      "Counters: `frames`, `pixels_per_frame`, and the means `psnr_db` (left out when infinite), "
      "`ssim_luma`, `ssim_rgb`, `ms_ssim_luma`, `flip_mean`. Phases: `io`, `compute`.";
  type.params_schema = kSchema;
  type.inputs = {{"frames", "frames", "The frames to evaluate (frames.json + PNGs).", false},
                 {"reference", "frames",
                  "Reference frames of the same names and size (HPM or ground-truth renders).",
                  false}};
  type.outputs = {
      {"table", "table", "Per-frame and mean PSNR, SSIM, MS-SSIM and FLIP.", false},
      {"flip", "frames", "FLIP error maps (magma colormap), one per frame.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
