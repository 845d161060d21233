// PSNR, SSIM, MS-SSIM and FLIP; definitions and sources in image_metrics.h.
//
// SSIM / MS-SSIM follow Wang et al. 2004 / 2003 in double precision with the
// conventions stated in the header (population covariances, valid-region
// means), which reproduce scikit-image's float64 SSIM.
//
// FLIP follows Andersson et al. 2020 (HPG) as implemented in NVIDIA's FLIP
// v1.6 (github.com/NVlabs/flip): the CSF filters and feature filters are
// separated into 1-D passes as described in the repository's
// separatedConvolutions.pdf, image borders are clamped, and per-pixel values
// are single precision in the same order of operations, because FLIP's
// reference values are only reproducible that way (this file is built with
// -ffp-contract=off -fno-fast-math). Departure: the mean is summed in double.
#include "stages/geometry/metrics/image_metrics.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

namespace pb {
namespace {

constexpr int kSsimRadius = 5;  // 11x11 window
constexpr int kSsimWindow = 2 * kSsimRadius + 1;
constexpr int kMsSsimScales = 5;
constexpr double kMsSsimWeights[kMsSsimScales] = {0.0448, 0.2856, 0.3001, 0.2363, 0.1333};

// Interleaved 8-bit RGB of an 8-bit gray / gray+alpha / RGB / RGBA image.
struct Rgb8 {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgb;  // width * height * 3
};

Expected<Rgb8> ToRgb8(const Image& image, const char* which) {
  if (image.type != Image::PixelType::kU8)
    return Status::Invalid(std::string(which) + " image: expected 8-bit samples (sRGB), got " +
                           (image.type == Image::PixelType::kU16 ? "16-bit" : "float"));
  if (image.channels < 1 || image.channels > 4 || image.width <= 0 || image.height <= 0 ||
      image.data.size() != image.sample_count())
    return Status::Invalid(std::string(which) + " image: malformed (" +
                           std::to_string(image.width) + "x" + std::to_string(image.height) + ", " +
                           std::to_string(image.channels) + " channels)");
  Rgb8 out;
  out.width = image.width;
  out.height = image.height;
  const size_t pixels = size_t(image.width) * size_t(image.height);
  out.rgb.resize(pixels * 3);
  const uint8_t* src = image.u8();
  const int color_channels = image.channels >= 3 ? 3 : 1;
  for (size_t i = 0; i < pixels; ++i)
    for (int c = 0; c < 3; ++c)
      out.rgb[i * 3 + c] = src[i * image.channels + (color_channels == 3 ? c : 0)];
  return out;
}

Expected<std::pair<Rgb8, Rgb8>> ToRgb8Pair(const Image& reference, const Image& test) {
  PB_ASSIGN_OR_RETURN(Rgb8 a, ToRgb8(reference, "reference"));
  PB_ASSIGN_OR_RETURN(Rgb8 b, ToRgb8(test, "test"));
  if (a.width != b.width || a.height != b.height)
    return Status::Invalid("image sizes differ: reference " + std::to_string(a.width) + "x" +
                           std::to_string(a.height) + ", test " + std::to_string(b.width) + "x" +
                           std::to_string(b.height));
  return std::pair{std::move(a), std::move(b)};
}

std::vector<double> Channel(const Rgb8& image, int channel) {
  std::vector<double> plane(image.rgb.size() / 3);
  for (size_t i = 0; i < plane.size(); ++i) plane[i] = image.rgb[i * 3 + channel];
  return plane;
}

std::vector<double> Luma(const Rgb8& image) {
  std::vector<double> plane(image.rgb.size() / 3);
  for (size_t i = 0; i < plane.size(); ++i)
    plane[i] = 0.299 * image.rgb[i * 3] + 0.587 * image.rgb[i * 3 + 1] + 0.114 * image.rgb[i * 3 + 2];
  return plane;
}

// The normalized 11-tap Gaussian of sigma 1.5; the 2-D window is its outer
// product, so filtering is two 1-D passes.
const std::array<double, kSsimWindow>& SsimKernel() {
  static const std::array<double, kSsimWindow> kernel = [] {
    std::array<double, kSsimWindow> k{};
    double sum = 0;
    for (int i = 0; i < kSsimWindow; ++i) {
      const double d = i - kSsimRadius;
      k[i] = std::exp(-d * d / (2 * 1.5 * 1.5));
      sum += k[i];
    }
    for (double& v : k) v /= sum;
    return k;
  }();
  return kernel;
}

struct SsimMeans {
  double cs = 0;    // mean contrast-structure term
  double ssim = 0;  // mean luminance x contrast-structure
};

// Valid-region means of the SSIM maps of two planes.
// With `mask` (width * height, nonzero = counted), only the positions whose
// window center is in the mask count; no such position gives NaN means.
SsimMeans SsimValidMeans(const std::vector<double>& a, const std::vector<double>& b, int width,
                         int height, const std::vector<uint8_t>* mask = nullptr) {
  const auto& k = SsimKernel();
  const int out_w = width - 2 * kSsimRadius, out_h = height - 2 * kSsimRadius;
  // Horizontal pass of the five moments: out_w x height each.
  enum { kA, kB, kAA, kBB, kAB, kMoments };
  std::vector<double> h(size_t(kMoments) * out_w * height);
  auto at = [&](int m, int x, int y) -> double& { return h[(size_t(m) * height + y) * out_w + x]; };
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < out_w; ++x) {
        double s[kMoments] = {0, 0, 0, 0, 0};
        for (int i = 0; i < kSsimWindow; ++i) {
          const size_t p = size_t(y) * width + x + i;
          const double va = a[p], vb = b[p];
          s[kA] += k[i] * va;
          s[kB] += k[i] * vb;
          s[kAA] += k[i] * (va * va);
          s[kBB] += k[i] * (vb * vb);
          s[kAB] += k[i] * (va * vb);
        }
        for (int m = 0; m < kMoments; ++m) at(m, x, y) = s[m];
      }
  });
  constexpr double kC1 = (0.01 * 255) * (0.01 * 255);
  constexpr double kC2 = (0.03 * 255) * (0.03 * 255);
  // Vertical pass and the maps, summed per row; rows are added in order so
  // the result does not depend on the thread count.
  std::vector<double> row_cs(out_h), row_ssim(out_h), row_count(out_h);
  tbb::parallel_for(tbb::blocked_range<int>(0, out_h), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y) {
      double sum_cs = 0, sum_ssim = 0, count = 0;
      for (int x = 0; x < out_w; ++x) {
        if (mask && !(*mask)[size_t(y + kSsimRadius) * width + x + kSsimRadius]) continue;
        ++count;
        double s[kMoments] = {0, 0, 0, 0, 0};
        for (int i = 0; i < kSsimWindow; ++i)
          for (int m = 0; m < kMoments; ++m) s[m] += k[i] * at(m, x, y + i);
        const double var_a = s[kAA] - s[kA] * s[kA];
        const double var_b = s[kBB] - s[kB] * s[kB];
        const double cov = s[kAB] - s[kA] * s[kB];
        const double luminance = (2 * s[kA] * s[kB] + kC1) / (s[kA] * s[kA] + s[kB] * s[kB] + kC1);
        const double cs = (2 * cov + kC2) / (var_a + var_b + kC2);
        sum_cs += cs;
        sum_ssim += luminance * cs;
      }
      row_cs[y] = sum_cs;
      row_ssim[y] = sum_ssim;
      row_count[y] = count;
    }
  });
  SsimMeans means;
  double n = 0;
  for (int y = 0; y < out_h; ++y) {
    means.cs += row_cs[y];
    means.ssim += row_ssim[y];
    n += row_count[y];
  }
  if (n == 0) return {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  means.cs /= n;
  means.ssim /= n;
  return means;
}

Status CheckSsimSize(int width, int height, int min_side, const char* metric) {
  if (width < min_side || height < min_side)
    return Status::Invalid(std::string(metric) + " needs images of at least " +
                           std::to_string(min_side) + "x" + std::to_string(min_side) +
                           " pixels, got " + std::to_string(width) + "x" + std::to_string(height));
  return Status::Ok();
}

// 2x2 box average; an odd last row / column is dropped.
std::vector<double> Downsample(const std::vector<double>& plane, int width, int height) {
  const int w = width / 2, h = height / 2;
  std::vector<double> out(size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t p = size_t(2 * y) * width + 2 * x;
      out[size_t(y) * w + x] = (plane[p] + plane[p + 1] + plane[p + width] + plane[p + width + 1]) / 4;
    }
  return out;
}

}  // namespace

double FlipDefaultPpd() {
  const float pi = 3.14159265358979f;
  return double(0.7f * (3840.0f / 0.7f) * (pi / 180.0f));
}

Expected<double> Psnr(const Image& reference, const Image& test) {
  PB_ASSIGN_OR_RETURN(auto pair, ToRgb8Pair(reference, test));
  const auto& [a, b] = pair;
  // Integer squared errors: exact, whatever the order.
  uint64_t sum = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    const int d = int(a.rgb[i]) - int(b.rgb[i]);
    sum += uint64_t(d * d);
  }
  if (sum == 0) return std::numeric_limits<double>::infinity();
  const double mse = double(sum) / double(a.rgb.size());
  return 10.0 * std::log10(255.0 * 255.0 / mse);
}

Expected<SsimResult> Ssim(const Image& reference, const Image& test) {
  PB_ASSIGN_OR_RETURN(auto pair, ToRgb8Pair(reference, test));
  const auto& [a, b] = pair;
  PB_RETURN_IF_ERROR(CheckSsimSize(a.width, a.height, kSsimWindow, "SSIM"));
  SsimResult result;
  result.luma = SsimValidMeans(Luma(a), Luma(b), a.width, a.height).ssim;
  double sum = 0;
  for (int c = 0; c < 3; ++c) sum += SsimValidMeans(Channel(a, c), Channel(b, c), a.width, a.height).ssim;
  result.rgb = sum / 3;
  return result;
}

Expected<double> MsSsim(const Image& reference, const Image& test) {
  PB_ASSIGN_OR_RETURN(auto pair, ToRgb8Pair(reference, test));
  const auto& [a, b] = pair;
  PB_RETURN_IF_ERROR(CheckSsimSize(a.width, a.height, kSsimWindow << (kMsSsimScales - 1), "MS-SSIM"));
  std::vector<double> pa = Luma(a), pb = Luma(b);
  int w = a.width, h = a.height;
  double product = 1;
  for (int scale = 0; scale < kMsSsimScales; ++scale) {
    const SsimMeans means = SsimValidMeans(pa, pb, w, h);
    const double term = scale + 1 < kMsSsimScales ? means.cs : means.ssim;
    // A negative base has no real fractional power: 0, as documented.
    product *= std::pow(std::max(term, 0.0), kMsSsimWeights[scale]);
    if (scale + 1 < kMsSsimScales) {
      pa = Downsample(pa, w, h);
      pb = Downsample(pb, w, h);
      w /= 2;
      h /= 2;
    }
  }
  return product;
}

Expected<ImageMetrics> CompareImages(const Image& reference, const Image& test,
                                     const ImageMetricsOptions& options, FlipResult* flip) {
  ImageMetrics m;
  PB_ASSIGN_OR_RETURN(m.psnr_db, Psnr(reference, test));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const bool ssim_fits = reference.width >= kSsimWindow && reference.height >= kSsimWindow;
  const bool ms_ssim_fits = reference.width >= (kSsimWindow << (kMsSsimScales - 1)) &&
                            reference.height >= (kSsimWindow << (kMsSsimScales - 1));
  m.ssim_luma = m.ssim_rgb = m.ms_ssim_luma = nan;
  if (ssim_fits) {
    PB_ASSIGN_OR_RETURN(const SsimResult ssim, Ssim(reference, test));
    m.ssim_luma = ssim.luma;
    m.ssim_rgb = ssim.rgb;
  }
  if (ms_ssim_fits) {
    PB_ASSIGN_OR_RETURN(m.ms_ssim_luma, MsSsim(reference, test));
  }
  PB_ASSIGN_OR_RETURN(FlipResult flip_result, Flip(reference, test, options.flip_ppd));
  m.flip_mean = flip_result.mean;
  if (flip) *flip = std::move(flip_result);
  return m;
}

Image BackgroundToBlack(Image image) {
  if (image.type != Image::PixelType::kU8 || (image.channels != 2 && image.channels != 4) ||
      image.data.size() != image.sample_count())
    return image;
  const size_t pixels = size_t(image.width) * size_t(image.height);
  const int alpha = image.channels - 1;
  uint8_t* px = image.u8();
  for (size_t i = 0; i < pixels; ++i, px += image.channels)
    if (px[alpha] == 0) std::fill(px, px + alpha, uint8_t{0});
  return image;
}

std::optional<std::array<uint8_t, 3>> DrawnBackground(const Image& image) {
  if (image.type != Image::PixelType::kU8 || (image.channels != 2 && image.channels != 4) ||
      image.data.size() != image.sample_count())
    return std::nullopt;
  const size_t pixels = size_t(image.width) * size_t(image.height);
  const int alpha = image.channels - 1;
  std::optional<std::array<uint8_t, 3>> color;
  const uint8_t* px = image.u8();
  for (size_t i = 0; i < pixels; ++i, px += image.channels) {
    if (px[alpha] != 0) continue;
    const std::array<uint8_t, 3> here =
        alpha == 3 ? std::array<uint8_t, 3>{px[0], px[1], px[2]} : std::array<uint8_t, 3>{px[0], px[0], px[0]};
    if (!color) color = here;
    else if (*color != here) return std::nullopt;
  }
  return color;
}

// ---------------------------------------------------------------------------
// Covered pixels (image_metrics.h, CompareCovered).
namespace {

// 1 where the image is covered (alpha > 0; every pixel without alpha).
std::vector<uint8_t> CoverageMask(const Image& image) {
  const size_t pixels = size_t(image.width) * size_t(image.height);
  std::vector<uint8_t> mask(pixels, 1);
  if (image.channels == 2 || image.channels == 4) {
    const uint8_t* src = image.u8();
    for (size_t i = 0; i < pixels; ++i) mask[i] = src[i * image.channels + image.channels - 1] > 0;
  }
  return mask;
}

// 1 where `covered` is 0 and no 4-connected path of uncovered pixels leads to
// the frame's border: background seen through the surface inside its own
// silhouette.
std::vector<uint8_t> EnclosedBackground(const std::vector<uint8_t>& covered, int width, int height) {
  std::vector<uint8_t> outside(covered.size(), 0);
  std::vector<size_t> stack;
  auto push = [&](int x, int y) {
    const size_t i = size_t(y) * width + x;
    if (covered[i] || outside[i]) return;
    outside[i] = 1;
    stack.push_back(i);
  };
  for (int x = 0; x < width; ++x) {
    push(x, 0);
    push(x, height - 1);
  }
  for (int y = 0; y < height; ++y) {
    push(0, y);
    push(width - 1, y);
  }
  while (!stack.empty()) {
    const size_t i = stack.back();
    stack.pop_back();
    const int x = int(i % width), y = int(i / width);
    if (x > 0) push(x - 1, y);
    if (x + 1 < width) push(x + 1, y);
    if (y > 0) push(x, y - 1);
    if (y + 1 < height) push(x, y + 1);
  }
  std::vector<uint8_t> enclosed(covered.size(), 0);
  for (size_t i = 0; i < covered.size(); ++i) enclosed[i] = !covered[i] && !outside[i];
  return enclosed;
}

// 2x2 "any" reduction of a mask, as Downsample halves a plane.
std::vector<uint8_t> DownsampleMask(const std::vector<uint8_t>& mask, int width, int height) {
  const int w = width / 2, h = height / 2;
  std::vector<uint8_t> out(size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t p = size_t(2 * y) * width + 2 * x;
      out[size_t(y) * w + x] = mask[p] | mask[p + 1] | mask[p + width] | mask[p + width + 1];
    }
  return out;
}

}  // namespace

Expected<CoveredComparison> CompareCovered(const Image& reference, const Image& test,
                                           const ImageMetricsOptions& options, FlipResult* flip,
                                           const Image* reference_depth, const Image* test_depth,
                                           const Image* reference_samples, Image* map) {
  PB_ASSIGN_OR_RETURN(auto pair, ToRgb8Pair(reference, test));
  Rgb8& a = pair.first;
  Rgb8& b = pair.second;
  const int w = a.width, h = a.height;
  const size_t pixels = size_t(w) * size_t(h);
  const std::vector<uint8_t> ref_covered = CoverageMask(reference), test_covered = CoverageMask(test);
  const std::vector<uint8_t> enclosed = EnclosedBackground(test_covered, w, h);
  if (reference_samples &&
      (reference_samples->type != Image::PixelType::kU8 || reference_samples->channels != 1 ||
       reference_samples->width != w || reference_samples->height != h))
    return Status::Invalid("covered comparison: a sample mask must be one 8-bit channel of " + std::to_string(w) +
                           "x" + std::to_string(h));
  const uint8_t* samples = reference_samples ? reference_samples->u8() : nullptr;
  CoveredComparison r;
  r.coverage.sample_mask = samples != nullptr;
  std::vector<uint8_t> both(pixels);
  // The map's class of each pixel (CoverageClass); nearer / farther below.
  enum CoverageClass : uint8_t { kNeither, kReferenceOnly, kTestOnly, kBoth, kNearer, kFarther, kHoleOutline,
                                 kHoleOpen, kHoleEnclosed };
  std::vector<uint8_t> classes(map ? pixels : 0, kNeither);
  for (size_t i = 0; i < pixels; ++i) {
    both[i] = ref_covered[i] && test_covered[i];
    r.coverage.reference_px += ref_covered[i];
    r.coverage.test_px += test_covered[i];
    r.coverage.both_px += both[i];
    r.coverage.union_px += ref_covered[i] || test_covered[i];
    r.coverage.splat_hole_px += ref_covered[i] && !test_covered[i];
    const bool footprint = samples ? samples[i] > 0 : ref_covered[i] != 0;
    r.coverage.footprint_px += footprint;
    if (map)
      classes[i] = both[i]            ? kBoth
                   : test_covered[i]  ? kTestOnly
                   : ref_covered[i]   ? kReferenceOnly
                                      : kNeither;
    if (footprint && !test_covered[i]) {
      ++r.coverage.hole_px;
      r.coverage.enclosed_hole_px += enclosed[i];
      if (map) classes[i] = enclosed[i] ? kHoleEnclosed : kHoleOpen;
      if (!enclosed[i]) {
        const int x = int(i % size_t(w)), y = int(i / size_t(w));
        bool touches = false;
        for (int dy = -1; dy <= 1 && !touches; ++dy)
          for (int dx = -1; dx <= 1 && !touches; ++dx) {
            const int nx = x + dx, ny = y + dy;
            touches = nx >= 0 && ny >= 0 && nx < w && ny < h && test_covered[size_t(ny) * w + nx];
          }
        r.coverage.silhouette_hole_px += touches;
        if (map && touches) classes[i] = kHoleOutline;
      }
    }
  }
  r.coverage.iou = r.coverage.union_px == 0 ? 1.0 : double(r.coverage.both_px) / double(r.coverage.union_px);
  r.coverage.hole_fraction =
      r.coverage.footprint_px == 0 ? 0.0 : double(r.coverage.hole_px) / double(r.coverage.footprint_px);
  r.coverage.splat_hole_fraction =
      r.coverage.reference_px == 0 ? 0.0 : double(r.coverage.splat_hole_px) / double(r.coverage.reference_px);
  if ((reference_depth == nullptr) != (test_depth == nullptr))
    return Status::Invalid("covered comparison: give both depth maps or neither");
  if (reference_depth) {
    for (const Image* d : {reference_depth, test_depth})
      if (d->type != Image::PixelType::kF32 || d->channels != 1 || d->width != w || d->height != h)
        return Status::Invalid("covered comparison: a depth map must be one float channel of " + std::to_string(w) +
                               "x" + std::to_string(h));
    if (!(options.depth_tolerance >= 0)) return Status::Invalid("covered comparison: depth_tolerance must be >= 0");
    r.coverage.depth_checked = true;
    const float* dr = reference_depth->f32();
    const float* dt = test_depth->f32();
    for (size_t i = 0; i < pixels; ++i) {
      if (!both[i] || !(dr[i] > 0) || !(dt[i] > 0)) continue;
      const double band = options.depth_tolerance * double(dr[i]);
      if (double(dt[i]) < double(dr[i]) - band) {
        ++r.coverage.nearer_px;
        both[i] = 0;
        if (map) classes[i] = kNearer;
      } else if (double(dt[i]) > double(dr[i]) + band) {
        ++r.coverage.farther_px;
        both[i] = 0;
        if (map) classes[i] = kFarther;
      }
    }
  }
  if (map) {
    *map = Image::Make(w, h, 3, Image::PixelType::kU8);
    static constexpr std::array<std::array<uint8_t, 3>, 9> kColors = {
        kCoverageMapNeither,  kCoverageMapReferenceOnly, kCoverageMapTestOnly,    kCoverageMapNeither /* kBoth */,
        kCoverageMapNearer,   kCoverageMapFarther,       kCoverageMapHoleOutline, kCoverageMapHoleOpen,
        kCoverageMapHoleEnclosed};
    uint8_t* out = map->u8();
    for (size_t i = 0; i < pixels; ++i) {
      std::array<uint8_t, 3> color = kColors[classes[i]];
      if (classes[i] == kBoth) {  // the model, as a gray from its luma
        const double luma = 0.299 * b.rgb[i * 3] + 0.587 * b.rgb[i * 3 + 1] + 0.114 * b.rgb[i * 3 + 2];
        const uint8_t gray = uint8_t(std::lround(96 + luma * (128.0 / 255.0)));
        color = {gray, gray, gray};
      }
      for (int c = 0; c < 3; ++c) out[i * 3 + size_t(c)] = color[size_t(c)];
    }
  }
  // Compared: covered in both, and so are the 4 neighbours (inside the frame):
  // supersampled edge pixels mix the surface with the background.
  std::vector<uint8_t> mask(pixels, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      mask[i] = both[i] && (x == 0 || both[i - 1]) && (x + 1 == w || both[i + 1]) &&
                (y == 0 || both[i - w]) && (y + 1 == h || both[i + w]);
      r.coverage.compared_px += mask[i];
    }
  // Outside the mask the test frame takes the reference's pixels, so windows
  // that straddle the mask's edge see no difference from outside it.
  for (size_t i = 0; i < pixels; ++i)
    if (!mask[i])
      for (int c = 0; c < 3; ++c) b.rgb[i * 3 + c] = a.rgb[i * 3 + c];

  const double nan = std::numeric_limits<double>::quiet_NaN();
  ImageMetrics& m = r.metrics;
  m.psnr_db = m.ssim_luma = m.ssim_rgb = m.ms_ssim_luma = m.flip_mean = nan;
  if (r.coverage.compared_px == 0) {
    if (flip) *flip = FlipResult{w, h, std::vector<float>(pixels, 0.0f), nan};
    return r;
  }
  uint64_t sum = 0;
  for (size_t i = 0; i < b.rgb.size(); ++i) {
    const int d = int(a.rgb[i]) - int(b.rgb[i]);
    sum += uint64_t(d * d);
  }
  m.psnr_db = sum == 0 ? std::numeric_limits<double>::infinity()
                       : 10.0 * std::log10(255.0 * 255.0 / (double(sum) / double(r.coverage.compared_px * 3)));
  if (w >= kSsimWindow && h >= kSsimWindow) {
    m.ssim_luma = SsimValidMeans(Luma(a), Luma(b), w, h, &mask).ssim;
    double rgb = 0;
    for (int c = 0; c < 3; ++c) rgb += SsimValidMeans(Channel(a, c), Channel(b, c), w, h, &mask).ssim;
    m.ssim_rgb = rgb / 3;
  }
  if (w >= (kSsimWindow << (kMsSsimScales - 1)) && h >= (kSsimWindow << (kMsSsimScales - 1))) {
    std::vector<double> pa = Luma(a), pb = Luma(b);
    std::vector<uint8_t> level_mask = mask;
    int lw = w, lh = h;
    double product = 1;
    for (int scale = 0; scale < kMsSsimScales; ++scale) {
      const SsimMeans means = SsimValidMeans(pa, pb, lw, lh, &level_mask);
      const double term = scale + 1 < kMsSsimScales ? means.cs : means.ssim;
      product *= std::isnan(term) ? nan : std::pow(std::max(term, 0.0), kMsSsimWeights[scale]);
      if (scale + 1 < kMsSsimScales) {
        pa = Downsample(pa, lw, lh);
        pb = Downsample(pb, lw, lh);
        level_mask = DownsampleMask(level_mask, lw, lh);
        lw /= 2;
        lh /= 2;
      }
    }
    m.ms_ssim_luma = product;
  }
  // FLIP of the filled frames (RGB, no alpha), averaged over the mask.
  Image ref_rgb = Image::Make(w, h, 3, Image::PixelType::kU8), test_rgb = Image::Make(w, h, 3, Image::PixelType::kU8);
  std::copy(a.rgb.begin(), a.rgb.end(), ref_rgb.u8());
  std::copy(b.rgb.begin(), b.rgb.end(), test_rgb.u8());
  PB_ASSIGN_OR_RETURN(FlipResult flip_result, Flip(ref_rgb, test_rgb, options.flip_ppd));
  double flip_sum = 0;
  for (size_t i = 0; i < pixels; ++i)
    if (mask[i]) flip_sum += flip_result.error[i];
  m.flip_mean = flip_sum / double(r.coverage.compared_px);
  flip_result.mean = m.flip_mean;
  if (flip) *flip = std::move(flip_result);
  return r;
}

// ---------------------------------------------------------------------------
// FLIP (LDR). Single precision throughout, see the top of the file.
namespace {

constexpr float kPi = 3.14159265358979f;

struct Float3 {
  float x = 0, y = 0, z = 0;
};

float SrgbToLinear(float c) {
  if (c <= 0.04045f) return c / 12.92f;
  return std::pow((c + 0.055f) / 1.055f, 2.4f);
}

Float3 LinearRgbToXyz(Float3 c) {
  // sRGB primaries, D65 white.
  const float a11 = 10135552.0f / 24577794.0f, a12 = 8788810.0f / 24577794.0f,
              a13 = 4435075.0f / 24577794.0f;
  const float a21 = 2613072.0f / 12288897.0f, a22 = 8788810.0f / 12288897.0f,
              a23 = 887015.0f / 12288897.0f;
  const float a31 = 1425312.0f / 73733382.0f, a32 = 8788810.0f / 73733382.0f,
              a33 = 70074185.0f / 73733382.0f;
  return {a11 * c.x + a12 * c.y + a13 * c.z, a21 * c.x + a22 * c.y + a23 * c.z,
          a31 * c.x + a32 * c.y + a33 * c.z};
}

Float3 XyzToLinearRgb(Float3 c) {
  return {3.241003275f * c.x + -1.537398934f * c.y + -0.498615861f * c.z,
          -0.969224334f * c.x + 1.875930071f * c.y + 0.041554224f * c.z,
          0.055639423f * c.x + -0.204011202f * c.y + 1.057148933f * c.z};
}

constexpr Float3 kWhite = {0.950428545f, 1.0f, 1.088900371f};     // D65
constexpr Float3 kInvWhite = {1.052156925f, 1.0f, 0.918357670f};  // its inverse

Float3 XyzToYCxCz(Float3 c) {
  const Float3 n = {c.x * kInvWhite.x, c.y * kInvWhite.y, c.z * kInvWhite.z};
  return {116.0f * n.y - 16.0f, 500.0f * (n.x - n.y), 200.0f * (n.y - n.z)};
}

Float3 YCxCzToXyz(Float3 c) {
  const float y = (c.x + 16.0f) / 116.0f;
  const float cx = c.y / 500.0f;
  const float cz = c.z / 200.0f;
  return {(y + cx) * kWhite.x, y * kWhite.y, (y - cz) * kWhite.z};
}

Float3 XyzToLab(Float3 c) {
  const float delta = 6.0f / 29.0f;
  const float delta_square = delta * delta;
  const float delta_cube = delta * delta_square;
  const float factor = 1.0f / (3.0f * delta_square);
  const float term = 4.0f / 29.0f;
  auto f = [&](float v) { return v > delta_cube ? std::pow(v, 1.0f / 3.0f) : factor * v + term; };
  const float fx = f(c.x * kInvWhite.x), fy = f(c.y * kInvWhite.y), fz = f(c.z * kInvWhite.z);
  return {116.0f * fy - 16.0f, 500.0f * (fx - fy), 200.0f * (fy - fz)};
}

// Hunt effect: chroma shrinks with lightness.
Float3 Hunt(Float3 lab) { return {lab.x, 0.01f * lab.x * lab.y, 0.01f * lab.x * lab.z}; }

// HyAB: city-block in L, Euclidean in (a, b).
float HyAb(Float3 p, Float3 q) {
  return std::fabs(p.x - q.x) + std::sqrt((p.y - q.y) * (p.y - q.y) + (p.z - q.z) * (p.z - q.z));
}

constexpr float kQc = 0.7f;   // color difference exponent
constexpr float kPc = 0.4f;   // fraction of cmax where the remap bends
constexpr float kPt = 0.95f;  // remapped value at the bend
constexpr float kW = 0.082f;  // feature filter width, degrees
constexpr float kQf = 0.5f;   // feature difference exponent

// The largest Hunt-adjusted HyAB distance: between pure green and pure blue.
float MaxColorDistance() {
  const Float3 green = Hunt(XyzToLab(LinearRgbToXyz({0.0f, 1.0f, 0.0f})));
  const Float3 blue = Hunt(XyzToLab(LinearRgbToXyz({0.0f, 0.0f, 1.0f})));
  return std::pow(HyAb(green, blue), kQc);
}

// The contrast sensitivity functions of the paper as sums of Gaussians,
// a sqrt(pi/b) exp(-pi^2 x^2 / b), x in degrees; a1, b1 per channel
// (Y, Cx, Cz), a second Gaussian only for Cz.
constexpr Float3 kA1 = {1.0f, 1.0f, 34.1f};
constexpr Float3 kB1 = {0.0047f, 0.0053f, 0.04f};
constexpr Float3 kA2 = {0.0f, 0.0f, 13.5f};
constexpr Float3 kB2 = {1.0e-5f, 1.0e-5f, 0.025f};

float CsfGaussian(float x2, float a, float b) {
  const float pi_sq = float(kPi * kPi);
  return a * std::sqrt(kPi / b) * std::exp(-pi_sq * x2 / b);
}

// The 1-D factor g of a 2-D Gaussian a sqrt(pi/b) exp(..x..) exp(..y..) =
// g(x) g(y), so that Cz's sum of two Gaussians splits into two separable
// filters.
float CsfGaussianSqrt(float x2, float a, float b) {
  const float pi_sq = float(kPi * kPi);
  return std::sqrt(a * std::sqrt(kPi / b)) * std::exp(-pi_sq * x2 / b);
}

struct CsfFilters {
  int radius = 0;
  std::vector<float> y, cx, cz1, cz2;
};

CsfFilters MakeCsfFilters(float ppd) {
  const float pi_sq = float(kPi * kPi);
  const float max_b = std::max({kB1.x, kB1.y, kB1.z, kB2.x, kB2.y, kB2.z});
  CsfFilters f;
  f.radius = int(std::ceil(3.0f * std::sqrt(max_b / (2.0f * pi_sq)) * ppd));
  const int width = 2 * f.radius + 1;
  const float dx = 1.0f / ppd;
  f.y.resize(width);
  f.cx.resize(width);
  f.cz1.resize(width);
  f.cz2.resize(width);
  float sum_y = 0, sum_cx = 0, sum_cz1 = 0, sum_cz2 = 0;
  for (int i = 0; i < width; ++i) {
    const float x = float(i - f.radius) * dx;
    const float x2 = x * x;
    f.y[i] = CsfGaussian(x2, kA1.x, kB1.x);
    f.cx[i] = CsfGaussian(x2, kA1.y, kB1.y);
    f.cz1[i] = CsfGaussianSqrt(x2, kA1.z, kB1.z);
    f.cz2[i] = CsfGaussianSqrt(x2, kA2.z, kB2.z);
    sum_y += f.y[i];
    sum_cx += f.cx[i];
    sum_cz1 += f.cz1[i];
    sum_cz2 += f.cz2[i];
  }
  const float norm_y = 1.0f / sum_y, norm_cx = 1.0f / sum_cx;
  const float norm_cz = 1.0f / std::sqrt(sum_cz1 * sum_cz1 + sum_cz2 * sum_cz2);
  for (int i = 0; i < width; ++i) {
    f.y[i] *= norm_y;
    f.cx[i] *= norm_cx;
    f.cz1[i] *= norm_cz;
    f.cz2[i] *= norm_cz;
  }
  return f;
}

// Gaussian, first and second derivative for edge and point detection, of
// standard deviation 0.5 w ppd pixels. The Gaussian sums to 1, the positive
// and negative lobes of each derivative to +1 and -1.
struct FeatureFilters {
  int radius = 0;
  std::vector<float> g, dg, ddg;
};

FeatureFilters MakeFeatureFilters(float ppd) {
  const float sd = 0.5f * kW * ppd;
  FeatureFilters f;
  f.radius = int(std::ceil(3.0f * sd));
  const int width = 2 * f.radius + 1;
  f.g.resize(width);
  f.dg.resize(width);
  f.ddg.resize(width);
  float g_sum = 0, dg_pos = 0, dg_neg = 0, ddg_pos = 0, ddg_neg = 0;
  for (int i = 0; i < width; ++i) {
    const float x = float(i - f.radius);
    const float g = std::exp(-(x * x) / (2.0f * sd * sd));
    const float dg = -x * g;
    const float ddg = (x * x / (sd * sd) - 1.0f) * g;
    g_sum += g;
    if (dg > 0.0f) dg_pos += dg; else dg_neg -= dg;
    if (ddg > 0.0f) ddg_pos += ddg; else ddg_neg -= ddg;
    f.g[i] = g;
    f.dg[i] = dg;
    f.ddg[i] = ddg;
  }
  for (int i = 0; i < width; ++i) {
    f.g[i] = f.g[i] / g_sum;
    f.dg[i] = f.dg[i] / (f.dg[i] > 0.0f ? dg_pos : dg_neg);
    f.ddg[i] = f.ddg[i] / (f.ddg[i] > 0.0f ? ddg_pos : ddg_neg);
  }
  return f;
}

std::vector<Float3> ToYCxCz(const Rgb8& image) {
  std::vector<Float3> out(image.rgb.size() / 3);
  for (size_t i = 0; i < out.size(); ++i) {
    Float3 c = {float(image.rgb[i * 3]), float(image.rgb[i * 3 + 1]), float(image.rgb[i * 3 + 2])};
    c = {c.x / 255.0f, c.y / 255.0f, c.z / 255.0f};
    out[i] = XyzToYCxCz(LinearRgbToXyz({SrgbToLinear(c.x), SrgbToLinear(c.y), SrgbToLinear(c.z)}));
  }
  return out;
}

template <typename Body>
void ForRows(int height, Body body) {
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y) body(y);
  });
}

// Per-pixel color difference in [0,1] after CSF filtering of both images.
std::vector<float> ColorDifference(const std::vector<Float3>& ref, const std::vector<Float3>& test,
                                   int w, int h, const CsfFilters& f) {
  const float cmax = MaxColorDistance();
  const float pccmax = kPc * cmax;
  // Horizontal pass: (Y, Cx, Cz with filter 1, Cz with filter 2) per image.
  struct Partial { float y, cx, cz1, cz2; };
  std::vector<Partial> hr(size_t(w) * h), ht(size_t(w) * h);
  ForRows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      Partial r{0, 0, 0, 0}, t{0, 0, 0, 0};
      for (int i = -f.radius; i <= f.radius; ++i) {
        const int xx = std::min(std::max(0, x + i), w - 1);
        const size_t k = size_t(i + f.radius), p = size_t(y) * w + xx;
        r.y += f.y[k] * ref[p].x;
        r.cx += f.cx[k] * ref[p].y;
        r.cz1 += f.cz1[k] * ref[p].z;
        r.cz2 += f.cz2[k] * ref[p].z;
        t.y += f.y[k] * test[p].x;
        t.cx += f.cx[k] * test[p].y;
        t.cz1 += f.cz1[k] * test[p].z;
        t.cz2 += f.cz2[k] * test[p].z;
      }
      hr[size_t(y) * w + x] = r;
      ht[size_t(y) * w + x] = t;
    }
  });
  std::vector<float> out(size_t(w) * h);
  auto to_hunt_lab = [](Float3 ycxcz) {
    Float3 rgb = XyzToLinearRgb(YCxCzToXyz(ycxcz));
    rgb = {std::min(std::max(rgb.x, 0.0f), 1.0f), std::min(std::max(rgb.y, 0.0f), 1.0f),
           std::min(std::max(rgb.z, 0.0f), 1.0f)};
    return Hunt(XyzToLab(LinearRgbToXyz(rgb)));
  };
  ForRows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      Partial r{0, 0, 0, 0}, t{0, 0, 0, 0};
      for (int i = -f.radius; i <= f.radius; ++i) {
        const int yy = std::min(std::max(0, y + i), h - 1);
        const size_t k = size_t(i + f.radius), p = size_t(yy) * w + x;
        r.y += f.y[k] * hr[p].y;
        r.cx += f.cx[k] * hr[p].cx;
        r.cz1 += f.cz1[k] * hr[p].cz1;
        r.cz2 += f.cz2[k] * hr[p].cz2;
        t.y += f.y[k] * ht[p].y;
        t.cx += f.cx[k] * ht[p].cx;
        t.cz1 += f.cz1[k] * ht[p].cz1;
        t.cz2 += f.cz2[k] * ht[p].cz2;
      }
      const Float3 lab_r = to_hunt_lab({r.y, r.cx, r.cz1 + r.cz2});
      const Float3 lab_t = to_hunt_lab({t.y, t.cx, t.cz1 + t.cz2});
      float d = std::pow(HyAb(lab_r, lab_t), kQc);
      // Remap: [0, pc cmax) -> [0, pt), [pc cmax, cmax] -> [pt, 1].
      if (d < pccmax)
        d *= kPt / pccmax;
      else
        d = kPt + ((d - pccmax) / (cmax - pccmax)) * (1.0f - kPt);
      out[size_t(y) * w + x] = d;
    }
  });
  return out;
}

// Combines the feature difference (edges, points of the achromatic channel)
// with the color difference into the FLIP error, in place.
void ApplyFeatureDifference(const std::vector<Float3>& ref, const std::vector<Float3>& test, int w,
                            int h, const FeatureFilters& f, std::vector<float>& error) {
  const float one_over_116 = 1.0f / 116.0f;
  const float sixteen_over_116 = 16.0f / 116.0f;
  // Horizontal pass: (first derivative, second derivative, Gaussian) of Y
  // normalized to [0,1].
  std::vector<Float3> hr(size_t(w) * h), ht(size_t(w) * h);
  ForRows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      Float3 r, t;
      for (int i = -f.radius; i <= f.radius; ++i) {
        const int xx = std::min(std::max(0, x + i), w - 1);
        const size_t k = size_t(i + f.radius), p = size_t(y) * w + xx;
        const float yr = ref[p].x * one_over_116 + sixteen_over_116;
        const float yt = test[p].x * one_over_116 + sixteen_over_116;
        r.x += f.dg[k] * yr;
        t.x += f.dg[k] * yt;
        r.y += f.ddg[k] * yr;
        t.y += f.ddg[k] * yt;
        r.z += f.g[k] * yr;
        t.z += f.g[k] * yt;
      }
      hr[size_t(y) * w + x] = r;
      ht[size_t(y) * w + x] = t;
    }
  });
  const float normalization = 1.0f / std::sqrt(2.0f);
  ForRows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      float dx_r = 0, dx_t = 0, ddx_r = 0, ddx_t = 0, dy_r = 0, dy_t = 0, ddy_r = 0, ddy_t = 0;
      for (int i = -f.radius; i <= f.radius; ++i) {
        const int yy = std::min(std::max(0, y + i), h - 1);
        const size_t k = size_t(i + f.radius), p = size_t(yy) * w + x;
        dx_r += f.g[k] * hr[p].x;
        dx_t += f.g[k] * ht[p].x;
        ddx_r += f.g[k] * hr[p].y;
        ddx_t += f.g[k] * ht[p].y;
        dy_r += f.dg[k] * hr[p].z;
        dy_t += f.dg[k] * ht[p].z;
        ddy_r += f.ddg[k] * hr[p].z;
        ddy_t += f.ddg[k] * ht[p].z;
      }
      const float edge_r = std::sqrt(dx_r * dx_r + dy_r * dy_r);
      const float edge_t = std::sqrt(dx_t * dx_t + dy_t * dy_t);
      const float point_r = std::sqrt(ddx_r * ddx_r + ddy_r * ddy_r);
      const float point_t = std::sqrt(ddx_t * ddx_t + ddy_t * ddy_t);
      const float edge_diff = std::fabs(edge_r - edge_t);
      const float point_diff = std::fabs(point_r - point_t);
      const float feature = std::pow(normalization * std::max(edge_diff, point_diff), kQf);
      float& e = error[size_t(y) * w + x];
      e = std::pow(e, 1.0f - feature);
    }
  });
}

}  // namespace

Expected<FlipResult> Flip(const Image& reference, const Image& test, double ppd) {
  if (!(ppd > 0) || !std::isfinite(ppd))
    return Status::Invalid("FLIP: pixels per degree must be a positive number, got " +
                           std::to_string(ppd));
  PB_ASSIGN_OR_RETURN(auto pair, ToRgb8Pair(reference, test));
  const auto& [a, b] = pair;
  const int w = a.width, h = a.height;
  const std::vector<Float3> ref = ToYCxCz(a), tst = ToYCxCz(b);
  FlipResult result;
  result.width = w;
  result.height = h;
  result.error = ColorDifference(ref, tst, w, h, MakeCsfFilters(float(ppd)));
  ApplyFeatureDifference(ref, tst, w, h, MakeFeatureFilters(float(ppd)), result.error);
  double sum = 0;
  for (float e : result.error) sum += e;
  result.mean = sum / double(result.error.size());
  return result;
}

// ---------------------------------------------------------------------------
// The magma colormap: matplotlib's _magma_data (Nathaniel J. Smith and Stefan
// van der Walt, CC0), the 256 sRGB entries FLIP's tool also uses.
namespace {

constexpr float kMagma[256][3] = {
    {0.001462f, 0.000466f, 0.013866f}, {0.002258f, 0.001295f, 0.018331f}, {0.003279f, 0.002305f, 0.023708f}, {0.004512f, 0.003490f, 0.029965f},
    {0.005950f, 0.004843f, 0.037130f}, {0.007588f, 0.006356f, 0.044973f}, {0.009426f, 0.008022f, 0.052844f}, {0.011465f, 0.009828f, 0.060750f},
    {0.013708f, 0.011771f, 0.068667f}, {0.016156f, 0.013840f, 0.076603f}, {0.018815f, 0.016026f, 0.084584f}, {0.021692f, 0.018320f, 0.092610f},
    {0.024792f, 0.020715f, 0.100676f}, {0.028123f, 0.023201f, 0.108787f}, {0.031696f, 0.025765f, 0.116965f}, {0.035520f, 0.028397f, 0.125209f},
    {0.039608f, 0.031090f, 0.133515f}, {0.043830f, 0.033830f, 0.141886f}, {0.048062f, 0.036607f, 0.150327f}, {0.052320f, 0.039407f, 0.158841f},
    {0.056615f, 0.042160f, 0.167446f}, {0.060949f, 0.044794f, 0.176129f}, {0.065330f, 0.047318f, 0.184892f}, {0.069764f, 0.049726f, 0.193735f},
    {0.074257f, 0.052017f, 0.202660f}, {0.078815f, 0.054184f, 0.211667f}, {0.083446f, 0.056225f, 0.220755f}, {0.088155f, 0.058133f, 0.229922f},
    {0.092949f, 0.059904f, 0.239164f}, {0.097833f, 0.061531f, 0.248477f}, {0.102815f, 0.063010f, 0.257854f}, {0.107899f, 0.064335f, 0.267289f},
    {0.113094f, 0.065492f, 0.276784f}, {0.118405f, 0.066479f, 0.286321f}, {0.123833f, 0.067295f, 0.295879f}, {0.129380f, 0.067935f, 0.305443f},
    {0.135053f, 0.068391f, 0.315000f}, {0.140858f, 0.068654f, 0.324538f}, {0.146785f, 0.068738f, 0.334011f}, {0.152839f, 0.068637f, 0.343404f},
    {0.159018f, 0.068354f, 0.352688f}, {0.165308f, 0.067911f, 0.361816f}, {0.171713f, 0.067305f, 0.370771f}, {0.178212f, 0.066576f, 0.379497f},
    {0.184801f, 0.065732f, 0.387973f}, {0.191460f, 0.064818f, 0.396152f}, {0.198177f, 0.063862f, 0.404009f}, {0.204935f, 0.062907f, 0.411514f},
    {0.211718f, 0.061992f, 0.418647f}, {0.218512f, 0.061158f, 0.425392f}, {0.225302f, 0.060445f, 0.431742f}, {0.232077f, 0.059889f, 0.437695f},
    {0.238826f, 0.059517f, 0.443256f}, {0.245543f, 0.059352f, 0.448436f}, {0.252220f, 0.059415f, 0.453248f}, {0.258857f, 0.059706f, 0.457710f},
    {0.265447f, 0.060237f, 0.461840f}, {0.271994f, 0.060994f, 0.465660f}, {0.278493f, 0.061978f, 0.469190f}, {0.284951f, 0.063168f, 0.472451f},
    {0.291366f, 0.064553f, 0.475462f}, {0.297740f, 0.066117f, 0.478243f}, {0.304081f, 0.067835f, 0.480812f}, {0.310382f, 0.069702f, 0.483186f},
    {0.316654f, 0.071690f, 0.485380f}, {0.322899f, 0.073782f, 0.487408f}, {0.329114f, 0.075972f, 0.489287f}, {0.335308f, 0.078236f, 0.491024f},
    {0.341482f, 0.080564f, 0.492631f}, {0.347636f, 0.082946f, 0.494121f}, {0.353773f, 0.085373f, 0.495501f}, {0.359898f, 0.087831f, 0.496778f},
    {0.366012f, 0.090314f, 0.497960f}, {0.372116f, 0.092816f, 0.499053f}, {0.378211f, 0.095332f, 0.500067f}, {0.384299f, 0.097855f, 0.501002f},
    {0.390384f, 0.100379f, 0.501864f}, {0.396467f, 0.102902f, 0.502658f}, {0.402548f, 0.105420f, 0.503386f}, {0.408629f, 0.107930f, 0.504052f},
    {0.414709f, 0.110431f, 0.504662f}, {0.420791f, 0.112920f, 0.505215f}, {0.426877f, 0.115395f, 0.505714f}, {0.432967f, 0.117855f, 0.506160f},
    {0.439062f, 0.120298f, 0.506555f}, {0.445163f, 0.122724f, 0.506901f}, {0.451271f, 0.125132f, 0.507198f}, {0.457386f, 0.127522f, 0.507448f},
    {0.463508f, 0.129893f, 0.507652f}, {0.469640f, 0.132245f, 0.507809f}, {0.475780f, 0.134577f, 0.507921f}, {0.481929f, 0.136891f, 0.507989f},
    {0.488088f, 0.139186f, 0.508011f}, {0.494258f, 0.141462f, 0.507988f}, {0.500438f, 0.143719f, 0.507920f}, {0.506629f, 0.145958f, 0.507806f},
    {0.512831f, 0.148179f, 0.507648f}, {0.519045f, 0.150383f, 0.507443f}, {0.525270f, 0.152569f, 0.507192f}, {0.531507f, 0.154739f, 0.506895f},
    {0.537755f, 0.156894f, 0.506551f}, {0.544015f, 0.159033f, 0.506159f}, {0.550287f, 0.161158f, 0.505719f}, {0.556571f, 0.163269f, 0.505230f},
    {0.562866f, 0.165368f, 0.504692f}, {0.569172f, 0.167454f, 0.504105f}, {0.575490f, 0.169530f, 0.503466f}, {0.581819f, 0.171596f, 0.502777f},
    {0.588158f, 0.173652f, 0.502035f}, {0.594508f, 0.175701f, 0.501241f}, {0.600868f, 0.177743f, 0.500394f}, {0.607238f, 0.179779f, 0.499492f},
    {0.613617f, 0.181811f, 0.498536f}, {0.620005f, 0.183840f, 0.497524f}, {0.626401f, 0.185867f, 0.496456f}, {0.632805f, 0.187893f, 0.495332f},
    {0.639216f, 0.189921f, 0.494150f}, {0.645633f, 0.191952f, 0.492910f}, {0.652056f, 0.193986f, 0.491611f}, {0.658483f, 0.196027f, 0.490253f},
    {0.664915f, 0.198075f, 0.488836f}, {0.671349f, 0.200133f, 0.487358f}, {0.677786f, 0.202203f, 0.485819f}, {0.684224f, 0.204286f, 0.484219f},
    {0.690661f, 0.206384f, 0.482558f}, {0.697098f, 0.208501f, 0.480835f}, {0.703532f, 0.210638f, 0.479049f}, {0.709962f, 0.212797f, 0.477201f},
    {0.716387f, 0.214982f, 0.475290f}, {0.722805f, 0.217194f, 0.473316f}, {0.729216f, 0.219437f, 0.471279f}, {0.735616f, 0.221713f, 0.469180f},
    {0.742004f, 0.224025f, 0.467018f}, {0.748378f, 0.226377f, 0.464794f}, {0.754737f, 0.228772f, 0.462509f}, {0.761077f, 0.231214f, 0.460162f},
    {0.767398f, 0.233705f, 0.457755f}, {0.773695f, 0.236249f, 0.455289f}, {0.779968f, 0.238851f, 0.452765f}, {0.786212f, 0.241514f, 0.450184f},
    {0.792427f, 0.244242f, 0.447543f}, {0.798608f, 0.247040f, 0.444848f}, {0.804752f, 0.249911f, 0.442102f}, {0.810855f, 0.252861f, 0.439305f},
    {0.816914f, 0.255895f, 0.436461f}, {0.822926f, 0.259016f, 0.433573f}, {0.828886f, 0.262229f, 0.430644f}, {0.834791f, 0.265540f, 0.427671f},
    {0.840636f, 0.268953f, 0.424666f}, {0.846416f, 0.272473f, 0.421631f}, {0.852126f, 0.276106f, 0.418573f}, {0.857763f, 0.279857f, 0.415496f},
    {0.863320f, 0.283729f, 0.412403f}, {0.868793f, 0.287728f, 0.409303f}, {0.874176f, 0.291859f, 0.406205f}, {0.879464f, 0.296125f, 0.403118f},
    {0.884651f, 0.300530f, 0.400047f}, {0.889731f, 0.305079f, 0.397002f}, {0.894700f, 0.309773f, 0.393995f}, {0.899552f, 0.314616f, 0.391037f},
    {0.904281f, 0.319610f, 0.388137f}, {0.908884f, 0.324755f, 0.385308f}, {0.913354f, 0.330052f, 0.382563f}, {0.917689f, 0.335500f, 0.379915f},
    {0.921884f, 0.341098f, 0.377376f}, {0.925937f, 0.346844f, 0.374959f}, {0.929845f, 0.352734f, 0.372677f}, {0.933606f, 0.358764f, 0.370541f},
    {0.937221f, 0.364929f, 0.368567f}, {0.940687f, 0.371224f, 0.366762f}, {0.944006f, 0.377643f, 0.365136f}, {0.947180f, 0.384178f, 0.363701f},
    {0.950210f, 0.390820f, 0.362468f}, {0.953099f, 0.397563f, 0.361438f}, {0.955849f, 0.404400f, 0.360619f}, {0.958464f, 0.411324f, 0.360014f},
    {0.960949f, 0.418323f, 0.359630f}, {0.963310f, 0.425390f, 0.359469f}, {0.965549f, 0.432519f, 0.359529f}, {0.967671f, 0.439703f, 0.359810f},
    {0.969680f, 0.446936f, 0.360311f}, {0.971582f, 0.454210f, 0.361030f}, {0.973381f, 0.461520f, 0.361965f}, {0.975082f, 0.468861f, 0.363111f},
    {0.976690f, 0.476226f, 0.364466f}, {0.978210f, 0.483612f, 0.366025f}, {0.979645f, 0.491014f, 0.367783f}, {0.981000f, 0.498428f, 0.369734f},
    {0.982279f, 0.505851f, 0.371874f}, {0.983485f, 0.513280f, 0.374198f}, {0.984622f, 0.520713f, 0.376698f}, {0.985693f, 0.528148f, 0.379371f},
    {0.986700f, 0.535582f, 0.382210f}, {0.987646f, 0.543015f, 0.385210f}, {0.988533f, 0.550446f, 0.388365f}, {0.989363f, 0.557873f, 0.391671f},
    {0.990138f, 0.565296f, 0.395122f}, {0.990871f, 0.572706f, 0.398714f}, {0.991558f, 0.580107f, 0.402441f}, {0.992196f, 0.587502f, 0.406299f},
    {0.992785f, 0.594891f, 0.410283f}, {0.993326f, 0.602275f, 0.414390f}, {0.993834f, 0.609644f, 0.418613f}, {0.994309f, 0.616999f, 0.422950f},
    {0.994738f, 0.624350f, 0.427397f}, {0.995122f, 0.631696f, 0.431951f}, {0.995480f, 0.639027f, 0.436607f}, {0.995810f, 0.646344f, 0.441361f},
    {0.996096f, 0.653659f, 0.446213f}, {0.996341f, 0.660969f, 0.451160f}, {0.996580f, 0.668256f, 0.456192f}, {0.996775f, 0.675541f, 0.461314f},
    {0.996925f, 0.682828f, 0.466526f}, {0.997077f, 0.690088f, 0.471811f}, {0.997186f, 0.697349f, 0.477182f}, {0.997254f, 0.704611f, 0.482635f},
    {0.997325f, 0.711848f, 0.488154f}, {0.997351f, 0.719089f, 0.493755f}, {0.997351f, 0.726324f, 0.499428f}, {0.997341f, 0.733545f, 0.505167f},
    {0.997285f, 0.740772f, 0.510983f}, {0.997228f, 0.747981f, 0.516859f}, {0.997138f, 0.755190f, 0.522806f}, {0.997019f, 0.762398f, 0.528821f},
    {0.996898f, 0.769591f, 0.534892f}, {0.996727f, 0.776795f, 0.541039f}, {0.996571f, 0.783977f, 0.547233f}, {0.996369f, 0.791167f, 0.553499f},
    {0.996162f, 0.798348f, 0.559820f}, {0.995932f, 0.805527f, 0.566202f}, {0.995680f, 0.812706f, 0.572645f}, {0.995424f, 0.819875f, 0.579140f},
    {0.995131f, 0.827052f, 0.585701f}, {0.994851f, 0.834213f, 0.592307f}, {0.994524f, 0.841387f, 0.598983f}, {0.994222f, 0.848540f, 0.605696f},
    {0.993866f, 0.855711f, 0.612482f}, {0.993545f, 0.862859f, 0.619299f}, {0.993170f, 0.870024f, 0.626189f}, {0.992831f, 0.877168f, 0.633109f},
    {0.992440f, 0.884330f, 0.640099f}, {0.992089f, 0.891470f, 0.647116f}, {0.991688f, 0.898627f, 0.654202f}, {0.991332f, 0.905763f, 0.661309f},
    {0.990930f, 0.912915f, 0.668481f}, {0.990570f, 0.920049f, 0.675675f}, {0.990175f, 0.927196f, 0.682926f}, {0.989815f, 0.934329f, 0.690198f},
    {0.989434f, 0.941470f, 0.697519f}, {0.989077f, 0.948604f, 0.704863f}, {0.988717f, 0.955742f, 0.712242f}, {0.988367f, 0.962878f, 0.719649f},
    {0.988033f, 0.970012f, 0.727077f}, {0.987691f, 0.977154f, 0.734536f}, {0.987387f, 0.984288f, 0.742002f}, {0.987053f, 0.991438f, 0.749504f},
};

uint8_t ToByte(float v) { return uint8_t(std::min(std::max(v, 0.0f), 1.0f) * 255.0f + 0.5f); }

}  // namespace

Image FlipErrorColorMap(const FlipResult& flip) {
  Image out = Image::Make(flip.width, flip.height, 3, Image::PixelType::kU8);
  uint8_t* px = out.u8();
  for (size_t i = 0; i < flip.error.size(); ++i) {
    const float v = std::min(std::max(flip.error[i], 0.0f), 1.0f);
    const float* c = kMagma[int(v * 255.0f + 0.5f)];
    for (int k = 0; k < 3; ++k) px[i * 3 + k] = ToByte(c[k]);
  }
  return out;
}

std::array<uint8_t, 3> MagmaColor(int index) {
  assert(index >= 0 && index < 256);
  return {ToByte(kMagma[index][0]), ToByte(kMagma[index][1]), ToByte(kMagma[index][2])};
}

}  // namespace pb
