// viewer_compare REFERENCE.png SCREENSHOT.png [--min-ssim X] [--max-coverage-diff X]
//
// For the viewer's browser test (tools/check_viewer.py): compares a
// screenshot of a model in the 3-D viewer with the render.frames frame of the
// same viewpoint. Both are RGBA; alpha > 0 marks covered pixels (the
// renderer's alpha is 255 on geometry, the screenshot is taken over a
// transparent background).
//   coverage_diff = |covered(reference) - covered(screenshot)| / covered(reference)
//   coverage_xor  = pixels covered in exactly one of them / covered(reference)
//   ssim_covered  = mean over the pixels covered in both of the SSIM map
//                   (Wang et al. 2004: 11x11 Gaussian window, sigma 1.5,
//                   K1 = 0.01, K2 = 0.03) of the luma (Y = 0.299 R + 0.587 G +
//                   0.114 B, sRGB values over black), so the background
//                   counts neither for nor against.
// Prints one JSON line with the figures; exit 0 when ssim_covered >=
// --min-ssim (default 0.8) and coverage_diff <= --max-coverage-diff
// (default 0.02), 1 otherwise, 2 on bad input.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "stages/geometry/core/image.h"

namespace {

struct Plane {
  int width = 0, height = 0;
  std::vector<double> luma;
  std::vector<bool> covered;
};

bool Load(const std::string& path, Plane* plane) {
  auto image = pb::ReadPng(path);
  if (!image.ok()) {
    std::fprintf(stderr, "viewer_compare: %s\n", image.status().message().c_str());
    return false;
  }
  if (image->type != pb::Image::PixelType::kU8 || image->channels != 4) {
    std::fprintf(stderr, "viewer_compare: %s: expected an 8-bit RGBA PNG\n", path.c_str());
    return false;
  }
  plane->width = image->width;
  plane->height = image->height;
  const size_t n = size_t(image->width) * size_t(image->height);
  plane->luma.resize(n);
  plane->covered.resize(n);
  const uint8_t* p = image->u8();
  for (size_t i = 0; i < n; ++i, p += 4) {
    const double a = p[3] / 255.0;  // over black
    plane->luma[i] = a * (0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]);
    plane->covered[i] = p[3] > 0;
  }
  return true;
}

// Separable 11-tap Gaussian (sigma 1.5) blur, edges clamped.
std::vector<double> Blur(const std::vector<double>& in, int w, int h) {
  double kernel[11], sum = 0;
  for (int k = -5; k <= 5; ++k) sum += kernel[k + 5] = std::exp(-(k * k) / (2 * 1.5 * 1.5));
  for (double& k : kernel) k /= sum;
  std::vector<double> tmp(in.size()), out(in.size());
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double v = 0;
      for (int k = -5; k <= 5; ++k) v += kernel[k + 5] * in[size_t(y) * w + std::clamp(x + k, 0, w - 1)];
      tmp[size_t(y) * w + x] = v;
    }
  }
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double v = 0;
      for (int k = -5; k <= 5; ++k) v += kernel[k + 5] * tmp[size_t(std::clamp(y + k, 0, h - 1)) * w + x];
      out[size_t(y) * w + x] = v;
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: viewer_compare REFERENCE.png SCREENSHOT.png [--min-ssim X] [--max-coverage-diff X]\n");
    return 2;
  }
  double min_ssim = 0.8, max_coverage_diff = 0.02;
  for (int i = 3; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--min-ssim") min_ssim = std::stod(argv[i + 1]);
    else if (flag == "--max-coverage-diff") max_coverage_diff = std::stod(argv[i + 1]);
    else {
      std::fprintf(stderr, "viewer_compare: unknown option %s\n", flag.c_str());
      return 2;
    }
  }
  Plane ref, test;
  if (!Load(argv[1], &ref) || !Load(argv[2], &test)) return 2;
  if (ref.width != test.width || ref.height != test.height) {
    std::fprintf(stderr, "viewer_compare: %s is %dx%d, %s %dx%d\n", argv[1], ref.width, ref.height, argv[2],
                 test.width, test.height);
    return 2;
  }
  const int w = ref.width, h = ref.height;
  const size_t n = size_t(w) * size_t(h);
  size_t covered_ref = 0, covered_test = 0, covered_both = 0, covered_one = 0;
  for (size_t i = 0; i < n; ++i) {
    covered_ref += ref.covered[i];
    covered_test += test.covered[i];
    covered_both += ref.covered[i] && test.covered[i];
    covered_one += ref.covered[i] != test.covered[i];
  }
  std::vector<double> xx(n), yy(n), xy(n);
  for (size_t i = 0; i < n; ++i) {
    xx[i] = ref.luma[i] * ref.luma[i];
    yy[i] = test.luma[i] * test.luma[i];
    xy[i] = ref.luma[i] * test.luma[i];
  }
  const auto mx = Blur(ref.luma, w, h), my = Blur(test.luma, w, h);
  const auto sxx = Blur(xx, w, h), syy = Blur(yy, w, h), sxy = Blur(xy, w, h);
  const double c1 = (0.01 * 255) * (0.01 * 255), c2 = (0.03 * 255) * (0.03 * 255);
  double ssim_sum = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!(ref.covered[i] && test.covered[i])) continue;
    const double vx = sxx[i] - mx[i] * mx[i], vy = syy[i] - my[i] * my[i], cxy = sxy[i] - mx[i] * my[i];
    ssim_sum += ((2 * mx[i] * my[i] + c1) * (2 * cxy + c2)) /
                ((mx[i] * mx[i] + my[i] * my[i] + c1) * (vx + vy + c2));
  }
  const double ssim = covered_both ? ssim_sum / double(covered_both) : 0.0;
  const double base = covered_ref ? double(covered_ref) : 1.0;
  const double coverage_diff = std::fabs(double(covered_ref) - double(covered_test)) / base;
  const double coverage_xor = double(covered_one) / base;
  const bool pass = covered_both > 0 && ssim >= min_ssim && coverage_diff <= max_coverage_diff;
  std::printf("{\"ssim_covered\": %.4f, \"coverage_reference\": %.4f, \"coverage_screenshot\": %.4f, "
              "\"coverage_diff\": %.4f, \"coverage_xor\": %.4f, \"pass\": %s}\n",
              ssim, double(covered_ref) / double(n), double(covered_test) / double(n), coverage_diff,
              coverage_xor, pass ? "true" : "false");
  return pass ? 0 : 1;
}
