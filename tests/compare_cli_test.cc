// End-to-end tests of `pointbake compare`: the real binary on PNG files.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

}  // namespace
}  // namespace pbtest
