#include "stages/geometry/io/ktx2.h"

#include <gtest/gtest.h>

#include "stages/geometry/testing/ktx2_sample.h"

namespace pb {
namespace {

using testing::Ktx2Sample;

TEST(Ktx2Test, ReadsHeaderCodecAndTransfer) {
  const auto etc1s = Ktx2Sample(163, 2048, 1024, 12, true);
  auto info = ReadKtx2Info(etc1s, "color.ktx2");
  ASSERT_TRUE(info.ok()) << info.status().message();
  EXPECT_EQ(info->width, 2048);
  EXPECT_EQ(info->height, 1024);
  EXPECT_EQ(info->levels, 12);
  EXPECT_EQ(info->codec, Ktx2Codec::kEtc1s);
  EXPECT_TRUE(info->srgb);
  EXPECT_FALSE(info->has_alpha);
  EXPECT_EQ(info->supercompression, 1u);
  EXPECT_EQ(info->data_bytes, 12u * 16u);

  auto uastc = ReadKtx2Info(Ktx2Sample(166, 64, 64, 1, false), "n.ktx2");
  ASSERT_TRUE(uastc.ok());
  EXPECT_EQ(uastc->codec, Ktx2Codec::kUastc);
  EXPECT_FALSE(uastc->srgb);
  auto alpha = ReadKtx2Info(Ktx2Sample(163, 64, 64, 1, true, 2), "a.ktx2");
  ASSERT_TRUE(alpha.ok());
  EXPECT_TRUE(alpha->has_alpha);
}

TEST(Ktx2Test, GpuBytesAreBlocksOverTheStoredLevels) {
  Ktx2Info info;
  info.width = 2048;
  info.height = 2048;
  info.levels = 12;  // 2048 .. 1
  info.codec = Ktx2Codec::kEtc1s;
  // Blocks per level: 512², 256², ... 1, 1, 1 (levels 4x4, 2x2, 1x1 each one block).
  uint64_t blocks = 0;
  for (uint64_t side = 512; side >= 1; side /= 2) blocks += side * side;
  blocks += 2;
  EXPECT_EQ(Ktx2GpuBytes(info), 8 * blocks);
  info.codec = Ktx2Codec::kUastc;
  EXPECT_EQ(Ktx2GpuBytes(info), 16 * blocks);
  info.codec = Ktx2Codec::kEtc1s;
  info.has_alpha = true;
  EXPECT_EQ(Ktx2GpuBytes(info), 16 * blocks);
  // 2048² RGBA8 with mips is 4 * 4/3 * 2048² = 22.4 MB; ETC1S is 1/8 of it.
  info.has_alpha = false;
  info.levels = 1;
  info.width = 5;  // partial blocks round up: 2 x 1 blocks
  info.height = 3;
  EXPECT_EQ(Ktx2GpuBytes(info), 16u);
  info.codec = Ktx2Codec::kOther;
  EXPECT_EQ(Ktx2GpuBytes(info), 0u);
}

TEST(Ktx2Test, DamagedFilesAreCorruptWithTheirName) {
  auto bytes = Ktx2Sample(163, 16, 16, 5, true);
  EXPECT_FALSE(IsKtx2(std::vector<uint8_t>{1, 2, 3}));
  EXPECT_TRUE(IsKtx2(bytes));
  auto wrong_id = bytes;
  wrong_id[1] = 'X';
  EXPECT_EQ(ReadKtx2Info(wrong_id, "x.ktx2").status().code(), Status::Code::kCorrupt);
  auto truncated = ReadKtx2Info(std::span(bytes).first(100), "t.ktx2");
  ASSERT_FALSE(truncated.ok());
  EXPECT_NE(truncated.status().message().find("t.ktx2"), std::string::npos);
  auto past_end = bytes;
  past_end[80 + 8] = 0xFF;  // level 0 length
  past_end[80 + 9] = 0xFF;
  auto status = ReadKtx2Info(past_end, "p.ktx2").status();
  EXPECT_NE(status.message().find("level 0 ends past the file"), std::string::npos) << status.message();
  auto no_dfd = bytes;
  no_dfd[52] = 0;  // dfdByteLength 0
  EXPECT_EQ(ReadKtx2Info(no_dfd, "d.ktx2").status().code(), Status::Code::kCorrupt);
}

}  // namespace
}  // namespace pb
