// The frames artifact (stages/geometry/io/frames.h) and the metrics.image stage
// through the fake context.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "stages/geometry/io/frames.h"
#include "stages/geometry/metrics/image_metrics.h"
#include "stages/geometry/core/table.h"
#include "stages/builtin.h"
#include "stages/stage_test_util.h"

namespace pb {
namespace {

Image Pattern(int width, int height, int seed, int channels = 3) {
  Image image = Image::Make(width, height, channels, Image::PixelType::kU8);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < channels; ++c)
        image.at_u8(x, y, c) =
            c == 3 ? 255 : uint8_t(((x * x + 3 * x * y + 7 * y * y) / 16 + 2 * x + y + 40 * c + seed) % 256);
  return image;
}

FrameSet MakeSet(int width, int height, const std::vector<std::pair<std::string, int>>& frames) {
  FrameSet set;
  set.width = width;
  set.height = height;
  for (const auto& [name, seed] : frames)
    set.frames.push_back(Frame{FrameEntry{name, name + ".png", std::nullopt}, Pattern(width, height, seed)});
  return set;
}

// ---------------------------------------------------------------------------
// frames.h

class FramesTest : public testing::TempDirTest {};

TEST_F(FramesTest, RoundTripWithViewpoint) {
  FrameSet set = MakeSet(24, 16, {{"door", 0}, {"corner", 5}});
  set.frames[0].entry.viewpoint = FrameViewpoint{{-1.2, -1.9, 1.6}, {1.5, 1.5, 1.2}, std::nullopt, 75.0};
  set.frames[1].image = Pattern(24, 16, 5, 4);  // RGBA
  ASSERT_TRUE(WriteFrames(dir_.string(), set).ok());
  Expected<FrameSet> read = ReadFrames(Path("frames.json"));
  ASSERT_TRUE(read.ok()) << read.status().message();
  ASSERT_EQ(read->frames.size(), 2u);
  EXPECT_EQ(read->width, 24);
  EXPECT_EQ(read->frames[1].entry.name, "corner");
  EXPECT_EQ(read->frames[1].image.channels, 4);
  EXPECT_EQ(read->frames[1].image.data, set.frames[1].image.data);
  ASSERT_TRUE(read->frames[0].entry.viewpoint.has_value());
  EXPECT_EQ(read->frames[0].entry.viewpoint->eye[1], -1.9);
  EXPECT_EQ(read->frames[0].entry.viewpoint->fov_deg, 75.0);
  EXPECT_FALSE(read->frames[0].entry.viewpoint->up.has_value());
  EXPECT_FALSE(read->frames[1].entry.viewpoint.has_value());
  EXPECT_NE(read->find("door"), nullptr);
  EXPECT_EQ(read->find("nope"), nullptr);
}

TEST_F(FramesTest, ClearErrors) {
  ASSERT_TRUE(WriteFrames(dir_.string(), MakeSet(24, 16, {{"a", 0}, {"b", 1}})).ok());
  // Missing image.
  std::filesystem::remove(Path("b.png"));
  Expected<FrameSet> read = ReadFrames(Path("frames.json"));
  ASSERT_FALSE(read.ok());
  EXPECT_EQ(read.status().code(), Status::Code::kNotFound);
  EXPECT_NE(read.status().message().find("'b'"), std::string::npos) << read.status().message();
  EXPECT_NE(read.status().message().find("b.png"), std::string::npos);
  // Wrong size.
  ASSERT_TRUE(WritePng(Path("b.png"), Pattern(24, 15, 0)).ok());
  read = ReadFrames(Path("frames.json"));
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.status().message().find("24x15"), std::string::npos) << read.status().message();
  // Bad JSON, wrong signature, newer version, bad entries.
  const std::string src = "x/frames.json";
  EXPECT_EQ(FramesIndexFromJson("{", src).status().code(), Status::Code::kCorrupt);
  EXPECT_EQ(FramesIndexFromJson(R"({"format":"other","version":1})", src).status().code(),
            Status::Code::kCorrupt);
  EXPECT_EQ(FramesIndexFromJson(R"({"format":"pointbake-frames","version":2})", src).status().code(),
            Status::Code::kUnsupported);
  const char* bad[] = {
      R"({"format":"pointbake-frames","version":1,"width":0,"height":4,"frames":[]})",
      R"({"format":"pointbake-frames","version":1,"width":4,"height":4,"frames":[{"name":"a","file":"../a.png"}]})",
      R"({"format":"pointbake-frames","version":1,"width":4,"height":4,"frames":[{"name":"a","file":"a.png"},{"name":"a","file":"b.png"}]})",
      R"({"format":"pointbake-frames","version":1,"width":4,"height":4,"frames":[{"name":"a","file":"a.png","eye":[1,2]}]})",
      R"({"format":"pointbake-frames","version":1,"width":4,"height":4,"frames":[{"name":"a","file":"a.png","eye":[1,2,3]}]})",
  };
  for (const char* text : bad) {
    Expected<FramesIndex> index = FramesIndexFromJson(text, src);
    EXPECT_EQ(index.status().code(), Status::Code::kInvalid) << text;
    EXPECT_NE(index.status().message().find(src), std::string::npos) << index.status().message();
  }
  // Missing index file.
  EXPECT_FALSE(ReadFrames(Path("none/frames.json")).ok());
}

// ---------------------------------------------------------------------------
// metrics.image

class ImageStageTest : public StageTest {
 protected:
  void SetUp() override {
    StageTest::SetUp();
    RegisterBuiltinStages(registry_);
  }
  // Writes `set` into dir_/name and connects it to `port`.
  void AddFrames(FakeContext& ctx, const std::string& port, const std::string& name, const FrameSet& set) {
    const std::filesystem::path d = dir_ / name;
    std::filesystem::create_directories(d);
    ASSERT_TRUE(WriteFrames(d.string(), set).ok());
    std::map<std::string, std::string> files = {{"frames.json", (d / "frames.json").string()}};
    for (const Frame& f : set.frames) files[f.entry.file] = (d / f.entry.file).string();
    ctx.AddInput(port, "frames", files, {{"renderer", "test"}});
  }
};

TEST_F(ImageStageTest, TableMatchesCompareImagesPerFrame) {
  const FrameSet test = MakeSet(200, 180, {{"a", 3}, {"b", 60}});
  const FrameSet reference = MakeSet(200, 180, {{"b", 0}, {"a", 0}});  // other order
  FakeContext ctx(dir_, {{"ppd", 30.0}}, 2);
  AddFrames(ctx, "frames", "test", test);
  AddFrames(ctx, "reference", "ref", reference);
  const Status st = Run("metrics.image", ctx);
  ASSERT_TRUE(st.ok()) << st.message();
  Expected<Table> table = ReadTable(ctx.outputs_.at("table"));
  ASSERT_TRUE(table.ok()) << table.status().message();
  ASSERT_EQ(table->rows.size(), 3u);
  double sum_flip = 0;
  for (size_t i = 0; i < 2; ++i) {
    const Frame& f = test.frames[i];
    EXPECT_EQ(std::get<std::string>(table->get(i, "frame")), f.entry.name);
    ImageMetricsOptions options;
    options.flip_ppd = 30.0;
    Expected<ImageMetrics> m = CompareImages(reference.find(f.entry.name)->image, f.image, options);
    ASSERT_TRUE(m.ok());
    EXPECT_DOUBLE_EQ(TableNumber(table->get(i, "psnr_db")), m->psnr_db);
    EXPECT_DOUBLE_EQ(TableNumber(table->get(i, "ssim_luma")), m->ssim_luma);
    EXPECT_DOUBLE_EQ(TableNumber(table->get(i, "ssim_rgb")), m->ssim_rgb);
    EXPECT_DOUBLE_EQ(TableNumber(table->get(i, "ms_ssim_luma")), m->ms_ssim_luma);
    EXPECT_DOUBLE_EQ(TableNumber(table->get(i, "flip_mean")), m->flip_mean);
    sum_flip += m->flip_mean;
  }
  EXPECT_EQ(std::get<std::string>(table->get(2, "frame")), "mean");
  EXPECT_DOUBLE_EQ(TableNumber(table->get(2, "flip_mean")), sum_flip / 2);
  EXPECT_DOUBLE_EQ(ctx.counters_.at("flip_mean"), sum_flip / 2);
  EXPECT_EQ(ctx.counters_.at("frames"), 2);
  EXPECT_TRUE(ctx.phases_.count("io") && ctx.phases_.count("compute"));
  EXPECT_EQ(ctx.last_progress_, 1.0);
  // The FLIP maps form a frames artifact of the same names.
  ASSERT_TRUE(ctx.files_.count("flip/frames.json"));
  Expected<FrameSet> maps = ReadFrames(ctx.files_.at("flip/frames.json"));
  ASSERT_TRUE(maps.ok()) << maps.status().message();
  ASSERT_EQ(maps->frames.size(), 2u);
  EXPECT_EQ(maps->frames[1].entry.name, "b");
  EXPECT_EQ(maps->frames[1].image.width, 200);
  EXPECT_EQ(ctx.meta_.at("flip").value("renderer", ""), "test");
  EXPECT_EQ(ctx.meta_.at("flip").value("kind", ""), "flip_error_maps");
}

TEST_F(ImageStageTest, IdenticalFramesGiveNullPsnrAndNoPsnrCounter) {
  const FrameSet set = MakeSet(32, 32, {{"v", 1}});
  FakeContext ctx(dir_, nlohmann::json::object());
  AddFrames(ctx, "frames", "test", set);
  AddFrames(ctx, "reference", "ref", set);
  ASSERT_TRUE(Run("metrics.image", ctx).ok());
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(ctx.outputs_.at("table")));
  EXPECT_TRUE(j["rows"][0][1].is_null()) << j.dump();  // PSNR: infinity
  EXPECT_TRUE(j["rows"][0][4].is_null()) << j.dump();  // MS-SSIM: too small
  EXPECT_EQ(j["rows"][0][5], 0.0);                     // FLIP
  EXPECT_EQ(ctx.counters_.count("psnr_db"), 0u);
  EXPECT_EQ(ctx.counters_.at("flip_mean"), 0.0);
}

TEST_F(ImageStageTest, MissingFrameIsNamed) {
  FakeContext ctx(dir_, nlohmann::json::object());
  AddFrames(ctx, "frames", "test", MakeSet(32, 32, {{"door", 1}, {"window", 2}}));
  AddFrames(ctx, "reference", "ref", MakeSet(32, 32, {{"door", 1}}));
  const Status st = Run("metrics.image", ctx);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("'window'"), std::string::npos) << st.message();

  FakeContext ctx2(dir_, nlohmann::json::object());
  AddFrames(ctx2, "frames", "test2", MakeSet(32, 32, {{"door", 1}}));
  AddFrames(ctx2, "reference", "ref2", MakeSet(32, 32, {{"door", 1}, {"corner", 2}}));
  const Status st2 = Run("metrics.image", ctx2);
  ASSERT_FALSE(st2.ok());
  EXPECT_NE(st2.message().find("'corner'"), std::string::npos) << st2.message();

  FakeContext ctx3(dir_, nlohmann::json::object());
  AddFrames(ctx3, "frames", "test3", MakeSet(32, 32, {{"door", 1}}));
  AddFrames(ctx3, "reference", "ref3", MakeSet(32, 30, {{"door", 1}}));
  const Status st3 = Run("metrics.image", ctx3);
  ASSERT_FALSE(st3.ok());
  EXPECT_NE(st3.message().find("32x30"), std::string::npos) << st3.message();
}

TEST_F(ImageStageTest, SchemaDefaultPpdIsFlipDefault) {
  const StageType* type = registry_.Find("metrics.image");
  ASSERT_NE(type, nullptr);
  const nlohmann::json schema = nlohmann::json::parse(type->params_schema);
  EXPECT_EQ(schema["properties"]["ppd"]["default"].get<double>(), FlipDefaultPpd());
  ASSERT_EQ(type->outputs.size(), 2u);
  EXPECT_EQ(type->outputs[1].type, "frames");
}

}  // namespace
}  // namespace pb
