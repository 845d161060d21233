#include "cli/compare_command.h"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>

#include "cli/command_args.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/metrics/image_metrics.h"

namespace pb {
namespace {

constexpr const char* kDescription =
    "Image-quality metrics of TEST against REF (8-bit PNGs of equal size; alpha\n"
    "is ignored, gray counts as R = G = B):\n"
    "  PSNR     dB over R, G, B, MAX 255 (inf for identical images)\n"
    "  SSIM     Wang et al. 2004, 11x11 Gaussian sigma 1.5, on luma\n"
    "           Y = 0.299 R + 0.587 G + 0.114 B and as the mean of R, G, B\n"
    "  MS-SSIM  5 scales on luma (n/a below 176x176 pixels)\n"
    "  FLIP     LDR-FLIP (Andersson et al. 2020, NVIDIA FLIP v1.6), mean error\n"
    "With --covered, as metrics.image measures a model against the scan's\n"
    "splats (docs/metrics.md, \"Covered pixels\"): a pixel is covered where its\n"
    "alpha is > 0; coverage IoU and hole pixels (REF's footprint, or its\n"
    "--samples mask, where TEST shows background) apart, and the metrics on the\n"
    "pixels covered in both (edge pixels, and with --depth the pixels whose\n"
    "surfaces differ in depth, left out).";

nlohmann::json NumberOrNull(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

std::string Fixed(double v, int decimals) {
  if (std::isnan(v)) return "n/a";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

int RunCompare(const std::vector<std::string>& args) {
  CLI::App app{kDescription, "pointbake compare"};
  std::vector<std::string> files(2);
  app.add_option("REF", files[0], "The reference image")->required();
  app.add_option("TEST", files[1], "The image compared with it")->required();
  std::string map_path;
  app.add_option("--map", map_path, "Write the FLIP error map (magma colormap) as a PNG");
  bool json = false;
  app.add_flag("--json", json, "Print one JSON object instead of the table (inf/n/a as null)");
  double ppd = FlipDefaultPpd();
  app.add_option("--ppd", ppd, "FLIP's pixels per degree (default: FLIP's monitor setup)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  bool covered = false;
  app.add_flag("--covered", covered,
               "Measure only the pixels covered (alpha > 0) in both images; print coverage and holes apart");
  std::string samples_path;
  app.add_option("--samples", samples_path,
                 "REF's sample mask (render.splats' <view>.samples.png): holes are counted on it (needs --covered)");
  std::vector<std::string> depth_paths;
  app.add_option("--depth", depth_paths,
                 "REF's and TEST's depth maps (<view>.depth.exr): surfaces more than --depth-tolerance apart are "
                 "counted (in front / behind) and left out of the metrics (needs --covered)")
      ->expected(2);
  std::string coverage_path;
  app.add_option("--coverage-map", coverage_path,
                 "Write the coverage map as a PNG: where the holes, the surfaces in front / behind and the "
                 "pixels only one image covers are (needs --covered; colours in docs/metrics.md)");
  double depth_tolerance = ImageMetricsOptions{}.depth_tolerance;
  app.add_option("--depth-tolerance", depth_tolerance, "With --depth: the depth difference that counts, x REF's depth")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  if (const std::optional<int> exit = ParseCommandArgs(app, args)) return *exit;
  if (!covered && (!samples_path.empty() || !depth_paths.empty() || !coverage_path.empty())) {
    std::fprintf(stderr, "pointbake compare: --samples, --depth and --coverage-map need --covered\n");
    return 2;
  }

  auto read = [](const std::string& path, Image* out) {
    Expected<Image> image = ReadImage(path);
    if (!image.ok()) {
      std::fprintf(stderr, "pointbake compare: %s\n", image.status().message().c_str());
      return false;
    }
    *out = std::move(image).value();
    return true;
  };
  Image images[2], samples, depths[2];
  for (int k = 0; k < 2; ++k)
    if (!read(files[k], &images[k])) return 2;
  if (!samples_path.empty() && !read(samples_path, &samples)) return 2;
  for (size_t k = 0; k < depth_paths.size(); ++k)
    if (!read(depth_paths[k], &depths[k])) return 2;
  ImageMetricsOptions options;
  options.flip_ppd = ppd;
  options.depth_tolerance = depth_tolerance;
  FlipResult flip;
  std::optional<CoverageStats> coverage;
  Image coverage_map;
  Expected<ImageMetrics> m = ImageMetrics{};
  if (covered) {
    Expected<CoveredComparison> c =
        CompareCovered(images[0], images[1], options, &flip, depth_paths.empty() ? nullptr : &depths[0],
                       depth_paths.empty() ? nullptr : &depths[1], samples_path.empty() ? nullptr : &samples,
                       coverage_path.empty() ? nullptr : &coverage_map);
    if (c.ok()) {
      coverage = c->coverage;
      m = c->metrics;
    } else {
      m = c.status();
    }
  } else {
    m = CompareImages(images[0], images[1], options, &flip);
  }
  if (!m.ok()) {
    std::fprintf(stderr, "pointbake compare: %s vs %s: %s\n", files[0].c_str(), files[1].c_str(),
                 m.status().message().c_str());
    return 2;
  }
  if (!map_path.empty()) {
    const Status st = WritePng(map_path, FlipErrorColorMap(flip));
    if (!st.ok()) {
      std::fprintf(stderr, "pointbake compare: writing the FLIP map: %s\n", st.message().c_str());
      return 2;
    }
  }
  if (!coverage_path.empty()) {
    const Status st = WritePng(coverage_path, coverage_map);
    if (!st.ok()) {
      std::fprintf(stderr, "pointbake compare: writing the coverage map: %s\n", st.message().c_str());
      return 2;
    }
  }
  if (json) {
    nlohmann::json out = {{"reference", files[0]},
                          {"test", files[1]},
                          {"width", images[0].width},
                          {"height", images[0].height},
                          {"psnr_db", NumberOrNull(m->psnr_db)},
                          {"ssim_luma", NumberOrNull(m->ssim_luma)},
                          {"ssim_rgb", NumberOrNull(m->ssim_rgb)},
                          {"ms_ssim_luma", NumberOrNull(m->ms_ssim_luma)},
                          {"flip_mean", m->flip_mean},
                          {"flip_ppd", ppd}};
    if (!map_path.empty()) out["flip_map"] = map_path;
    if (!coverage_path.empty()) out["coverage_map"] = coverage_path;
    if (coverage) {
      const CoverageStats& c = *coverage;
      out["covered"] = {{"reference_px", c.reference_px},
                        {"test_px", c.test_px},
                        {"coverage_iou", c.iou},
                        {"footprint", c.sample_mask ? "samples" : "covered"},
                        {"footprint_px", c.footprint_px},
                        {"hole_px", c.hole_px},
                        {"enclosed_hole_px", c.enclosed_hole_px},
                        {"silhouette_hole_px", c.silhouette_hole_px},
                        {"hole_fraction", c.hole_fraction},
                        {"compared_px", c.compared_px}};
      if (c.depth_checked) {
        out["covered"]["nearer_px"] = c.nearer_px;
        out["covered"]["farther_px"] = c.farther_px;
      }
    }
    std::printf("%s\n", out.dump(2).c_str());
    return 0;
  }
  std::printf("reference  %s (%dx%d)\n", files[0].c_str(), images[0].width, images[0].height);
  std::printf("test       %s\n", files[1].c_str());
  if (coverage) {
    const CoverageStats& c = *coverage;
    std::printf("covered            %zu px in REF, %zu in TEST, IoU %.6f\n", c.reference_px, c.test_px, c.iou);
    std::printf("holes              %zu of %zu %s px (%s %%): %zu enclosed, %zu at the outline, %zu open\n",
                c.hole_px, c.footprint_px, c.sample_mask ? "sample" : "covered",
                Fixed(100 * c.hole_fraction, 4).c_str(), c.enclosed_hole_px, c.silhouette_hole_px,
                c.hole_px - c.enclosed_hole_px - c.silhouette_hole_px);
    if (c.depth_checked)
      std::printf("depth              %zu px TEST in front, %zu behind\n", c.nearer_px, c.farther_px);
    std::printf("compared           %zu px (covered in both, edges left out)\n", c.compared_px);
  }
  std::printf("PSNR               %s dB\n", Fixed(m->psnr_db, 4).c_str());
  std::printf("SSIM luma          %s\n", Fixed(m->ssim_luma, 6).c_str());
  std::printf("SSIM RGB mean      %s\n", Fixed(m->ssim_rgb, 6).c_str());
  std::printf("MS-SSIM luma       %s\n", Fixed(m->ms_ssim_luma, 6).c_str());
  std::printf("FLIP mean          %s (ppd %.4f)\n", Fixed(m->flip_mean, 6).c_str(), ppd);
  if (!map_path.empty()) std::printf("FLIP map           %s\n", map_path.c_str());
  if (!coverage_path.empty()) std::printf("coverage map       %s\n", coverage_path.c_str());
  return 0;
}

}  // namespace

CliCommand CompareCommand() {
  return {"compare", "Image metrics (PSNR, SSIM, MS-SSIM, FLIP) of two images", &RunCompare};
}

}  // namespace pb
