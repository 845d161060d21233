// End-to-end tests of `pointbake compare`: the real binary on PNG files.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <string>

#include "stages/geometry/core/image.h"
#include "tests/cli_test_util.h"

namespace pbtest {
namespace {

// The issue-7 reference pair R0, T1 (256x256) and two flat grays.
pb::Image Pattern(int size, bool perturbed) {
  pb::Image image = pb::Image::Make(size, size, 3, pb::Image::PixelType::kU8);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x)
      for (int c = 0; c < 3; ++c) {
        int v = ((x * x + 3 * x * y + 7 * y * y) / 16 + 2 * x + y + 40 * c) % 256;
        if (perturbed) v = std::clamp(v + ((17 * x + 31 * y + (x * y % 13) + 5 * c) % 21) - 10, 0, 255);
        image.at_u8(x, y, c) = uint8_t(v);
      }
  return image;
}

class CompareCli : public CliTest {
 protected:
  void SetUp() override {
    ASSERT_TRUE(pb::WritePng(P("r0.png"), Pattern(256, false)).ok());
    ASSERT_TRUE(pb::WritePng(P("t1.png"), Pattern(256, true)).ok());
    ASSERT_TRUE(pb::WritePng(P("small.png"), Pattern(64, false)).ok());
  }
};

TEST_F(CompareCli, JsonReproducesReferenceValues) {
  const RunResult r = pbtest::Run({"compare", P("r0.png"), P("t1.png"), "--json", "--map", P("flip.png")});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  const Json j = Json::parse(r.out, nullptr, false);
  ASSERT_FALSE(j.is_discarded()) << r.out;
  EXPECT_NEAR(j["psnr_db"].get<double>(), 32.5856, 1e-4);
  EXPECT_NEAR(j["ssim_luma"].get<double>(), 0.997619, 1e-5);
  EXPECT_NEAR(j["ssim_rgb"].get<double>(), 0.996503, 1e-5);
  EXPECT_NEAR(j["ms_ssim_luma"].get<double>(), 0.997406, 1e-5);
  EXPECT_NEAR(j["flip_mean"].get<double>(), 0.0620375, 0.0620375e-3);
  EXPECT_EQ(j["width"], 256);
  pb::Expected<pb::Image> map = pb::ReadPng(P("flip.png"));
  ASSERT_TRUE(map.ok()) << map.status().message();
  EXPECT_EQ(map->width, 256);
  EXPECT_EQ(map->channels, 3);
}

TEST_F(CompareCli, TableLabelsAndInfinity) {
  const RunResult r = pbtest::Run({"compare", P("r0.png"), P("r0.png")});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  for (const char* label : {"PSNR", "SSIM luma", "SSIM RGB mean", "MS-SSIM luma", "FLIP mean"})
    EXPECT_NE(r.out.find(label), std::string::npos) << label << "\n" << r.out;
  EXPECT_NE(r.out.find("inf dB"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1.000000"), std::string::npos) << r.out;
  const RunResult j = pbtest::Run({"compare", P("r0.png"), P("r0.png"), "--json"});
  ASSERT_EQ(j.exit_code, 0) << j.Describe();
  EXPECT_TRUE(Json::parse(j.out)["psnr_db"].is_null()) << j.out;
  EXPECT_EQ(Json::parse(j.out)["flip_mean"].get<double>(), 0.0);
}

TEST_F(CompareCli, ErrorsGoToStderrWithNonZeroExit) {
  RunResult r = pbtest::Run({"compare", P("r0.png"), P("missing.png")});
  EXPECT_EQ(r.exit_code, 2) << r.Describe();
  EXPECT_NE(r.err.find("missing.png"), std::string::npos) << r.Describe();
  EXPECT_TRUE(r.out.empty()) << r.Describe();

  r = pbtest::Run({"compare", P("r0.png"), P("small.png")});
  EXPECT_EQ(r.exit_code, 2) << r.Describe();
  EXPECT_NE(r.err.find("sizes differ"), std::string::npos) << r.Describe();

  r = pbtest::Run({"compare", P("r0.png")});
  EXPECT_EQ(r.exit_code, 2) << r.Describe();
  EXPECT_NE(r.err.find("Usage"), std::string::npos) << r.Describe();

  r = pbtest::Run({"compare", P("r0.png"), P("t1.png"), "--ppd", "-3"});
  EXPECT_EQ(r.exit_code, 2) << r.Describe();
  EXPECT_NE(r.err.find("--ppd"), std::string::npos) << r.Describe();
  r = pbtest::Run({"compare", P("r0.png"), P("t1.png"), "--bogus"});
  EXPECT_EQ(r.exit_code, 2) << r.Describe();
  EXPECT_NE(r.err.find("--bogus"), std::string::npos) << r.Describe();
  r = pbtest::Run({"compare", "--help"});
  EXPECT_EQ(r.exit_code, 0) << r.Describe();
  EXPECT_NE(r.out.find("--map"), std::string::npos) << r.Describe();
}

TEST_F(CompareCli, ListedInHelpAndPpdChangesFlip) {
  const RunResult help = pbtest::Run({"--help"});
  EXPECT_NE(help.out.find("compare"), std::string::npos) << help.Describe();
  const RunResult a = pbtest::Run({"compare", P("r0.png"), P("t1.png"), "--json"});
  const RunResult b = pbtest::Run({"compare", P("r0.png"), P("t1.png"), "--json", "--ppd", "20"});
  ASSERT_EQ(a.exit_code, 0);
  ASSERT_EQ(b.exit_code, 0);
  EXPECT_NE(Json::parse(a.out)["flip_mean"], Json::parse(b.out)["flip_mean"]);
  EXPECT_EQ(Json::parse(b.out)["flip_ppd"].get<double>(), 20.0);
}

// --covered: the frames' alpha says where there is surface. REF covers a
// square; TEST the same square but for a 3 x 3 hole inside it and its last
// column, and with a different color on its left half. Whole-frame metrics
// count the background; covered ones only the surface.
TEST_F(CompareCli, CoveredMeasuresTheSurfaceAndCountsHolesApart) {
  constexpr int kSize = 200, kLo = 40, kHi = 160;  // square [kLo, kHi)
  pb::Image ref = pb::Image::Make(kSize, kSize, 4, pb::Image::PixelType::kU8);
  pb::Image test = ref;
  pb::Image mask = pb::Image::Make(kSize, kSize, 1, pb::Image::PixelType::kU8);
  for (int y = kLo; y < kHi; ++y)
    for (int x = kLo; x < kHi; ++x) {
      for (int c = 0; c < 3; ++c) ref.at_u8(x, y, c) = test.at_u8(x, y, c) = uint8_t(60 + (x + 2 * y + 30 * c) % 120);
      if (x < 100) test.at_u8(x, y, 0) = uint8_t(test.at_u8(x, y, 0) + 20);
      ref.at_u8(x, y, 3) = test.at_u8(x, y, 3) = 255;
      if (x % 2 == 0) mask.at_u8(x, y, 0) = 255;  // every other column holds a sample
    }
  for (int y = 99; y < 102; ++y)
    for (int x = 119; x < 122; ++x) test.at_u8(x, y, 3) = 0;  // the hole
  for (int y = kLo; y < kHi; ++y) test.at_u8(kHi - 1, y, 3) = 0;  // the outline a pixel short
  ASSERT_TRUE(pb::WritePng(P("ref.png"), ref).ok());
  ASSERT_TRUE(pb::WritePng(P("test.png"), test).ok());
  ASSERT_TRUE(pb::WritePng(P("ref.samples.png"), mask).ok());

  RunResult r = pbtest::Run({"compare", P("ref.png"), P("test.png"), "--covered", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  Json j = Json::parse(r.out);
  const size_t square = size_t(kHi - kLo) * size_t(kHi - kLo);
  EXPECT_EQ(j["covered"]["reference_px"], square);
  EXPECT_EQ(j["covered"]["test_px"], square - 9 - size_t(kHi - kLo));
  EXPECT_EQ(j["covered"]["footprint"], "covered");
  EXPECT_EQ(j["covered"]["hole_px"], 9 + size_t(kHi - kLo));
  EXPECT_EQ(j["covered"]["enclosed_hole_px"], 9u);
  EXPECT_EQ(j["covered"]["silhouette_hole_px"], size_t(kHi - kLo));
  EXPECT_NEAR(j["covered"]["coverage_iou"].get<double>(), double(square - 9 - (kHi - kLo)) / double(square), 1e-12);
  const double covered_psnr = j["psnr_db"].get<double>();
  // Only the left half differs, by 20 in red: MSE 20^2 / 3 over it.
  EXPECT_GT(covered_psnr, 10 * std::log10(255.0 * 255.0 / (400.0 / 3)) - 0.01);
  EXPECT_LT(covered_psnr, 10 * std::log10(255.0 * 255.0 / (400.0 / 6)) + 0.01);
  // Whole frames: the same difference over the whole frame, and the
  // background pixels (equal: 0) in the mean.
  const RunResult whole = pbtest::Run({"compare", P("ref.png"), P("test.png"), "--json"});
  ASSERT_EQ(whole.exit_code, 0) << whole.Describe();
  EXPECT_FALSE(Json::parse(whole.out).contains("covered"));
  EXPECT_NE(Json::parse(whole.out)["psnr_db"].get<double>(), covered_psnr);

  // On the sample mask: every other column.
  r = pbtest::Run({"compare", P("ref.png"), P("test.png"), "--covered", "--json", "--samples", P("ref.samples.png")});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  j = Json::parse(r.out);
  EXPECT_EQ(j["covered"]["footprint"], "samples");
  EXPECT_EQ(j["covered"]["footprint_px"], square / 2);
  // The hole's columns 120 and the last column 159 (odd: no sample) -> 3.
  EXPECT_EQ(j["covered"]["hole_px"], 3u);

  // The coverage map: the hole enclosed (yellow), the short outline (red),
  // the model's gray inside, black outside.
  r = pbtest::Run({"compare", P("ref.png"), P("test.png"), "--covered", "--coverage-map", P("cov.png")});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  pb::Expected<pb::Image> map = pb::ReadPng(P("cov.png"));
  ASSERT_TRUE(map.ok()) << map.status().message();
  auto color = [&](int x, int y) {
    return std::array<int, 3>{map->at_u8(x, y, 0), map->at_u8(x, y, 1), map->at_u8(x, y, 2)};
  };
  EXPECT_EQ(color(120, 100), (std::array<int, 3>{255, 230, 0}));
  EXPECT_EQ(color(kHi - 1, 70), (std::array<int, 3>{255, 0, 0}));
  EXPECT_EQ(color(10, 10), (std::array<int, 3>{0, 0, 0}));
  const std::array<int, 3> model = color(60, 60);
  EXPECT_EQ(model[0], model[1]);
  EXPECT_GE(model[0], 96);

  // The table says the same.
  r = pbtest::Run({"compare", P("ref.png"), P("test.png"), "--covered"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  EXPECT_NE(r.out.find("holes              129 of 14400 covered px (0.8958 %): 9 enclosed, 120 at the outline, 0 open"),
            std::string::npos)
      << r.out;

  // Depth maps: TEST's surface in front on the top rows.
  pb::Image ref_depth = pb::Image::Make(kSize, kSize, 1, pb::Image::PixelType::kF32);
  pb::Image test_depth = ref_depth;
  for (int y = kLo; y < kHi; ++y)
    for (int x = kLo; x < kHi; ++x) {
      ref_depth.at_f32(x, y, 0) = 2.0f;
      test_depth.at_f32(x, y, 0) = y < kLo + 10 ? 1.5f : 2.02f;
    }
  ASSERT_TRUE(pb::WriteExr(P("ref.depth.exr"), ref_depth).ok());
  ASSERT_TRUE(pb::WriteExr(P("test.depth.exr"), test_depth).ok());
  r = pbtest::Run({"compare", P("ref.png"), P("test.png"), "--covered", "--json", "--depth", P("ref.depth.exr"),
                   P("test.depth.exr")});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  j = Json::parse(r.out);
  EXPECT_EQ(j["covered"]["nearer_px"], size_t(10 * (kHi - kLo - 1)));
  EXPECT_EQ(j["covered"]["farther_px"], 0u);

  // Options that need --covered; a missing mask; a mask of another size.
  r = pbtest::Run({"compare", P("ref.png"), P("test.png"), "--samples", P("ref.samples.png")});
  EXPECT_EQ(r.exit_code, 2) << r.Describe();
  EXPECT_NE(r.err.find("need --covered"), std::string::npos) << r.Describe();
  r = pbtest::Run({"compare", P("ref.png"), P("test.png"), "--coverage-map", P("cov2.png")});
  EXPECT_EQ(r.exit_code, 2) << r.Describe();
  EXPECT_FALSE(std::filesystem::exists(P("cov2.png")));
  r = pbtest::Run({"compare", P("ref.png"), P("test.png"), "--covered", "--samples", P("nope.png")});
  EXPECT_EQ(r.exit_code, 2) << r.Describe();
  EXPECT_NE(r.err.find("nope.png"), std::string::npos) << r.Describe();
  r = pbtest::Run({"compare", P("ref.png"), P("test.png"), "--covered", "--samples", P("small.png")});
  EXPECT_EQ(r.exit_code, 2) << r.Describe();
  EXPECT_TRUE(r.out.empty()) << r.Describe();
}

}  // namespace
}  // namespace pbtest
