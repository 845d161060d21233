// The frames artifact (stages/geometry/io/frames.h) and the metrics.image stage
// through the fake context.
#include <gtest/gtest.h>

#include <array>
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

TEST_F(FramesTest, DepthMapsRoundTripAndBadDepthFilesAreNamed) {
  FrameSet set = MakeSet(24, 16, {{"door", 0}});
  set.frames[0].entry.depth_file = "door.depth.exr";
  set.frames[0].depth = Image::Make(24, 16, 1, Image::PixelType::kF32);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 24; ++x) set.frames[0].depth.at_f32(x, y, 0) = 1.0f + 0.25f * x;
  ASSERT_TRUE(WriteFrames(dir_.string(), set).ok());
  Expected<FrameSet> read = ReadFrames(Path("frames.json"));
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->frames[0].entry.depth_file, "door.depth.exr");
  EXPECT_EQ(read->frames[0].depth.data, set.frames[0].depth.data);
  // A depth file named like the image, or not .exr, or missing its map.
  FrameSet bad = set;
  bad.frames[0].entry.depth_file = "door.png";
  EXPECT_FALSE(WriteFrames(Path("bad1"), bad).ok());
  bad.frames[0].entry.depth_file = "door.depth.png";
  Status named = Validate(FramesIndex{24, 16, {bad.frames[0].entry}});
  EXPECT_NE(named.message().find(".exr"), std::string::npos) << named.message();
  bad.frames[0].entry.depth_file = "d.exr";
  bad.frames[0].depth = Image();
  std::filesystem::create_directories(Path("bad3"));
  EXPECT_FALSE(WriteFrames(Path("bad3"), bad).ok());
  // frames.json naming a depth file that is not there.
  std::filesystem::remove(Path("door.depth.exr"));
  Expected<FrameSet> missing = ReadFrames(Path("frames.json"));
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("door.depth.exr"), std::string::npos) << missing.status().message();
}

TEST_F(FramesTest, SampleMasksRoundTripAndBadSampleFilesAreNamed) {
  FrameSet set = MakeSet(24, 16, {{"door", 0}});
  set.frames[0].entry.samples_file = "door.samples.png";
  set.frames[0].samples = Image::Make(24, 16, 1, Image::PixelType::kU8);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 24; ++x) set.frames[0].samples.at_u8(x, y, 0) = (x + y) % 3 ? 0 : 255;
  ASSERT_TRUE(WriteFrames(dir_.string(), set).ok());
  Expected<FrameSet> read = ReadFrames(Path("frames.json"));
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->frames[0].entry.samples_file, "door.samples.png");
  EXPECT_EQ(read->frames[0].samples.data, set.frames[0].samples.data);
  // Named like the image, not .png, or without its mask.
  FrameSet bad = set;
  bad.frames[0].entry.samples_file = "door.png";
  EXPECT_FALSE(WriteFrames(Path("bad1"), bad).ok());
  bad.frames[0].entry.samples_file = "door.samples.exr";
  Status named = Validate(FramesIndex{24, 16, {bad.frames[0].entry}});
  EXPECT_NE(named.message().find("samples file"), std::string::npos) << named.message();
  bad.frames[0].entry.samples_file = "m.png";
  bad.frames[0].samples = Image();
  std::filesystem::create_directories(Path("bad3"));
  EXPECT_FALSE(WriteFrames(Path("bad3"), bad).ok());
  std::filesystem::remove(Path("door.samples.png"));
  Expected<FrameSet> missing = ReadFrames(Path("frames.json"));
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("door.samples.png"), std::string::npos) << missing.status().message();
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
    for (const Frame& f : set.frames) {
      files[f.entry.file] = (d / f.entry.file).string();
      if (!f.entry.depth_file.empty()) files[f.entry.depth_file] = (d / f.entry.depth_file).string();
    }
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
  const nlohmann::json schema = CheckedSchema(*type, true);
  EXPECT_EQ(schema["properties"]["ppd"]["default"].get<double>(), FlipDefaultPpd());
  ASSERT_EQ(type->outputs.size(), 4u);
  EXPECT_EQ(type->outputs[1].type, "frames");
  EXPECT_EQ(type->outputs[2].name, "flip_covered");
  EXPECT_EQ(type->outputs[3].name, "coverage");
  EXPECT_EQ(type->outputs[3].type, "frames");
  EXPECT_EQ(type->version, 6);
}

TEST_F(ImageStageTest, CoveredColumnsAndHolesBesideTheWholeFrame) {
  // RGBA frames: the reference covered but for a 10-pixel border, the test
  // the same with a 6 x 4 hole in the middle and 5 on its brightness.
  FrameSet reference = MakeSet(64, 64, {{"v", 0}}), test = MakeSet(64, 64, {{"v", 5}});
  for (FrameSet* set : {&reference, &test}) {
    Image rgba = Image::Make(64, 64, 4, Image::PixelType::kU8);
    const Image& rgb = set->frames[0].image;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        bool covered = x >= 10 && x < 54 && y >= 10 && y < 54;
        if (set == &test && x >= 30 && x < 36 && y >= 30 && y < 34) covered = false;
        for (int c = 0; c < 3; ++c) rgba.at_u8(x, y, c) = covered ? rgb.at_u8(x, y, c) : 0;
        rgba.at_u8(x, y, 3) = covered ? 255 : 0;
      }
    set->frames[0].image = std::move(rgba);
  }
  FakeContext ctx(dir_, nlohmann::json::object());
  AddFrames(ctx, "frames", "test", test);
  AddFrames(ctx, "reference", "ref", reference);
  ASSERT_TRUE(Run("metrics.image", ctx).ok());
  Expected<Table> table = ReadTable(ctx.outputs_.at("table"));
  ASSERT_TRUE(table.ok()) << table.status().message();
  Expected<CoveredComparison> c = CompareCovered(reference.frames[0].image, test.frames[0].image);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(TableNumber(table->get(0, "hole_px")), 24);
  EXPECT_EQ(TableNumber(table->get(0, "enclosed_hole_px")), 24);
  EXPECT_DOUBLE_EQ(TableNumber(table->get(0, "hole_fraction")), 24.0 / (44 * 44));
  EXPECT_DOUBLE_EQ(TableNumber(table->get(0, "coverage_iou")), (44.0 * 44 - 24) / (44 * 44));
  EXPECT_DOUBLE_EQ(TableNumber(table->get(0, "covered_psnr_db")), c->metrics.psnr_db);
  EXPECT_DOUBLE_EQ(TableNumber(table->get(0, "covered_flip_mean")), c->metrics.flip_mean);
  EXPECT_DOUBLE_EQ(TableNumber(table->get(0, "compared_px")), double(c->coverage.compared_px));
  // The whole frame counts the black border, the same in both, as agreement.
  EXPECT_LT(TableNumber(table->get(0, "covered_psnr_db")), TableNumber(table->get(0, "psnr_db")));
  EXPECT_EQ(ctx.counters_.at("hole_px"), 24);
  EXPECT_TRUE(std::holds_alternative<std::monostate>(table->get(0, "nearer_px")));  // no depth maps
  ASSERT_TRUE(ctx.files_.count("flip_covered/frames.json"));

  // The same with depth maps: 2 m everywhere in the reference, the test's
  // top-left 8 x 8 of the covered square 0.5 m nearer.
  for (FrameSet* set : {&reference, &test}) {
    set->frames[0].entry.depth_file = "v.depth.exr";
    set->frames[0].depth = Image::Make(64, 64, 1, Image::PixelType::kF32);
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x)
        set->frames[0].depth.at_f32(x, y, 0) = set == &test && x >= 10 && x < 18 && y >= 10 && y < 18 ? 1.5f : 2.0f;
  }
  std::filesystem::create_directories(dir_ / "depth");
  FakeContext with_depth(dir_ / "depth", nlohmann::json::object());
  AddFrames(with_depth, "frames", "test_d", test);
  AddFrames(with_depth, "reference", "ref_d", reference);
  const Status status = Run("metrics.image", with_depth);
  ASSERT_TRUE(status.ok()) << status.message();
  Expected<Table> depth_table = ReadTable(with_depth.outputs_.at("table"));
  ASSERT_TRUE(depth_table.ok());
  EXPECT_EQ(TableNumber(depth_table->get(0, "nearer_px")), 64);
  EXPECT_EQ(TableNumber(depth_table->get(0, "farther_px")), 0);
  EXPECT_DOUBLE_EQ(TableNumber(depth_table->get(0, "nearer_fraction")), 64.0 / (44 * 44));
  Expected<FrameSet> maps = ReadFrames(with_depth.files_.at("flip_covered/frames.json"));
  ASSERT_TRUE(maps.ok()) << maps.status().message();
  EXPECT_TRUE(maps->frames[0].entry.depth_file.empty());
  // The coverage map: the hole yellow (enclosed), the nearer block magenta.
  Expected<FrameSet> coverage = ReadFrames(with_depth.files_.at("coverage/frames.json"));
  ASSERT_TRUE(coverage.ok()) << coverage.status().message();
  ASSERT_EQ(coverage->frames.size(), 1u);
  const Image& map = coverage->frames[0].image;
  ASSERT_EQ(map.width, 64);
  auto at = [&](int x, int y) { return std::array<uint8_t, 3>{map.at_u8(x, y, 0), map.at_u8(x, y, 1), map.at_u8(x, y, 2)}; };
  EXPECT_EQ(at(32, 31), kCoverageMapHoleEnclosed);
  EXPECT_EQ(at(12, 12), kCoverageMapNearer);
  EXPECT_EQ(at(2, 2), kCoverageMapNeither);
  EXPECT_EQ(with_depth.meta_.at("coverage")["kind"], "coverage_maps");
}

TEST_F(ImageStageTest, TheWholeFrameDoesNotDependOnTheBackgroundTheFramesWereDrawnOn) {
  // The frames of CoveredColumnsAndHolesBesideTheWholeFrame (a covered square
  // with a border, the test's with a hole), their uncovered pixels drawn on
  // `background`: a workflow's frames set to magenta to show holes, compared
  // with a reference drawn on black, measure as both drawn on black.
  auto drawn = [](int brightness, bool hole, std::array<uint8_t, 3> background) {
    FrameSet set = MakeSet(64, 64, {{"v", brightness}});
    Image rgba = Image::Make(64, 64, 4, Image::PixelType::kU8);
    const Image& rgb = set.frames[0].image;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        bool covered = x >= 10 && x < 54 && y >= 10 && y < 54;
        if (hole && x >= 30 && x < 36 && y >= 30 && y < 34) covered = false;
        for (int c = 0; c < 3; ++c) rgba.at_u8(x, y, c) = covered ? rgb.at_u8(x, y, c) : background[size_t(c)];
        rgba.at_u8(x, y, 3) = covered ? 255 : 0;
      }
    set.frames[0].image = std::move(rgba);
    return set;
  };
  const std::array<uint8_t, 3> black{0, 0, 0}, magenta{255, 0, 255};
  struct Case {
    const char* name;
    std::array<uint8_t, 3> test, reference;
    bool warns;
  };
  const Case cases[] = {{"black", black, black, false},
                        {"test_magenta", magenta, black, true},
                        {"both_magenta", magenta, magenta, false},
                        {"reference_magenta", black, magenta, true}};
  std::vector<Table> tables;
  for (const Case& c : cases) {
    std::filesystem::create_directories(dir_ / c.name);
    FakeContext ctx(dir_ / c.name, nlohmann::json::object());
    AddFrames(ctx, "frames", std::string(c.name) + "_test", drawn(5, true, c.test));
    AddFrames(ctx, "reference", std::string(c.name) + "_ref", drawn(0, false, c.reference));
    const Status st = Run("metrics.image", ctx);
    ASSERT_TRUE(st.ok()) << st.message();
    if (c.warns) {
      ASSERT_EQ(ctx.warnings_.size(), 1u) << c.name;
      const std::string said = "'frames' are drawn on background " +
                               std::string(c.test == magenta ? "255,0,255" : "0,0,0") + " and 'reference' on " +
                               (c.reference == magenta ? "255,0,255" : "0,0,0");
      EXPECT_NE(ctx.warnings_[0].find(said), std::string::npos) << ctx.warnings_[0];
    } else {
      EXPECT_TRUE(ctx.warnings_.empty()) << c.name << ": " << ctx.warnings_[0];
    }
    Expected<Table> table = ReadTable(ctx.outputs_.at("table"));
    ASSERT_TRUE(table.ok()) << table.status().message();
    tables.push_back(std::move(*table));
  }
  // On black, the 24 hole pixels are errors of the whole frame.
  EXPECT_LT(TableNumber(tables[0].get(0, "psnr_db")), 60);
  for (size_t i = 1; i < tables.size(); ++i)
    for (const char* column : {"psnr_db", "ssim_luma", "ssim_rgb", "flip_mean", "covered_psnr_db",
                               "covered_flip_mean", "hole_px", "coverage_iou"})
      EXPECT_DOUBLE_EQ(TableNumber(tables[i].get(0, column)), TableNumber(tables[0].get(0, column)))
          << cases[i].name << " " << column;
}

}  // namespace
}  // namespace pb
