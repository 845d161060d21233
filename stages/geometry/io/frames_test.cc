#include "stages/geometry/io/frames.h"

#include <gtest/gtest.h>

#include "base/testing/durable_write_check.h"
#include "base/testing/temp_dir.h"

namespace pb {
namespace {

FrameSet TwoFrames(uint8_t shade) {
  FrameSet set;
  set.width = 8;
  set.height = 6;
  for (const char* name : {"door", "window"}) {
    Frame frame;
    frame.entry.name = name;
    frame.entry.file = std::string(name) + ".png";
    frame.image = Image::Make(8, 6, 3, Image::PixelType::kU8);
    for (uint8_t& sample : frame.image.data) sample = shade;
    set.frames.push_back(std::move(frame));
  }
  return set;
}

TEST(FramesTest, RoundTrip) {
  testing::TempDir dir;
  const FrameSet written = TwoFrames(40);
  ASSERT_TRUE(WriteFrames(dir.path(), written).ok());
  auto read = ReadFrames(dir.Path(kFramesIndexFile));
  ASSERT_TRUE(read.ok()) << read.status().message();
  ASSERT_EQ(read->frames.size(), 2u);
  EXPECT_EQ(read->find("window")->image.data, written.frames[1].image.data);
}

// Each image, then the index: a failure at any of them keeps the earlier
// files and leaves no file that looks complete.
TEST(FramesTest, FailedWritesKeepTheEarlierFiles) {
  testing::TempDir dir;
  ASSERT_TRUE(WriteFrames(dir.path(), TwoFrames(40)).ok());
  const FrameSet newer = TwoFrames(200);
  EXPECT_EQ(testing::ExpectFailedWritesKeepEarlierFiles(
                dir.path(), [&](Env* env) { return WriteFrames(dir.path(), newer, env); }),
            3);
}

}  // namespace
}  // namespace pb
