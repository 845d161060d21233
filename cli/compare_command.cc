#include "cli/compare_command.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "stages/geometry/core/image.h"
#include "stages/geometry/metrics/image_metrics.h"

namespace pb {
namespace {

constexpr const char* kUsage =
    "Usage: pointbake compare REF TEST [--map FLIP.png] [--json] [--ppd X]\n"
    "\n"
    "Image-quality metrics of TEST against REF (8-bit PNGs of equal size; alpha\n"
    "is ignored, gray counts as R = G = B):\n"
    "  PSNR     dB over R, G, B, MAX 255 (inf for identical images)\n"
    "  SSIM     Wang et al. 2004, 11x11 Gaussian sigma 1.5, on luma\n"
    "           Y = 0.299 R + 0.587 G + 0.114 B and as the mean of R, G, B\n"
    "  MS-SSIM  5 scales on luma (n/a below 176x176 pixels)\n"
    "  FLIP     LDR-FLIP (Andersson et al. 2020, NVIDIA FLIP v1.6), mean error\n"
    "\n"
    "Options:\n"
    "  --map FILE  write the FLIP error map (magma colormap) as a PNG\n"
    "  --json      print one JSON object instead of the table (inf/n/a as null)\n"
    "  --ppd X     FLIP's pixels per degree (default 67.0206, FLIP's monitor setup)\n"
    "  -h, --help  this text\n";

int Usage(const std::string& problem) {
  std::fprintf(stderr, "pointbake compare: %s\n\n%s", problem.c_str(), kUsage);
  return 2;
}

nlohmann::json NumberOrNull(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

std::string Fixed(double v, int decimals) {
  if (std::isnan(v)) return "n/a";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

int RunCompare(const std::vector<std::string>& args) {
  std::vector<std::string> files;
  std::string map_path;
  bool json = false;
  double ppd = FlipDefaultPpd();
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (a == "--json") {
      json = true;
    } else if (a == "--map" || a == "--ppd") {
      if (i + 1 >= args.size()) return Usage(a + " needs a value");
      const std::string& value = args[++i];
      if (a == "--map") {
        map_path = value;
      } else {
        char* end = nullptr;
        ppd = std::strtod(value.c_str(), &end);
        if (value.empty() || *end != '\0' || !(ppd > 0) || !std::isfinite(ppd))
          return Usage("--ppd must be a positive number, got '" + value + "'");
      }
    } else if (a.size() > 1 && a[0] == '-') {
      return Usage("unknown option '" + a + "'");
    } else {
      files.push_back(a);
    }
  }
  if (files.size() != 2) return Usage("expected two images, REF and TEST");

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
