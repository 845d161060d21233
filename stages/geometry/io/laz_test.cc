#include "stages/geometry/io/laz.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "stages/geometry/io/las.h"
#include "stages/geometry/io/laz_test_encoder.h"
#include "stages/geometry/testing/test_data.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

template <typename T>
void Put(std::string* bytes, size_t offset, T value) {
  std::memcpy(bytes->data() + offset, &value, sizeof(T));
}

class LazTest : public pb::testing::TempDirTest {
 protected:
  // Every record of `path`, every field decoded.
  std::string DecodeAll(const std::string& path) {
    const std::string bytes = ReadFile(path);
    LazPointLayout layout;
    layout.point_offset = Get<uint32_t>(bytes, 96);
    layout.point_format = static_cast<uint8_t>(bytes[104]) & 0x3F;
    layout.record_bytes = Get<uint16_t>(bytes, 105);
    layout.point_count = Get<uint32_t>(bytes, 107);
    if (bytes[25] == 4) layout.point_count = Get<uint64_t>(bytes, 247);
    // The laszip VLR is the last VLR (CompressLas puts it there).
    const size_t vlr_bytes = Get<uint16_t>(bytes, layout.point_offset - 0) * 0;
    (void)vlr_bytes;
    size_t offset = Get<uint16_t>(bytes, 94);
    std::span<const uint8_t> vlr;
    uint64_t vlr_offset = 0;
    for (uint32_t i = 0; i < Get<uint32_t>(bytes, 100); ++i) {
      const uint16_t payload = Get<uint16_t>(bytes, offset + 20);
      if (bytes.compare(offset + 2, 14, "laszip encoded") == 0) {
        vlr = {reinterpret_cast<const uint8_t*>(bytes.data()) + offset + 54, payload};
        vlr_offset = offset + 54;
      }
      offset += 54 + payload;
    }
    BufferedInput in;
    EXPECT_TRUE(in.Open(path, "a LAZ file", nullptr).ok());
    LazOptions options;
    options.all_layers = true;
    options.max_batch_bytes = 100000;  // several batches
    auto reader = LazReader::Open(&in, path, layout, vlr, vlr_offset, options);
    if (!reader.ok()) return "error: " + reader.status().message();
    std::string records;
    for (;;) {
      std::span<const uint8_t> batch;
      const Status status = (*reader)->Next(&batch);
      if (!status.ok()) return "error: " + status.message();
      if (batch.empty()) break;
      records.append(reinterpret_cast<const char*>(batch.data()), batch.size());
    }
    return records;
  }

  static std::string ReadFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  template <typename T>
  static T Get(const std::string& bytes, size_t offset) {
    T value;
    std::memcpy(&value, bytes.data() + offset, sizeof(T));
    return value;
  }
  static std::string Records(const std::string& las) { return las.substr(Get<uint32_t>(las, 96)); }

  void ExpectRoundTrip(int format, size_t points, size_t extra_bytes,
                       const laz::LazWriteOptions& options) {
    SCOPED_TRACE("format " + std::to_string(format) + ", " + std::to_string(points) + " points, " +
                 std::to_string(extra_bytes) + " extra bytes");
    const std::string las = laz::SyntheticAirborneLas(
        format, points, extra_bytes, static_cast<uint32_t>(format + 10 * extra_bytes));
    const std::string laz_path =
        Write("p" + std::to_string(format) + ".laz", laz::CompressLas(las, options));
    const std::string decoded = DecodeAll(laz_path);
    ASSERT_EQ(decoded.size(), Records(las).size()) << decoded.substr(0, 300);
    const std::string expected = Records(las);
    const size_t record_bytes = Get<uint16_t>(las, 105);
    for (size_t i = 0; i < points; ++i) {
      ASSERT_EQ(
          decoded.compare(i * record_bytes, record_bytes, expected, i * record_bytes, record_bytes),
          0)
          << "first different record: " << i;
    }
    // The scan reader (selected layers) gives the points of the LAS file.
    const std::string las_path = Write("p" + std::to_string(format) + ".las", las);
    auto from_las = ReadLas(las_path, {});
    auto from_laz = ReadLas(laz_path, {});
    ASSERT_TRUE(from_las.ok()) << from_las.status().message();
    ASSERT_TRUE(from_laz.ok()) << from_laz.status().message();
    EXPECT_EQ(from_laz->points.positions, from_las->points.positions);
    EXPECT_EQ(from_laz->points.intensities, from_las->points.intensities);
    EXPECT_EQ(from_laz->points.colors, from_las->points.colors);
    EXPECT_EQ(from_laz->points.origin, from_las->points.origin);
  }
};

TEST_F(LazTest, PointwiseFormatsRoundTrip) {
  laz::LazWriteOptions options;
  options.chunk_size = 3000;
  for (int format = 0; format <= 3; ++format) ExpectRoundTrip(format, 10000, 0, options);
  ExpectRoundTrip(3, 7000, 5, options);
}

TEST_F(LazTest, LayeredFormatsRoundTrip) {
  laz::LazWriteOptions options;
  options.chunk_size = 3000;
  for (int format = 6; format <= 8; ++format) ExpectRoundTrip(format, 10000, 0, options);
  ExpectRoundTrip(7, 7000, 3, options);
}

TEST_F(LazTest, VariableChunksAndTableOffsetAtTheEnd) {
  laz::LazWriteOptions options;
  options.chunk_points = {1, 4000, 2, 999, 3000};
  options.table_offset_at_end = true;
  ExpectRoundTrip(7, 8002, 0, options);
  ExpectRoundTrip(1, 8002, 0, options);
}

TEST_F(LazTest, NotChunkedPointwise) {
  laz::LazWriteOptions options;
  options.not_chunked = true;
  ExpectRoundTrip(1, 6000, 0, options);
}

TEST_F(LazTest, CopcFileReads) {
  laz::LazWriteOptions options;
  options.copc = true;
  ExpectRoundTrip(7, 5500, 0, options);
}

}  // namespace
}  // namespace pb

namespace pb {
namespace {

// For the laz-perf oracle (ctest laz_oracle): pairs X.las / X.laz in
// $PB_LAZ_SAMPLE_DIR, the .laz compressed by our test encoder; the oracle
// decodes each .laz and compares with the .las. Without the variable the
// test writes into its temporary directory and only checks our decoder.
TEST_F(LazTest, OracleSamples) {
  const char* env = std::getenv("PB_LAZ_SAMPLE_DIR");
  const std::string dir = env ? env : Path("samples");
  std::filesystem::create_directories(dir);
  struct Sample {
    const char* name;
    int format;
    size_t points;
    size_t extra_bytes;
    laz::LazWriteOptions options;
    int scanner_channels = 1;
  };
  laz::LazWriteOptions small_chunks;
  small_chunks.chunk_size = 5000;
  laz::LazWriteOptions copc;
  copc.copc = true;
  laz::LazWriteOptions variable;
  variable.chunk_points = {1, 7000, 3, 4996};
  const Sample samples[] = {
      {"pointwise_f0", 0, 12000, 0, small_chunks},
      {"pointwise_f1", 1, 12000, 0, small_chunks},
      {"pointwise_f2_rgb", 2, 12000, 0, small_chunks},
      {"pointwise_f3_rgb", 3, 12000, 0, small_chunks},
      {"pointwise_f3_extra", 3, 12000, 4, small_chunks},
      {"layered_f6_channels", 6, 12000, 0, small_chunks, 4},
      {"layered_f7_rgb", 7, 12000, 0, small_chunks},
      {"layered_f8_rgbnir", 8, 12000, 0, small_chunks},
      {"layered_f7_extra", 7, 12000, 2, small_chunks},
      {"layered_f7_variable", 7, 12000, 0, variable},
      {"copc_f7", 7, 8200, 0, copc},
  };
  for (const Sample& sample : samples) {
    SCOPED_TRACE(sample.name);
    const std::string las = laz::SyntheticAirborneLas(
        sample.format, sample.points, sample.extra_bytes,
        static_cast<uint32_t>(sample.points + sample.format), sample.scanner_channels);
    const std::string stem = dir + "/" + sample.name;
    { std::ofstream(stem + ".las", std::ios::binary) << las; }
    { std::ofstream(stem + ".laz", std::ios::binary) << laz::CompressLas(las, sample.options); }
    EXPECT_EQ(DecodeAll(stem + ".laz"), Records(las));
  }
}

}  // namespace
}  // namespace pb

namespace pb {
namespace {

using ::testing::ContainsRegex;
using ::testing::StartsWith;

class LazErrorTest : public LazTest {
 protected:
  // A format 7 file of 3000 points in chunks of 1000.
  std::string Laz7() {
    laz::LazWriteOptions options;
    options.chunk_size = 1000;
    return laz::CompressLas(laz::SyntheticAirborneLas(7, 3000, 0, 5, 1), options);
  }
  std::string ErrorOf(const std::string& bytes, const std::string& name = "bad.laz") {
    auto read = ReadLas(Write(name, bytes), {});
    return read.ok() ? "" : read.status().message();
  }
  // Where chunk `i` starts: walks the chunks from the table offset's end.
  static size_t PointOffset(const std::string& laz) { return Get<uint32_t>(laz, 96); }
};

TEST_F(LazErrorTest, ParallelAndSerialDecodeAgree) {
  const std::string path = Write("p.laz", Laz7());
  Expected<ScanReadResult> one = Status::Internal("not run"), all = Status::Internal("not run");
  tbb::task_arena(1).execute([&] { one = ReadLas(path, {}); });
  tbb::task_arena(2).execute([&] { all = ReadLas(path, {}); });
  ASSERT_TRUE(one.ok()) << one.status().message();
  ASSERT_TRUE(all.ok()) << all.status().message();
  EXPECT_EQ(one->points.positions, all->points.positions);
  EXPECT_EQ(one->points.colors, all->points.colors);
  EXPECT_EQ(one->format, "laz layered 1.4 format 7");
}

TEST_F(LazErrorTest, TruncatedFilesNameFileAndPlace) {
  const std::string laz = Laz7();
  for (size_t cut = 0; cut < laz.size(); cut += cut < PointOffset(laz) + 64 ? 31 : 997) {
    SCOPED_TRACE("cut at " + std::to_string(cut));
    const std::string error = ErrorOf(laz.substr(0, cut));
    ASSERT_THAT(error, StartsWith(Path("bad.laz") + ": "));
  }
  EXPECT_THAT(
      ErrorOf(laz.substr(0, laz.size() - 20)),
      ContainsRegex("bad.laz: LAZ chunk table offset [0-9]+ \\(byte [0-9]+\\) is outside the "
                    "file's [0-9]+\\.\\.[0-9]+ bytes; truncated file\\?"));
}

TEST_F(LazErrorTest, DamagedBytesNeverCrash) {
  // Every byte in turn set to 0xFF, then to its complement: the reader
  // either reads (LAZ has no checksums) or names the file; under the
  // sanitizer build it also proves no read outside the buffers.
  const std::string laz = Laz7();
  size_t errors = 0;
  for (size_t at = 0; at < laz.size(); at += at < PointOffset(laz) + 200 ? 3 : 97) {
    for (int flip : {0, 1}) {
      std::string damaged = laz;
      damaged[at] = flip ? static_cast<char>(~damaged[at]) : '\xFF';
      const std::string error = ErrorOf(damaged);
      if (!error.empty()) {
        ++errors;
        ASSERT_THAT(error, StartsWith(Path("bad.laz") + ": ")) << "byte " << at;
      }
    }
  }
  EXPECT_GT(errors, 0u);
}

TEST_F(LazErrorTest, LayerSizePastTheChunk) {
  std::string laz = Laz7();
  const size_t sizes = PointOffset(laz) + 8 + 36 + 4;  // chunk 0: raw point, count, sizes
  Put<uint32_t>(&laz, sizes, 0x7FFFFFFF);
  EXPECT_THAT(ErrorOf(laz),
              ContainsRegex("bad.laz: LAZ chunk 0 of 3 \\(points 0-999, bytes [0-9]+-[0-9]+\\): "
                            "layer 0 of 2147483647 bytes runs past the chunk's end"));
}

TEST_F(LazErrorTest, ShortLayerRunsOut) {
  std::string laz = Laz7();
  const size_t sizes = PointOffset(laz) + 8 + 36 + 4;
  Put<uint32_t>(&laz, sizes, 40);  // the XY layer cut to 40 bytes
  EXPECT_THAT(ErrorOf(laz),
              ContainsRegex("bad.laz: LAZ chunk 0 of 3 \\(points 0-999, bytes [0-9]+-[0-9]+\\): "
                            "(compressed data ran out|damaged compressed data) at point [0-9]+"));
}

TEST_F(LazErrorTest, VlrErrorsNameTheVlr) {
  const std::string laz = Laz7();
  // The laszip VLR is the last before the points: 34 + 6 * 2 bytes.
  const size_t vlr = PointOffset(laz) - 46;
  std::string bad = laz;
  Put<uint16_t>(&bad, vlr, 7);
  EXPECT_THAT(ErrorOf(bad),
              HasSubstr("bad.laz: LAZ compressor 7 is unknown (expected 1 pointwise, 2 "
                        "pointwise chunked or 3 layered) (laszip VLR at byte " +
                        std::to_string(vlr) + ")"));
  bad = laz;
  Put<uint16_t>(&bad, vlr + 34 + 6 + 4, 4);  // RGB14 version 4
  EXPECT_THAT(
      ErrorOf(bad),
      HasSubstr("bad.laz: laszip VLR item 1 (RGB14) version 4 is not supported (expected 3)"));
  bad = laz;
  Put<uint16_t>(&bad, vlr + 34 + 6, 8);  // RGB12 in a format 7 file
  EXPECT_THAT(ErrorOf(bad),
              HasSubstr("bad.laz: laszip VLR item 1 (RGB12) does not belong to point format 7"));
  bad = laz;
  bad[104] = static_cast<char>(0x80 | 5);
  Put<uint16_t>(&bad, 105, 63);
  EXPECT_THAT(ErrorOf(bad), HasSubstr("bad.laz: LAZ point format 5 (waveforms) is not supported"));
}

}  // namespace
}  // namespace pb

namespace pb {
namespace {

// value / (length >> 15) reaches 2^15 + 63 (length >= 2^24): the lookup at
// that index and the next must stay inside every model's decoder table.
TEST(LazCodecTest, DecoderTableCoversEveryScaledValue) {
  for (uint32_t symbols : {17u, 33u, 64u, 128u, 256u, 257u, 515u, 516u, 1024u}) {
    laz::SymbolModel model(symbols);
    ASSERT_FALSE(model.decoder_table_.empty());
    const uint32_t max_scaled = (1u << 15) + 63;
    EXPECT_LE((max_scaled >> model.table_shift_) + 1, model.decoder_table_.size() - 1) << symbols;
  }
}

// Random symbols, bits, raw bits and integers through the encoder and
// back, for the model sizes LAZ uses.
TEST(LazCodecTest, EncoderAndDecoderRoundTrip) {
  std::mt19937 random(3);
  const std::vector<uint32_t> sizes = {2, 3, 4, 5, 6, 13, 16, 64, 128, 256, 515, 516};
  std::vector<laz::SymbolModel> encode_models, decode_models;
  for (uint32_t s : sizes) {
    encode_models.emplace_back(s);
    decode_models.emplace_back(s);
  }
  laz::BitModel encode_bit, decode_bit;
  laz::IntegerModel encode_int(32, 3), decode_int(32, 3);
  laz::IntegerModel encode_short(16, 2), decode_short(16, 2);
  laz::ArithmeticEncoder encoder;
  struct Step {
    int kind;
    uint32_t model;
    int32_t prediction;
    int64_t value;
  };
  std::vector<Step> steps;
  for (int i = 0; i < 200000; ++i) {
    const int kind = static_cast<int>(random() % 5);
    const uint32_t m = static_cast<uint32_t>(random() % sizes.size());
    // Mostly small values, so the models adapt away from uniform.
    const uint32_t skew = random() % 8 == 0 ? static_cast<uint32_t>(random()) : random() % 4;
    Step step{kind, m, static_cast<int32_t>(random() % 1000), 0};
    switch (kind) {
      case 0:
        step.value = skew % sizes[m];
        encoder.EncodeSymbol(encode_models[m], static_cast<uint32_t>(step.value));
        break;
      case 1:
        step.value = skew & 1;
        encoder.EncodeBit(encode_bit, static_cast<uint32_t>(step.value));
        break;
      case 2:
        step.value = static_cast<int32_t>(step.prediction + static_cast<int32_t>(skew));
        encoder.EncodeInt(encode_int, step.prediction, static_cast<int32_t>(step.value), m % 3);
        break;
      case 3:
        step.value = (step.prediction + skew) % 65536;
        encoder.EncodeInt(encode_short, step.prediction, static_cast<int32_t>(step.value), m % 2);
        break;
      default:
        step.value = skew & ((2u << m) - 1);
        encoder.WriteBits(1 + m, static_cast<uint32_t>(step.value));
        break;
    }
    steps.push_back(step);
  }
  const std::vector<uint8_t> bytes = encoder.Done();
  laz::ArithmeticDecoder decoder;
  decoder.Init(bytes.data(), bytes.data() + bytes.size());
  for (size_t i = 0; i < steps.size(); ++i) {
    const Step& step = steps[i];
    int64_t got = 0;
    switch (step.kind) {
      case 0:
        got = decoder.DecodeSymbol(decode_models[step.model]);
        break;
      case 1:
        got = decoder.DecodeBit(decode_bit);
        break;
      case 2:
        got = decoder.DecodeInt(decode_int, step.prediction, step.model % 3);
        break;
      case 3:
        got = decoder.DecodeInt(decode_short, step.prediction, step.model % 2);
        break;
      default:
        got = decoder.ReadBits(1 + step.model);
        break;
    }
    ASSERT_EQ(got, step.value) << "step " << i << " kind " << step.kind;
  }
  EXPECT_EQ(decoder.overrun_bytes(), 0u);
  EXPECT_FALSE(decoder.corrupt());
}

}  // namespace
}  // namespace pb
