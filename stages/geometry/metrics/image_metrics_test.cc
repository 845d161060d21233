// PSNR, SSIM, MS-SSIM and FLIP against the independent reference values of
// issue 7 (official FLIP v1.6; a float64 SSIM agreeing with scikit-image to
// 1e-13) and against closed-form cases.
#include "stages/geometry/metrics/image_metrics.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <limits>

namespace pb {
namespace {

constexpr int kSize = 256;

Image MakeRgb(int width, int height, const std::function<int(int, int, int)>& value) {
  Image image = Image::Make(width, height, 3, Image::PixelType::kU8);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) image.at_u8(x, y, c) = uint8_t(value(x, y, c));
  return image;
}

// The formulas; integer arithmetic, `/` is floor division (all
// operands are non-negative here, so C++'s truncation is the same).
int R0(int x, int y, int c) { return ((x * x + 3 * x * y + 7 * y * y) / 16 + 2 * x + y + 40 * c) % 256; }
int T1(int x, int y, int c) {
  return std::clamp(R0(x, y, c) + ((17 * x + 31 * y + (x * y % 13) + 5 * c) % 21) - 10, 0, 255);
}
int T2(int x, int y, int c) {
  int sum = 0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      sum += R0(std::clamp(x + dx, 0, kSize - 1), std::clamp(y + dy, 0, kSize - 1), c);
  return (sum + 4) / 9;
}

Image Gray(int width, int height, int level) {
  return MakeRgb(width, height, [level](int, int, int) { return level; });
}

struct Reference {
  const char* name;
  Image reference, test;
  double psnr_db, ssim_luma, ssim_rgb, ms_ssim_luma, flip;
};

std::vector<Reference> ReferenceCases() {
  const Image r0 = MakeRgb(kSize, kSize, R0);
  return {
      {"R0,T1", r0, MakeRgb(kSize, kSize, T1), 32.5856, 0.997619, 0.996503, 0.997406, 0.0620375},
      {"R0,T2", r0, MakeRgb(kSize, kSize, T2), 11.2835, 0.179604, 0.145733, 0.693916, 0.299146},
      {"C100,C110", Gray(kSize, kSize, 100), Gray(kSize, kSize, 110), 28.1308, 0.995476, 0.995476,
       0.999396, 0.153475},
  };
}

// Tolerances: the table gives 6 significant digits. PSNR within 1e-4 dB (the
// table's rounding; 1e-5 relative would be 3e-4 dB), SSIM and MS-SSIM within
// 1e-5 absolute, FLIP within 1e-3 relative.
TEST(ImageMetricsTest, ReproducesReferenceTable) {
  for (const Reference& r : ReferenceCases()) {
    SCOPED_TRACE(r.name);
    Expected<ImageMetrics> m = CompareImages(r.reference, r.test);
    ASSERT_TRUE(m.ok()) << m.status().message();
    std::printf("%-10s PSNR %.10f  SSIM-Y %.10f  SSIM-RGB %.10f  MS-SSIM %.10f  FLIP %.10f\n", r.name,
                m->psnr_db, m->ssim_luma, m->ssim_rgb, m->ms_ssim_luma, m->flip_mean);
    EXPECT_NEAR(m->psnr_db, r.psnr_db, 1e-4);
    EXPECT_NEAR(m->ssim_luma, r.ssim_luma, 1e-5);
    EXPECT_NEAR(m->ssim_rgb, r.ssim_rgb, 1e-5);
    EXPECT_NEAR(m->ms_ssim_luma, r.ms_ssim_luma, 1e-5);
    EXPECT_NEAR(m->flip_mean, r.flip, 1e-3 * r.flip);
  }
}

TEST(ImageMetricsTest, DefaultPpdIsFlipsMonitorSetup) {
  EXPECT_NEAR(FlipDefaultPpd(), 67.0206, 5e-5);
}

TEST(ImageMetricsTest, IdenticalImages) {
  const Image r0 = MakeRgb(kSize, kSize, R0);
  Expected<ImageMetrics> m = CompareImages(r0, r0);
  ASSERT_TRUE(m.ok()) << m.status().message();
  EXPECT_TRUE(std::isinf(m->psnr_db) && m->psnr_db > 0);
  EXPECT_NEAR(m->ssim_luma, 1.0, 1e-12);
  EXPECT_NEAR(m->ssim_rgb, 1.0, 1e-12);
  EXPECT_NEAR(m->ms_ssim_luma, 1.0, 1e-12);
  EXPECT_EQ(m->flip_mean, 0.0);
}

// A constant offset of d levels: MSE = d^2 exactly, PSNR = 20 log10(255/d).
TEST(ImageMetricsTest, ConstantOffsetPsnr) {
  const Image r0 = MakeRgb(64, 48, [](int x, int y, int c) { return std::min(R0(x, y, c), 200); });
  for (int d : {1, 3, 17, 55}) {
    const Image shifted = MakeRgb(64, 48, [d](int x, int y, int c) { return std::min(R0(x, y, c), 200) + d; });
    Expected<double> psnr = Psnr(r0, shifted);
    ASSERT_TRUE(psnr.ok());
    EXPECT_DOUBLE_EQ(*psnr, 20 * std::log10(255.0 / d)) << d;
  }
}

// Uniform images: the SSIM map is constant and equals the luminance term
// (2 a b + C1) / (a^2 + b^2 + C1), variances being zero.
TEST(ImageMetricsTest, SsimOfUniformImagesIsLuminanceTerm) {
  Expected<SsimResult> s = Ssim(Gray(40, 30, 100), Gray(40, 30, 110));
  ASSERT_TRUE(s.ok());
  const double c1 = (0.01 * 255) * (0.01 * 255);
  const double expected = (2.0 * 100 * 110 + c1) / (100.0 * 100 + 110.0 * 110 + c1);
  EXPECT_NEAR(s->luma, expected, 1e-13);
  EXPECT_NEAR(s->rgb, expected, 1e-13);
}

// An image against its negative: SSIM strongly negative, and MS-SSIM 0
// rather than NaN (negative terms count as 0).
TEST(ImageMetricsTest, NegativeImage) {
  const Image a = MakeRgb(kSize, kSize, R0);
  const Image b = MakeRgb(kSize, kSize, [](int x, int y, int c) { return 255 - R0(x, y, c); });
  Expected<ImageMetrics> m = CompareImages(a, b);
  ASSERT_TRUE(m.ok());
  EXPECT_LT(m->ssim_rgb, -0.5);
  EXPECT_EQ(m->ms_ssim_luma, 0.0);
  EXPECT_GT(m->flip_mean, 0.3);
}

TEST(ImageMetricsTest, SymmetricMetrics) {
  const Image a = MakeRgb(kSize, kSize, R0), b = MakeRgb(kSize, kSize, T1);
  Expected<ImageMetrics> ab = CompareImages(a, b), ba = CompareImages(b, a);
  ASSERT_TRUE(ab.ok() && ba.ok());
  EXPECT_EQ(ab->psnr_db, ba->psnr_db);
  EXPECT_NEAR(ab->ssim_luma, ba->ssim_luma, 1e-15);
  EXPECT_NEAR(ab->ssim_rgb, ba->ssim_rgb, 1e-15);
  EXPECT_NEAR(ab->ms_ssim_luma, ba->ms_ssim_luma, 1e-15);
  // FLIP is symmetric too: every step treats the two images alike.
  EXPECT_NEAR(ab->flip_mean, ba->flip_mean, 1e-7);
}

TEST(ImageMetricsTest, GrayAndAlphaChannelsCountAsRgb) {
  const Image rgb = MakeRgb(32, 32, [](int x, int y, int) { return (x * 7 + y * 3) % 256; });
  Image gray = Image::Make(32, 32, 1, Image::PixelType::kU8);
  Image rgba = Image::Make(32, 32, 4, Image::PixelType::kU8);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      gray.at_u8(x, y, 0) = rgb.at_u8(x, y, 0);
      for (int c = 0; c < 3; ++c) rgba.at_u8(x, y, c) = rgb.at_u8(x, y, c);
      rgba.at_u8(x, y, 3) = uint8_t(x * 8);  // ignored
    }
  const Image other = Gray(32, 32, 90);
  Expected<ImageMetrics> m_rgb = CompareImages(rgb, other), m_gray = CompareImages(gray, other),
                         m_rgba = CompareImages(rgba, other);
  ASSERT_TRUE(m_rgb.ok() && m_gray.ok() && m_rgba.ok());
  for (const auto* m : {&*m_gray, &*m_rgba}) {
    EXPECT_EQ(m->psnr_db, m_rgb->psnr_db);
    EXPECT_EQ(m->ssim_luma, m_rgb->ssim_luma);
    EXPECT_EQ(m->flip_mean, m_rgb->flip_mean);
  }
  // 32 px is too small for MS-SSIM's five scales: NaN, not an error.
  EXPECT_TRUE(std::isnan(m_rgb->ms_ssim_luma));
  EXPECT_FALSE(MsSsim(rgb, other).ok());
}

TEST(ImageMetricsTest, DrawnBackgroundAndBackgroundToBlack) {
  Image rgba = Image::Make(4, 3, 4, Image::PixelType::kU8);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) {
      const bool covered = x == 1;
      const uint8_t color[4] = {uint8_t(covered ? 90 : 255), uint8_t(covered ? 40 : 0), uint8_t(covered ? 10 : 255),
                                uint8_t(covered ? 255 : 0)};
      for (int c = 0; c < 4; ++c) rgba.at_u8(x, y, c) = color[c];
    }
  ASSERT_TRUE(DrawnBackground(rgba).has_value());
  EXPECT_EQ(*DrawnBackground(rgba), (std::array<uint8_t, 3>{255, 0, 255}));
  const Image on_black = BackgroundToBlack(rgba);
  EXPECT_EQ(*DrawnBackground(on_black), (std::array<uint8_t, 3>{0, 0, 0}));
  EXPECT_EQ(on_black.at_u8(1, 2, 0), 90);  // covered pixels are kept
  EXPECT_EQ(on_black.at_u8(0, 2, 3), 0);   // and alpha
  // Two colours under alpha 0, no pixel without alpha, no alpha at all: none.
  Image mixed = rgba;
  mixed.at_u8(3, 2, 1) = 7;
  EXPECT_FALSE(DrawnBackground(mixed).has_value());
  Image opaque = rgba;
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) opaque.at_u8(x, y, 3) = 255;
  EXPECT_FALSE(DrawnBackground(opaque).has_value());
  Image rgb = Image::Make(4, 3, 3, Image::PixelType::kU8);
  EXPECT_FALSE(DrawnBackground(rgb).has_value());
  EXPECT_EQ(BackgroundToBlack(rgb).data, rgb.data);
}

TEST(ImageMetricsTest, BadInputIsInvalid) {
  const Image a = Gray(64, 64, 10), b = Gray(64, 63, 10);
  for (const Status& s : {Psnr(a, b).status(), Ssim(a, b).status(), MsSsim(a, b).status(),
                          Flip(a, b).status(), CompareImages(a, b).status()}) {
    EXPECT_EQ(s.code(), Status::Code::kInvalid);
    EXPECT_NE(s.message().find("64x63"), std::string::npos) << s.message();
  }
  Image wide = Image::Make(64, 64, 3, Image::PixelType::kU16);
  EXPECT_EQ(Psnr(wide, wide).status().code(), Status::Code::kInvalid);
  EXPECT_EQ(Flip(a, a, 0.0).status().code(), Status::Code::kInvalid);
  EXPECT_EQ(Flip(a, a, std::nan("")).status().code(), Status::Code::kInvalid);
  EXPECT_EQ(Ssim(Gray(10, 64, 1), Gray(10, 64, 1)).status().code(), Status::Code::kInvalid);
}

// FLIP's error map: size, range, zero where nothing differs far away, and
// its mean is the reported mean.
TEST(ImageMetricsTest, FlipMapAndColorMap) {
  const Image a = Gray(80, 60, 128);
  Image b = a;
  for (int c = 0; c < 3; ++c) b.at_u8(40, 30, c) = 255;  // one white pixel
  Expected<FlipResult> flip = Flip(a, b);
  ASSERT_TRUE(flip.ok());
  ASSERT_EQ(flip->error.size(), size_t(80 * 60));
  double sum = 0;
  for (float e : flip->error) {
    EXPECT_GE(e, 0.0f);
    EXPECT_LE(e, 1.0f);
    sum += e;
  }
  EXPECT_DOUBLE_EQ(flip->mean, sum / (80 * 60));
  EXPECT_GT(flip->error[30 * 80 + 40], 0.1f);
  EXPECT_EQ(flip->error[0], 0.0f);  // beyond every filter's reach
  const Image map = FlipErrorColorMap(*flip);
  ASSERT_EQ(map.width, 80);
  ASSERT_EQ(map.channels, 3);
  EXPECT_EQ((std::array<uint8_t, 3>{map.at_u8(0, 0, 0), map.at_u8(0, 0, 1), map.at_u8(0, 0, 2)}),
            MagmaColor(0));
}

// The transcribed colormap: the published end points, and magma's luminance
// rising monotonically (a wrong digit in the table would likely break it).
TEST(ImageMetricsTest, MagmaTable) {
  EXPECT_EQ(MagmaColor(0), (std::array<uint8_t, 3>{0, 0, 4}));
  EXPECT_EQ(MagmaColor(255), (std::array<uint8_t, 3>{252, 253, 191}));
  double previous = -1;
  for (int i = 0; i < 256; ++i) {
    const auto c = MagmaColor(i);
    auto linear = [](uint8_t v) {
      const double s = v / 255.0;
      return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
    };
    const double luma = 0.2126 * linear(c[0]) + 0.7152 * linear(c[1]) + 0.0722 * linear(c[2]);
    EXPECT_GE(luma, previous) << i;
    previous = luma;
  }
}

// Rows are summed in a fixed order: the same bits on 1 and 2 threads.
TEST(ImageMetricsTest, SameResultOnAnyThreadCount) {
  const Image a = MakeRgb(kSize, kSize, R0), b = MakeRgb(kSize, kSize, T2);
  ImageMetrics m[2];
  FlipResult flip[2];
  for (int threads : {1, 2}) {
    tbb::task_arena arena(threads);
    arena.execute([&] {
      Expected<ImageMetrics> r = CompareImages(a, b, {}, &flip[threads - 1]);
      ASSERT_TRUE(r.ok());
      m[threads - 1] = *r;
    });
  }
  EXPECT_EQ(m[0].ssim_luma, m[1].ssim_luma);
  EXPECT_EQ(m[0].ssim_rgb, m[1].ssim_rgb);
  EXPECT_EQ(m[0].ms_ssim_luma, m[1].ms_ssim_luma);
  EXPECT_EQ(m[0].flip_mean, m[1].flip_mean);
  EXPECT_EQ(flip[0].error, flip[1].error);
}

// ---- covered pixels ----

// An RGBA frame: R0's texture (plus `offset`) where `covered`, black and
// alpha 0 elsewhere.
Image Frame(int size, const std::function<bool(int, int)>& covered, int offset = 0) {
  Image image = Image::Make(size, size, 4, Image::PixelType::kU8);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const bool on = covered(x, y);
      for (int c = 0; c < 3; ++c) image.at_u8(x, y, c) = on ? uint8_t(std::clamp(R0(x, y, c) / 2 + 40 + offset, 0, 255)) : 0;
      image.at_u8(x, y, 3) = on ? 255 : 0;
    }
  return image;
}

bool Disk(int x, int y, double cx, double cy, double r) { return (x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r; }

TEST(CoveredTest, IdenticalFramesScorePerfectly) {
  const Image frame = Frame(kSize, [](int x, int y) { return Disk(x, y, 128, 128, 90); });
  Expected<CoveredComparison> r = CompareCovered(frame, frame);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->metrics.psnr_db, std::numeric_limits<double>::infinity());
  EXPECT_DOUBLE_EQ(r->metrics.ssim_luma, 1.0);
  EXPECT_DOUBLE_EQ(r->metrics.ssim_rgb, 1.0);
  EXPECT_DOUBLE_EQ(r->metrics.ms_ssim_luma, 1.0);
  EXPECT_EQ(r->metrics.flip_mean, 0.0);
  EXPECT_EQ(r->coverage.iou, 1.0);
  EXPECT_EQ(r->coverage.hole_px, 0u);
  EXPECT_EQ(r->coverage.both_px, r->coverage.reference_px);
  EXPECT_GT(r->coverage.compared_px, 24000u);  // pi 90^2 = 25447, minus the rim
  EXPECT_LT(r->coverage.compared_px, r->coverage.both_px);
}

TEST(CoveredTest, CountsHolePixelsExactly) {
  // Reference: covered everywhere. Test: a 7 x 5 hole inside (enclosed) and a
  // 3-pixel strip along the left border (a silhouette miss, not enclosed).
  const Image reference = Frame(64, [](int, int) { return true; });
  auto covered = [](int x, int y) {
    const bool hole = x >= 30 && x < 37 && y >= 20 && y < 25;
    return !hole && x >= 3;
  };
  const Image test = Frame(64, covered);
  Expected<CoveredComparison> r = CompareCovered(reference, test);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->coverage.reference_px, 64u * 64u);
  EXPECT_EQ(r->coverage.hole_px, 35u + 3u * 64u);
  EXPECT_EQ(r->coverage.enclosed_hole_px, 35u);
  EXPECT_EQ(r->coverage.silhouette_hole_px, 64u);  // the strip's column next to the covered pixels
  EXPECT_DOUBLE_EQ(r->coverage.hole_fraction, (35.0 + 192.0) / 4096.0);
  EXPECT_DOUBLE_EQ(r->coverage.iou, (4096.0 - 227.0) / 4096.0);
  // The same texture where both are covered.
  EXPECT_EQ(r->metrics.psnr_db, std::numeric_limits<double>::infinity());
  // The compared pixels leave out the ring around the hole and the strip.
  EXPECT_EQ(r->coverage.compared_px, 4096u - 227u - (2u * 7u + 2u * 5u) - 64u);
  // Whole-frame metrics see the holes as black texture.
  Expected<ImageMetrics> whole = CompareImages(reference, test);
  ASSERT_TRUE(whole.ok());
  EXPECT_LT(whole->psnr_db, 25);  // 5.5 % of the pixels black instead of ~100
}

TEST(CoveredTest, HolesCountOnTheSampleMaskWhenGiven) {
  // Reference: a disk of radius 20 drawn around samples that fill a disk of
  // radius 16 only (the splats reach past the last samples). Test: covered
  // on the radius-16 disk except a 4 x 4 hole at its middle.
  const Image reference = Frame(64, [](int x, int y) { return Disk(x, y, 32, 32, 20); });
  const Image test = Frame(64, [](int x, int y) {
    return Disk(x, y, 32, 32, 16) && !(x >= 30 && x < 34 && y >= 30 && y < 34);
  });
  Image samples = Image::Make(64, 64, 1, Image::PixelType::kU8);
  size_t sample_px = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      samples.at_u8(x, y, 0) = Disk(x, y, 32, 32, 16) ? 255 : 0;
      sample_px += samples.at_u8(x, y, 0) != 0;
    }
  Expected<CoveredComparison> r = CompareCovered(reference, test, {}, nullptr, nullptr, nullptr, &samples);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_TRUE(r->coverage.sample_mask);
  EXPECT_EQ(r->coverage.footprint_px, sample_px);
  EXPECT_EQ(r->coverage.hole_px, 16u);
  EXPECT_EQ(r->coverage.enclosed_hole_px, 16u);
  EXPECT_EQ(r->coverage.silhouette_hole_px, 0u);
  EXPECT_DOUBLE_EQ(r->coverage.hole_fraction, 16.0 / double(sample_px));
  // The disks' count: the hole and the ring between radius 16 and 20.
  EXPECT_EQ(r->coverage.splat_hole_px, r->coverage.reference_px - (sample_px - 16));
  EXPECT_DOUBLE_EQ(r->coverage.splat_hole_fraction,
                   double(r->coverage.splat_hole_px) / double(r->coverage.reference_px));
  // Without a mask both counts are the disks'.
  Expected<CoveredComparison> plain = CompareCovered(reference, test);
  ASSERT_TRUE(plain.ok());
  EXPECT_FALSE(plain->coverage.sample_mask);
  EXPECT_EQ(plain->coverage.hole_px, r->coverage.splat_hole_px);
  EXPECT_EQ(plain->coverage.footprint_px, plain->coverage.reference_px);
  // A mask of the wrong size or type is refused.
  const Image small = Image::Make(32, 32, 1, Image::PixelType::kU8);
  EXPECT_FALSE(CompareCovered(reference, test, {}, nullptr, nullptr, nullptr, &small).ok());
}

TEST(CoveredTest, SilhouetteDifferenceDoesNotChangeCoveredPsnr) {
  // The test frames are the reference's texture plus 10 wherever they are
  // covered, on a disk that is smaller, the same, or larger than the
  // reference's: the covered-pixel PSNR is 20 log10(255 / 10) for each; only
  // the coverage figures tell them apart.
  const Image reference = Frame(kSize, [](int x, int y) { return Disk(x, y, 128, 128, 80); });
  const double expected_psnr = 20 * std::log10(255.0 / 10.0);
  double previous_iou = -1;
  for (double radius : {60.0, 80.0, 100.0}) {
    const Image test = Frame(kSize, [&](int x, int y) { return Disk(x, y, 120, 128, radius); }, 10);
    Expected<CoveredComparison> r = CompareCovered(reference, test);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_NEAR(r->metrics.psnr_db, expected_psnr, 1e-12) << radius;
    EXPECT_GT(r->metrics.ssim_luma, 0.9) << radius;  // a constant offset barely moves SSIM
    EXPECT_NE(r->coverage.iou, previous_iou);
    previous_iou = r->coverage.iou;
    Expected<ImageMetrics> whole = CompareImages(reference, test);
    ASSERT_TRUE(whole.ok());
    EXPECT_LT(whole->psnr_db, expected_psnr - 3) << radius;  // silhouette errors dominate the whole frame
  }
}

TEST(CoveredTest, NoCommonCoverageGivesNaNAndZeroIou) {
  const Image left = Frame(32, [](int x, int) { return x < 10; });
  const Image right = Frame(32, [](int x, int) { return x > 20; });
  Expected<CoveredComparison> r = CompareCovered(left, right);
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(std::isnan(r->metrics.psnr_db));
  EXPECT_TRUE(std::isnan(r->metrics.flip_mean));
  EXPECT_EQ(r->coverage.iou, 0.0);
  EXPECT_EQ(r->coverage.hole_px, 10u * 32u);
  EXPECT_EQ(r->coverage.enclosed_hole_px, 0u);
}

TEST(CoveredTest, DepthMapsSetSurfacesInFrontOrBehindApart) {
  // The same frame, but a 10 x 10 block of the test frame is another surface
  // 0.5 m in front (and of another color), a 6 x 6 block one 1 m behind.
  const int size = 64;
  const Image reference = Frame(size, [](int, int) { return true; });
  Image test = reference;
  Image reference_depth = Image::Make(size, size, 1, Image::PixelType::kF32);
  Image test_depth = Image::Make(size, size, 1, Image::PixelType::kF32);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      float d = 2.0f;
      const bool front = x >= 10 && x < 20 && y >= 10 && y < 20, behind = x >= 40 && x < 46 && y >= 30 && y < 36;
      if (front) d = 1.5f;
      if (behind) d = 3.0f;
      if (front || behind)
        for (int c = 0; c < 3; ++c) test.at_u8(x, y, c) = uint8_t(255 - test.at_u8(x, y, c));
      reference_depth.at_f32(x, y, 0) = 2.0f;
      test_depth.at_f32(x, y, 0) = d;
    }
  Expected<CoveredComparison> without = CompareCovered(reference, test);
  ASSERT_TRUE(without.ok());
  EXPECT_FALSE(without->coverage.depth_checked);
  EXPECT_LT(without->metrics.psnr_db, 30);  // the blocks count as texture error
  Expected<CoveredComparison> r = CompareCovered(reference, test, {}, nullptr, &reference_depth, &test_depth);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_TRUE(r->coverage.depth_checked);
  EXPECT_EQ(r->coverage.nearer_px, 100u);
  EXPECT_EQ(r->coverage.farther_px, 36u);
  EXPECT_EQ(r->coverage.iou, 1.0);  // coverage is coverage
  EXPECT_EQ(r->coverage.compared_px, size_t(size * size - 100 - 40 - 36 - 24));
  EXPECT_EQ(r->metrics.psnr_db, std::numeric_limits<double>::infinity());
  EXPECT_FALSE(CompareCovered(reference, test, {}, nullptr, &reference_depth, nullptr).ok());
}

// The coverage map: one colour per class of pixel, counted the same as the
// figures. Reference: the left 48 columns. Test: columns 3..55 (the strip
// 0..2 an outline miss, 48..55 only the test's), with an enclosed 4 x 4 hole
// and a 5 x 5 block 0.5 m in front, a 3 x 3 block 1 m behind; with depth.
TEST(CoveredTest, TheCoverageMapShowsEachClassOfPixel) {
  const int size = 64;
  const Image reference = Frame(size, [](int x, int) { return x < 48; });
  const Image test = Frame(size, [](int x, int y) {
    const bool hole = x >= 20 && x < 24 && y >= 20 && y < 24;
    return !hole && x >= 3 && x < 56;
  });
  Image reference_depth = Image::Make(size, size, 1, Image::PixelType::kF32);
  Image test_depth = Image::Make(size, size, 1, Image::PixelType::kF32);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      reference_depth.at_f32(x, y, 0) = x < 48 ? 2.0f : 0.0f;
      const bool front = x >= 30 && x < 35 && y >= 40 && y < 45, behind = x >= 10 && x < 13 && y >= 50 && y < 53;
      test_depth.at_f32(x, y, 0) = front ? 1.5f : behind ? 3.0f : 2.0f;
    }
  Image map;
  Expected<CoveredComparison> r =
      CompareCovered(reference, test, {}, nullptr, &reference_depth, &test_depth, nullptr, &map);
  ASSERT_TRUE(r.ok()) << r.status().message();
  ASSERT_EQ(map.width, size);
  ASSERT_EQ(map.channels, 3);
  std::map<std::array<uint8_t, 3>, size_t> counts;
  size_t gray = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const std::array<uint8_t, 3> c = {map.at_u8(x, y, 0), map.at_u8(x, y, 1), map.at_u8(x, y, 2)};
      const bool is_gray = c[0] == c[1] && c[1] == c[2] && c[0] >= 96 && c[0] <= 224;
      gray += is_gray;
      if (!is_gray) ++counts[c];
    }
  EXPECT_EQ(counts[kCoverageMapHoleEnclosed], r->coverage.enclosed_hole_px);
  EXPECT_EQ(counts[kCoverageMapHoleEnclosed], 16u);
  EXPECT_EQ(counts[kCoverageMapHoleOutline], r->coverage.silhouette_hole_px);
  EXPECT_EQ(counts[kCoverageMapHoleOutline], 64u);  // column 2
  EXPECT_EQ(counts[kCoverageMapHoleOpen], r->coverage.hole_px - 16u - 64u);
  EXPECT_EQ(counts[kCoverageMapHoleOpen], 128u);  // columns 0 and 1
  EXPECT_EQ(counts[kCoverageMapNearer], r->coverage.nearer_px);
  EXPECT_EQ(counts[kCoverageMapNearer], 25u);
  EXPECT_EQ(counts[kCoverageMapFarther], 9u);
  EXPECT_EQ(counts[kCoverageMapTestOnly], size_t(8 * size));
  EXPECT_EQ(counts[kCoverageMapNeither], size_t(8 * size));
  EXPECT_EQ(counts[kCoverageMapReferenceOnly], 0u);  // every reference pixel is a footprint pixel here
  EXPECT_EQ(gray, r->coverage.both_px - 25u - 9u);
  // Without a map asked the figures are the same.
  Expected<CoveredComparison> plain = CompareCovered(reference, test, {}, nullptr, &reference_depth, &test_depth);
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ(plain->coverage.hole_px, r->coverage.hole_px);
  EXPECT_EQ(plain->metrics.psnr_db, r->metrics.psnr_db);
}

}  // namespace
}  // namespace pb
