// Image: the `image` artifact in memory, and its files.
//
// Pixels are row-major, top row first, channels interleaved. Channel counts
// 1 (gray / Y), 2 (gray + alpha), 3 (RGB) or 4 (RGBA). Sample types:
//   kU8  one byte per sample (sRGB color, 0..255)
//   kU16 native-endian uint16 per sample (0..65535)
//   kF32 native float per sample (linear values, normals in [-1,1], depths)
// `data` holds width * height * channels * bytes_per_sample() bytes.
//
// Files: PNG (libpng) for kU8/kU16, all four channel counts; OpenEXR for kF32
// with FLOAT channels named Y / Y,A / R,G,B / R,G,B,A. ReadImage/WriteImage
// pick the format from the extension (".png", ".exr").
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "base/env.h"
#include "base/status.h"

namespace pb {

struct Image {
  enum class PixelType { kU8, kU16, kF32 };

  int width = 0;
  int height = 0;
  int channels = 0;
  PixelType type = PixelType::kU8;
  std::vector<uint8_t> data;

  // A zero-filled image.
  static Image Make(int width, int height, int channels, PixelType type);

  size_t bytes_per_sample() const { return type == PixelType::kU8 ? 1 : type == PixelType::kU16 ? 2 : 4; }
  size_t sample_count() const { return size_t(width) * size_t(height) * size_t(channels); }
  size_t sample_index(int x, int y, int channel) const {
    assert(x >= 0 && x < width && y >= 0 && y < height && channel >= 0 && channel < channels);
    return (size_t(y) * size_t(width) + size_t(x)) * size_t(channels) + size_t(channel);
  }

  // Typed views of `data`; assert the pixel type.
  uint8_t* u8() { assert(type == PixelType::kU8); return data.data(); }
  const uint8_t* u8() const { assert(type == PixelType::kU8); return data.data(); }
  uint16_t* u16() { assert(type == PixelType::kU16); return reinterpret_cast<uint16_t*>(data.data()); }
  const uint16_t* u16() const { assert(type == PixelType::kU16); return reinterpret_cast<const uint16_t*>(data.data()); }
  float* f32() { assert(type == PixelType::kF32); return reinterpret_cast<float*>(data.data()); }
  const float* f32() const { assert(type == PixelType::kF32); return reinterpret_cast<const float*>(data.data()); }

  uint8_t& at_u8(int x, int y, int channel) { return u8()[sample_index(x, y, channel)]; }
  uint8_t at_u8(int x, int y, int channel) const { return u8()[sample_index(x, y, channel)]; }
  uint16_t& at_u16(int x, int y, int channel) { return u16()[sample_index(x, y, channel)]; }
  uint16_t at_u16(int x, int y, int channel) const { return u16()[sample_index(x, y, channel)]; }
  float& at_f32(int x, int y, int channel) { return f32()[sample_index(x, y, channel)]; }
  float at_f32(int x, int y, int channel) const { return f32()[sample_index(x, y, channel)]; }
};

// PNG: 1/2/4/8/16-bit gray, gray+alpha, RGB, RGBA and palette files are read
// (palette and low bit depths expand to 8-bit; transparency to alpha). 16-bit
// files give kU16, all others kU8. Writing takes kU8 or kU16.
Expected<Image> ReadPng(const std::string& path);
// kFast (default): the Sub filter on every row and zlib's run-length
// strategy, 5x faster than libpng's default on baked maps for files 4-5 %
// larger. kSmall: libpng's default (adaptive filter per row, deflate level
// 6), up to 2x smaller on photographic images such as rendered frames; for
// pictures that are kept (reports, docs). Both are lossless.
enum class PngEncoding { kFast, kSmall };
// Files are written durably (env->WriteFileAtomic): on failure `path` keeps
// what it held.
Status WritePng(const std::string& path, const Image& image,
                PngEncoding encoding = PngEncoding::kFast, Env* env = Env::Default());
// The bytes of the PNG file WritePng would write (e.g. to embed in a .glb).
// Status::Invalid for kF32 or a malformed image.
Expected<std::vector<uint8_t>> EncodePng(const Image& image,
                                         PngEncoding encoding = PngEncoding::kFast);

// OpenEXR: reads the data window of a scanline or tiled file (channels
// R,G,B[,A] or Y[,A], any stored pixel type) as kF32. Writing takes kF32,
// ZIP-compressed FLOAT channels.
Expected<Image> ReadExr(const std::string& path);
Status WriteExr(const std::string& path, const Image& image, Env* env = Env::Default());
// The bytes of the OpenEXR file WriteExr writes; `path` only names the image
// in errors.
Expected<std::string> EncodeExr(const Image& image, const std::string& path);

// Width and height of a PNG or OpenEXR file (its data window), and a PNG's
// bit depth, from its header, without decoding pixels; the format is told by the file's
// signature, not its name (cache files have no extension). Status::Unsupported
// for a file that is neither, Status::Corrupt for an unreadable header,
// Status::NotFound for a missing file.
struct ImageSize {
  int width = 0;
  int height = 0;
  int png_bit_depth = 0;  // as stored (IHDR): 1, 2, 4, 8 or 16; 0 for OpenEXR
};
Expected<ImageSize> ReadImageSize(const std::string& path);

// By extension (case-insensitive): ".png" or ".exr"; Status::Unsupported
// otherwise.
Expected<Image> ReadImage(const std::string& path);
Status WriteImage(const std::string& path, const Image& image, Env* env = Env::Default());

}  // namespace pb
