#include "cli/compare_command.h"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

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
    "  FLIP     LDR-FLIP (Andersson et al. 2020, NVIDIA FLIP v1.6), mean error";

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
  if (const std::optional<int> exit = ParseCommandArgs(app, args)) return *exit;

  Image images[2];
  for (int k = 0; k < 2; ++k) {
    Expected<Image> image = ReadImage(files[k]);
    if (!image.ok()) {
      std::fprintf(stderr, "pointbake compare: %s\n", image.status().message().c_str());
      return 2;
    }
    images[k] = std::move(image).value();
  }
  ImageMetricsOptions options;
  options.flip_ppd = ppd;
  FlipResult flip;
  Expected<ImageMetrics> m = CompareImages(images[0], images[1], options, &flip);
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
    std::printf("%s\n", out.dump(2).c_str());
    return 0;
  }
  std::printf("reference  %s (%dx%d)\n", files[0].c_str(), images[0].width, images[0].height);
  std::printf("test       %s\n", files[1].c_str());
  std::printf("PSNR               %s dB\n", Fixed(m->psnr_db, 4).c_str());
  std::printf("SSIM luma          %s\n", Fixed(m->ssim_luma, 6).c_str());
  std::printf("SSIM RGB mean      %s\n", Fixed(m->ssim_rgb, 6).c_str());
  std::printf("MS-SSIM luma       %s\n", Fixed(m->ms_ssim_luma, 6).c_str());
  std::printf("FLIP mean          %s (ppd %.4f)\n", Fixed(m->flip_mean, 6).c_str(), ppd);
  if (!map_path.empty()) std::printf("FLIP map           %s\n", map_path.c_str());
  return 0;
}

}  // namespace

CliCommand CompareCommand() {
  return {"compare", "Image metrics (PSNR, SSIM, MS-SSIM, FLIP) of two images", &RunCompare};
}

}  // namespace pb
