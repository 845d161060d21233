#include "stages/geometry/core/text_parse.h"
#include "stages/geometry/core/image.h"

#include <png.h>
#include <zlib.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <exception>
#include <string_view>

namespace pb {

Image Image::Make(int width, int height, int channels, PixelType type) {
  assert(width >= 0 && height >= 0 && channels >= 1 && channels <= 4);
  Image image;
  image.width = width;
  image.height = height;
  image.channels = channels;
  image.type = type;
  image.data.assign(image.sample_count() * image.bytes_per_sample(), 0);
  return image;
}

namespace {

// ---------------------------------------------------------------------------
// PNG. libpng reports errors by longjmp. Every function below that calls
// setjmp holds only trivially destructible locals, and every C++ object
// (vectors, strings) is created outside them, so the jump never skips a
// destructor.

struct PngErrorState {
  char message[256] = "";
};

extern "C" void PngOnError(png_structp png, png_const_charp message) {
  auto* state = static_cast<PngErrorState*>(png_get_error_ptr(png));
  std::snprintf(state->message, sizeof state->message, "%s", message);
  png_longjmp(png, 1);
}

extern "C" void PngOnWarning(png_structp, png_const_charp) {}

struct PngInfo {
  png_uint_32 width = 0;
  png_uint_32 height = 0;
  int bit_depth = 0;       // per sample, after the transforms: 8 or 16
  int file_bit_depth = 0;  // as stored (IHDR): 1, 2, 4, 8 or 16
  int channels = 0;
};

// Reads the header and sets the transforms that give 8/16-bit samples in
// native byte order.
bool PngReadInfo(png_structp png, png_infop info, FILE* file, PngInfo* out) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_init_io(png, file);
  png_set_sig_bytes(png, 8);
  png_read_info(png, info);
  const int color_type = png_get_color_type(png, info);
  const int bit_depth = png_get_bit_depth(png, info);
  if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
  if (bit_depth == 16 && std::endian::native == std::endian::little) png_set_swap(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  out->width = png_get_image_width(png, info);
  out->height = png_get_image_height(png, info);
  out->bit_depth = png_get_bit_depth(png, info);
  out->file_bit_depth = bit_depth;
  out->channels = png_get_channels(png, info);
  return true;
}

bool PngReadRows(png_structp png, png_infop info, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_image(png, rows);
  png_read_end(png, info);
  return true;
}

// Encoder settings of both writers. kFast: the Sub filter on every row and
// zlib's run-length strategy. On baked 4096^2 maps this encodes 5x faster
// than libpng's default (adaptive choice among all five filters per row,
// deflate level 6: 2.05 + 3.29 CPU-s for a color + normal map, 0.60 + 0.48 s
// now) for files 4-5 % larger (docs/bake.md). kSmall keeps libpng's default.
// Lossless either way: the decoded pixels are the same.
void PngSetEncoding(png_structp png, PngEncoding encoding) {
  if (encoding == PngEncoding::kSmall) return;
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_set_compression_strategy(png, Z_RLE);
}

// In-memory PNG writing: libpng calls these instead of fwrite/fflush.
extern "C" void PngAppendToVector(png_structp png, png_bytep data, png_size_t length) {
  auto* out = static_cast<std::vector<uint8_t>*>(png_get_io_ptr(png));
  out->insert(out->end(), data, data + length);
}

extern "C" void PngFlushNothing(png_structp) {}

// Writes `image` through `png`, whose output (a FILE or a vector) the caller
// has set up. False on a libpng error (the message is in the error state).
bool PngWriteAll(png_structp png, png_infop info, const Image* image, png_bytepp rows,
                 PngEncoding encoding) {
  if (setjmp(png_jmpbuf(png))) return false;
  static const int kColorTypes[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA,
                                    PNG_COLOR_TYPE_RGB, PNG_COLOR_TYPE_RGB_ALPHA};
  png_set_IHDR(png, info, static_cast<png_uint_32>(image->width),
               static_cast<png_uint_32>(image->height),
               image->type == Image::PixelType::kU16 ? 16 : 8, kColorTypes[image->channels - 1],
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  PngSetEncoding(png, encoding);
  png_write_info(png, info);
  if (image->type == Image::PixelType::kU16 && std::endian::native == std::endian::little) {
    png_set_swap(png);
  }
  png_write_image(png, rows);
  png_write_end(png, info);
  return true;
}

class File {
 public:
  File(const std::string& path, const char* mode) : file_(std::fopen(path.c_str(), mode)) {}
  ~File() {
    if (file_) std::fclose(file_);
  }
  File(const File&) = delete;
  File& operator=(const File&) = delete;
  FILE* get() const { return file_; }

 private:
  FILE* file_;
};


// ---------------------------------------------------------------------------
// OpenEXR.

const char* const kExrChannelNames[4][4] = {
    {"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};

// The format registry: extension -> reader and writer.
struct ImageFormat {
  std::string_view extension;
  Expected<Image> (*read)(const std::string&);
  Status (*write)(const std::string&, const Image&, Env*);
};
Status WriteFastPng(const std::string& path, const Image& image, Env* env) {
  return WritePng(path, image, PngEncoding::kFast, env);
}
constexpr ImageFormat kImageFormats[] = {
    {".png", &ReadPng, &WriteFastPng},
    {".exr", &ReadExr, &WriteExr},
};

Expected<const ImageFormat*> FormatFor(const std::string& path) {
  const std::string extension = LowerExtension(path);
  for (const ImageFormat& format : kImageFormats) {
    if (format.extension == extension) return &format;
  }
  return Status::Unsupported(path + ": unsupported image extension '" + extension +
                             "' (supported: .png, .exr)");
}

}  // namespace

Expected<Image> ReadPng(const std::string& path) {
  File file(path, "rb");
  if (!file.get()) {
    if (errno == ENOENT) return Status::NotFound(path + ": no such file");
    return Status::Errno(path, "open");
  }
  png_byte signature[8] = {};
  if (std::fread(signature, 1, 8, file.get()) != 8 || png_sig_cmp(signature, 0, 8) != 0) {
    return Status::Corrupt(path + ": not a PNG file (bad signature)");
  }
  PngErrorState error;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &error, PngOnError, PngOnWarning);
  if (!png) return Status::Internal(path + ": png_create_read_struct failed");
  png_infop info = png_create_info_struct(png);
  struct Cleanup {
    png_structp* png;
    png_infop* info;
    ~Cleanup() { png_destroy_read_struct(png, info, nullptr); }
  } cleanup{&png, &info};
  if (!info) return Status::Internal(path + ": png_create_info_struct failed");

  PngInfo header;
  if (!PngReadInfo(png, info, file.get(), &header)) {
    return Status::Corrupt(path + ": corrupt PNG: " + error.message);
  }
  if (header.bit_depth != 8 && header.bit_depth != 16) {
    return Status::Unsupported(path + ": PNG bit depth " + std::to_string(header.bit_depth));
  }
  if (header.width > (1u << 20) || header.height > (1u << 20)) {
    return Status::Unsupported(path + ": PNG of " + std::to_string(header.width) + "x" +
                               std::to_string(header.height) + " pixels is too large");
  }
  Image image = Image::Make(static_cast<int>(header.width), static_cast<int>(header.height),
                            header.channels,
                            header.bit_depth == 16 ? Image::PixelType::kU16 : Image::PixelType::kU8);
  const size_t row_bytes = size_t(image.width) * size_t(image.channels) * image.bytes_per_sample();
  std::vector<png_bytep> rows(image.height);
  for (int y = 0; y < image.height; ++y) rows[y] = image.data.data() + y * row_bytes;
  if (!PngReadRows(png, info, rows.data())) {
    return Status::Corrupt(path + ": corrupt PNG: " + error.message);
  }
  return image;
}

namespace {

// The PNG bytes of `image`; errors start with `what` (a path, or "encoding PNG").
Expected<std::vector<uint8_t>> EncodePngFor(const Image& image, PngEncoding encoding,
                                            const std::string& what) {
  if (image.type == Image::PixelType::kF32) {
    return Status::Invalid(what + ": PNG holds 8/16-bit samples, not float (write float images as .exr)");
  }
  if (image.channels < 1 || image.channels > 4 || image.width <= 0 || image.height <= 0 ||
      image.data.size() != image.sample_count() * image.bytes_per_sample()) {
    return Status::Invalid(what + ": malformed image (" + std::to_string(image.width) + "x" +
                           std::to_string(image.height) + "x" + std::to_string(image.channels) +
                           ", " + std::to_string(image.data.size()) + " bytes)");
  }
  std::vector<uint8_t> bytes;
  PngErrorState error;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, PngOnError, PngOnWarning);
  if (!png) return Status::Internal(what + ": png_create_write_struct failed");
  png_infop info = png_create_info_struct(png);
  struct Cleanup {
    png_structp* png;
    png_infop* info;
    ~Cleanup() { png_destroy_write_struct(png, info); }
  } cleanup{&png, &info};
  if (!info) return Status::Internal(what + ": png_create_info_struct failed");
  const size_t row_bytes = size_t(image.width) * size_t(image.channels) * image.bytes_per_sample();
  std::vector<png_bytep> rows(image.height);
  // libpng takes non-const rows but does not modify them when writing.
  png_bytep base = const_cast<png_bytep>(image.data.data());
  for (int y = 0; y < image.height; ++y) rows[y] = base + y * row_bytes;
  png_set_write_fn(png, &bytes, PngAppendToVector, PngFlushNothing);
  if (!PngWriteAll(png, info, &image, rows.data(), encoding)) {
    return Status::Internal(what + ": encoding PNG: " + error.message);
  }
  return bytes;
}

}  // namespace

Status WritePng(const std::string& path, const Image& image, PngEncoding encoding, Env* env) {
  PB_ASSIGN_OR_RETURN(const std::vector<uint8_t> bytes, EncodePngFor(image, encoding, path));
  return env->WriteFileAtomic(
      path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

Expected<std::vector<uint8_t>> EncodePng(const Image& image, PngEncoding encoding) {
  return EncodePngFor(image, encoding, "encoding PNG");
}

Expected<ImageSize> ReadImageSize(const std::string& path) {
  unsigned char magic[8] = {};
  {
    File file(path, "rb");
    if (!file.get()) {
      if (errno == ENOENT) return Status::NotFound(path + ": no such file");
      return Status::Errno(path, "open");
    }
    const size_t got = std::fread(magic, 1, sizeof magic, file.get());
    if (got == sizeof magic && png_sig_cmp(magic, 0, 8) == 0) {
      PngErrorState error;
      png_structp png =
          png_create_read_struct(PNG_LIBPNG_VER_STRING, &error, PngOnError, PngOnWarning);
      if (!png) return Status::Internal(path + ": png_create_read_struct failed");
      png_infop info = png_create_info_struct(png);
      struct Cleanup {
        png_structp* png;
        png_infop* info;
        ~Cleanup() { png_destroy_read_struct(png, info, nullptr); }
      } cleanup{&png, &info};
      if (!info) return Status::Internal(path + ": png_create_info_struct failed");
      PngInfo header;
      if (!PngReadInfo(png, info, file.get(), &header))
        return Status::Corrupt(path + ": corrupt or truncated PNG: " + error.message);
      if (header.width > 0x7fffffffu || header.height > 0x7fffffffu)
        return Status::Corrupt(path + ": PNG header gives an invalid size");
      return ImageSize{static_cast<int>(header.width), static_cast<int>(header.height),
                       header.file_bit_depth};
    }
  }
  if (magic[0] != 0x76 || magic[1] != 0x2f || magic[2] != 0x31 || magic[3] != 0x01)
    return Status::Unsupported(path + ": neither PNG nor OpenEXR");
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i window = file.header().dataWindow();
    const int64_t width = int64_t(window.max.x) - window.min.x + 1;
    const int64_t height = int64_t(window.max.y) - window.min.y + 1;
    if (width <= 0 || height <= 0 || width > 0x7fffffff || height > 0x7fffffff)
      return Status::Corrupt(path + ": EXR data window gives an invalid size");
    return ImageSize{static_cast<int>(width), static_cast<int>(height)};
  } catch (const std::exception& e) {
    return Status::Corrupt(path + ": corrupt or unreadable EXR: " + e.what());
  }
}

Expected<Image> ReadExr(const std::string& path) {
  {
    File probe(path, "rb");
    if (!probe.get()) {
      if (errno == ENOENT) return Status::NotFound(path + ": no such file");
      return Status::Errno(path, "open");
    }
  }
  try {
    Imf::InputFile file(path.c_str());
    const Imf::Header& header = file.header();
    const Imf::ChannelList& channel_list = header.channels();
    const bool has_rgb = channel_list.findChannel("R") && channel_list.findChannel("G") &&
                         channel_list.findChannel("B");
    const bool has_y = channel_list.findChannel("Y") != nullptr;
    const bool has_a = channel_list.findChannel("A") != nullptr;
    int channels = 0;
    if (has_rgb) {
      channels = has_a ? 4 : 3;
    } else if (has_y) {
      channels = has_a ? 2 : 1;
    } else {
      std::string names;
      for (auto it = channel_list.begin(); it != channel_list.end(); ++it) {
        names += (names.empty() ? "" : ", ") + std::string(it.name());
      }
      return Status::Unsupported(path + ": EXR channels {" + names +
                                 "}; expected R,G,B[,A] or Y[,A]");
    }
    const Imath::Box2i window = header.dataWindow();
    const int64_t width = int64_t(window.max.x) - window.min.x + 1;
    const int64_t height = int64_t(window.max.y) - window.min.y + 1;
    if (width <= 0 || height <= 0 || width > (1 << 20) || height > (1 << 20)) {
      return Status::Corrupt(path + ": EXR data window of " + std::to_string(width) + "x" +
                             std::to_string(height) + " pixels");
    }
    Image image = Image::Make(static_cast<int>(width), static_cast<int>(height), channels,
                              Image::PixelType::kF32);
    Imf::FrameBuffer frame_buffer;
    const size_t x_stride = sizeof(float) * size_t(channels);
    const size_t y_stride = x_stride * size_t(width);
    for (int c = 0; c < channels; ++c) {
      frame_buffer.insert(kExrChannelNames[channels - 1][c],
                          Imf::Slice::Make(Imf::FLOAT, image.f32() + c, window, x_stride, y_stride));
    }
    file.setFrameBuffer(frame_buffer);
    file.readPixels(window.min.y, window.max.y);
    return image;
  } catch (const std::exception& e) {
    return Status::Corrupt(path + ": corrupt or unreadable EXR: " + e.what());
  }
}

namespace {

// OpenEXR writes through an OStream and seeks back to fill in the line offset
// table, so the file is built in memory and then written durably.
class MemoryOStream : public Imf::OStream {
 public:
  explicit MemoryOStream(const std::string& path) : Imf::OStream(path.c_str()) {}
  void write(const char c[], int n) override {
    const size_t end = position_ + static_cast<size_t>(n);
    if (end > bytes_.size()) bytes_.resize(end);
    std::memcpy(bytes_.data() + position_, c, static_cast<size_t>(n));
    position_ = end;
  }
  uint64_t tellp() override { return position_; }
  void seekp(uint64_t position) override { position_ = static_cast<size_t>(position); }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
  size_t position_ = 0;
};

}  // namespace

Expected<std::string> EncodeExr(const Image& image, const std::string& path) {
  if (image.type != Image::PixelType::kF32) {
    return Status::Invalid(path + ": EXR files hold float samples; write 8/16-bit images as .png");
  }
  if (image.channels < 1 || image.channels > 4 || image.width <= 0 || image.height <= 0 ||
      image.data.size() != image.sample_count() * image.bytes_per_sample()) {
    return Status::Invalid(path + ": malformed image (" + std::to_string(image.width) + "x" +
                           std::to_string(image.height) + "x" + std::to_string(image.channels) +
                           ", " + std::to_string(image.data.size()) + " bytes)");
  }
  try {
    Imf::Header header(image.width, image.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    const char* const* names = kExrChannelNames[image.channels - 1];
    for (int c = 0; c < image.channels; ++c) {
      header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
    }
    MemoryOStream stream(path);
    {
      // The line offset table is written when the file object is destroyed.
      Imf::OutputFile file(stream, header);
      Imf::FrameBuffer frame_buffer;
      const size_t x_stride = sizeof(float) * size_t(image.channels);
      const size_t y_stride = x_stride * size_t(image.width);
      // OpenEXR takes non-const slices but only reads them when writing.
      float* base = const_cast<float*>(image.f32());
      for (int c = 0; c < image.channels; ++c) {
        frame_buffer.insert(names[c], Imf::Slice::Make(Imf::FLOAT, base + c, header.dataWindow(),
                                                       x_stride, y_stride));
      }
      file.setFrameBuffer(frame_buffer);
      file.writePixels(image.height);
    }
    return std::string(stream.bytes());
  } catch (const std::exception& e) {
    return Status::Io(path + ": writing EXR: " + e.what());
  }
}

Status WriteExr(const std::string& path, const Image& image, Env* env) {
  PB_ASSIGN_OR_RETURN(const std::string bytes, EncodeExr(image, path));
  return env->WriteFileAtomic(path, bytes);
}

Expected<Image> ReadImage(const std::string& path) {
  PB_ASSIGN_OR_RETURN(const ImageFormat* format, FormatFor(path));
  return format->read(path);
}

Status WriteImage(const std::string& path, const Image& image, Env* env) {
  PB_ASSIGN_OR_RETURN(const ImageFormat* format, FormatFor(path));
  return format->write(path, image, env);
}

}  // namespace pb
