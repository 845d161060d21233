#include "stages/geometry/core/image.h"
#include "stages/geometry/testing/test_data.h"
#include "base/testing/durable_write_check.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace pb {
namespace {

using ::testing::HasSubstr;

class ImageTest : public pb::testing::TempDirTest {};

TEST_F(ImageTest, Png8BitAllChannelCounts) {
  for (int channels = 1; channels <= 4; ++channels) {
    Image image = Image::Make(5, 3, channels, Image::PixelType::kU8);
    for (size_t i = 0; i < image.data.size(); ++i) image.data[i] = static_cast<uint8_t>(i * 37 + channels);
    const std::string path = Path("img" + std::to_string(channels) + ".png");
    ASSERT_TRUE(WritePng(path, image).ok());
    auto read = ReadPng(path);
    ASSERT_TRUE(read.ok()) << read.status().message();
    EXPECT_EQ(read->width, 5);
    EXPECT_EQ(read->height, 3);
    EXPECT_EQ(read->channels, channels);
    EXPECT_EQ(read->type, Image::PixelType::kU8);
    EXPECT_EQ(read->data, image.data);
  }
}

// A rendered-looking image: smooth shading plus texture-like detail.
TEST_F(ImageTest, PngEncodingsDecodeAlikeAndSmallIsSmaller) {
  Image image = Image::Make(256, 256, 3, Image::PixelType::kU8);
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x)
      for (int c = 0; c < 3; ++c)
        image.u8()[image.sample_index(x, y, c)] =
            static_cast<uint8_t>((x / 2 + y / 3 + 40 * c + ((x * 7 + y * 13) % 11) + (x * y) % 5) & 255);
  auto fast = EncodePng(image, PngEncoding::kFast);
  auto small = EncodePng(image, PngEncoding::kSmall);
  ASSERT_TRUE(fast.ok() && small.ok());
  EXPECT_LT(small->size(), fast->size());
  for (const auto& [name, bytes] : {std::pair{"fast.png", *fast}, std::pair{"small.png", *small}}) {
    std::ofstream(Path(name), std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    auto read = ReadPng(Path(name));
    ASSERT_TRUE(read.ok()) << read.status().message();
    EXPECT_EQ(read->data, image.data) << name;
  }
  // WritePng writes what EncodePng returns.
  ASSERT_TRUE(WritePng(Path("w.png"), image, PngEncoding::kSmall).ok());
  EXPECT_EQ(std::filesystem::file_size(Path("w.png")), small->size());
}

TEST_F(ImageTest, ReadImageSizeFromHeadersWhateverTheFileName) {
  const Image png = Image::Make(37, 21, 3, Image::PixelType::kU8);
  const Image exr = Image::Make(19, 44, 3, Image::PixelType::kF32);
  ASSERT_TRUE(WritePng(Path("a.png"), png).ok());
  ASSERT_TRUE(WriteExr(Path("b.exr"), exr).ok());
  // As in the cache: no extension.
  std::filesystem::rename(Path("a.png"), Path("a"));
  std::filesystem::rename(Path("b.exr"), Path("b"));
  auto png_size = ReadImageSize(Path("a"));
  ASSERT_TRUE(png_size.ok()) << png_size.status().message();
  EXPECT_EQ(png_size->width, 37);
  EXPECT_EQ(png_size->height, 21);
  EXPECT_EQ(png_size->png_bit_depth, 8);
  auto exr_size = ReadImageSize(Path("b"));
  ASSERT_TRUE(exr_size.ok()) << exr_size.status().message();
  EXPECT_EQ(exr_size->width, 19);
  EXPECT_EQ(exr_size->height, 44);
  EXPECT_EQ(exr_size->png_bit_depth, 0);
  ASSERT_TRUE(WritePng(Path("deep.png"), Image::Make(3, 2, 1, Image::PixelType::kU16)).ok());
  EXPECT_EQ(ReadImageSize(Path("deep.png"))->png_bit_depth, 16);

  std::ofstream(Path("text")) << "not an image at all";
  EXPECT_EQ(ReadImageSize(Path("text")).status().code(), Status::Code::kUnsupported);
  std::ofstream(Path("short"), std::ios::binary) << "\x89PNG\r\n\x1a\n";
  auto truncated = ReadImageSize(Path("short"));
  EXPECT_EQ(truncated.status().code(), Status::Code::kCorrupt);
  EXPECT_THAT(truncated.status().message(), HasSubstr(Path("short")));
  EXPECT_EQ(ReadImageSize(Path("missing")).status().code(), Status::Code::kNotFound);
}

TEST_F(ImageTest, Png16BitKeepsFullValues) {
  Image image = Image::Make(4, 2, 3, Image::PixelType::kU16);
  image.at_u16(0, 0, 0) = 0x1234;
  image.at_u16(3, 1, 2) = 65535;
  image.at_u16(2, 1, 1) = 258;  // 0x0102: catches byte-order mistakes
  ASSERT_TRUE(WriteImage(Path("deep.PNG"), image).ok());
  auto read = ReadImage(Path("deep.PNG"));
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->type, Image::PixelType::kU16);
  EXPECT_EQ(read->at_u16(0, 0, 0), 0x1234);
  EXPECT_EQ(read->at_u16(3, 1, 2), 65535);
  EXPECT_EQ(read->at_u16(2, 1, 1), 258);
  EXPECT_EQ(read->data, image.data);
}

TEST_F(ImageTest, ExrFloatRoundTrip) {
  for (int channels : {1, 3, 4}) {
    Image image = Image::Make(7, 5, channels, Image::PixelType::kF32);
    for (size_t i = 0; i < image.sample_count(); ++i) image.f32()[i] = -1.0f + 0.013f * i;
    image.at_f32(6, 4, channels - 1) = 1e20f;
    const std::string path = Path("n" + std::to_string(channels) + ".exr");
    ASSERT_TRUE(WriteImage(path, image).ok());
    auto read = ReadImage(path);
    ASSERT_TRUE(read.ok()) << read.status().message();
    EXPECT_EQ(read->width, 7);
    EXPECT_EQ(read->height, 5);
    EXPECT_EQ(read->channels, channels);
    EXPECT_EQ(read->type, Image::PixelType::kF32);
    EXPECT_EQ(read->data, image.data);
  }
}

// PNG and OpenEXR: a failed write keeps the earlier file.
TEST_F(ImageTest, FailedWritesKeepTheEarlierFile) {
  for (const auto& [name, type] : {std::pair{"map.png", Image::PixelType::kU8},
                                  std::pair{"map.png", Image::PixelType::kU16},
                                  std::pair{"map.exr", Image::PixelType::kF32}}) {
    SCOPED_TRACE(name);
    testing::TempDir dir;
    const Image older = Image::Make(4, 4, 3, type);
    Image newer = Image::Make(6, 5, 3, type);
    newer.data[1] = 7;
    ASSERT_TRUE(WriteImage(dir.Path(name), older).ok());
    EXPECT_EQ(testing::ExpectFailedWritesKeepEarlierFiles(dir.path(), [&](Env* env) {
                return WriteImage(dir.Path(name), newer, env);
              }),
              1);
  }
}

TEST_F(ImageTest, CorruptAndWrongFilesAreClearErrors) {
  std::ofstream(Path("text.png")) << "this is not a png";
  auto not_png = ReadPng(Path("text.png"));
  ASSERT_FALSE(not_png.ok());
  EXPECT_THAT(not_png.status().message(), HasSubstr("text.png: not a PNG file"));

  // A real PNG cut in half: libpng's error comes back as a Status.
  Image image = Image::Make(64, 64, 3, Image::PixelType::kU8);
  for (size_t i = 0; i < image.data.size(); ++i) image.data[i] = static_cast<uint8_t>(i * 7919 % 251);
  ASSERT_TRUE(WritePng(Path("full.png"), image).ok());
  const auto size = std::filesystem::file_size(Path("full.png"));
  std::filesystem::copy_file(Path("full.png"), Path("cut.png"));
  std::filesystem::resize_file(Path("cut.png"), size / 2);
  auto cut = ReadPng(Path("cut.png"));
  ASSERT_FALSE(cut.ok());
  EXPECT_EQ(cut.status().code(), Status::Code::kCorrupt);
  EXPECT_THAT(cut.status().message(), HasSubstr("cut.png: corrupt PNG"));

  std::ofstream(Path("text.exr")) << "this is not an exr";
  auto not_exr = ReadExr(Path("text.exr"));
  ASSERT_FALSE(not_exr.ok());
  EXPECT_THAT(not_exr.status().message(), HasSubstr("text.exr: corrupt or unreadable EXR"));

  EXPECT_EQ(ReadImage(Path("x.tiff")).status().code(), Status::Code::kUnsupported);
  EXPECT_EQ(ReadPng(Path("missing.png")).status().code(), Status::Code::kNotFound);
  EXPECT_EQ(WritePng(Path("f.png"), Image::Make(2, 2, 1, Image::PixelType::kF32)).code(),
            Status::Code::kInvalid);
  EXPECT_EQ(WriteExr(Path("f.exr"), Image::Make(2, 2, 1, Image::PixelType::kU8)).code(),
            Status::Code::kInvalid);
}

}  // namespace
}  // namespace pb
