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

size_t StandardBytes(int format) {
  static constexpr size_t kSizes[] = {20, 28, 26, 34, 57, 63, 30, 36, 38};
  return kSizes[format];
}

template <typename T>
void Put(std::string* bytes, size_t offset, T value) {
  std::memcpy(bytes->data() + offset, &value, sizeof(T));
}

// An uncompressed LAS file whose every field varies the way airborne scans
// do: pulses of 1-3 returns (up to 7 or 15 now and then), two interleaved
// flight lines (GPS time jumps between sequences), up to
// `scanner_channels` channels switching (formats 6-8), grey and colored
// points.
std::string MakeScanLas(int format, size_t points, size_t extra_bytes = 0, uint32_t seed = 1,
                        int scanner_channels = 4) {
  const int minor = format >= 6 ? 4 : 2;
  const size_t header_bytes = minor == 4 ? 375 : 227;
  const size_t record_bytes = StandardBytes(format) + extra_bytes;
  std::string las(header_bytes + record_bytes * points, '\0');
  std::memcpy(las.data(), "LASF", 4);
  las[24] = 1;
  las[25] = static_cast<char>(minor);
  Put<uint16_t>(&las, 94, static_cast<uint16_t>(header_bytes));
  Put<uint32_t>(&las, 96, static_cast<uint32_t>(header_bytes));
  las[104] = static_cast<char>(format);
  Put<uint16_t>(&las, 105, static_cast<uint16_t>(record_bytes));
  Put<uint32_t>(&las, 107, minor == 4 ? 0 : static_cast<uint32_t>(points));
  if (minor == 4) Put<uint64_t>(&las, 247, points);
  const double scale = 0.01;
  const double offsets[3] = {652000, 5412000, 0};
  for (int axis = 0; axis < 3; ++axis) {
    Put<double>(&las, 131 + 8 * axis, scale);
    Put<double>(&las, 155 + 8 * axis, offsets[axis]);
  }
  std::mt19937 random(seed);
  auto uniform = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(random); };
  int32_t x = 30000, y = 40000, z = 2000;
  int32_t min[3] = {INT32_MAX, INT32_MAX, INT32_MAX}, max[3] = {INT32_MIN, INT32_MIN, INT32_MIN};
  double times[2] = {1000.0, 90000.0};
  int line = 0, returns = 1, return_number = 1, channel = 0;
  uint16_t rgb[3] = {1000, 2000, 3000};
  int16_t scan_angle = 0;
  uint16_t point_source = 7;
  uint8_t classification = 2;
  for (size_t i = 0; i < points; ++i) {
    if (return_number >= returns) {  // a new pulse
      return_number = 1;
      returns = uniform(0, 99) < 70 ? 1 : uniform(0, 99) < 90 ? uniform(2, 3) : uniform(4, format >= 6 ? 15 : 7);
      if (uniform(0, 199) == 0) line ^= 1;
      times[line] += uniform(0, 99) < 95 ? 1.0e-5 : uniform(0, 99) < 50 ? 3.0e-5 : 7.5;
      x += uniform(5, 60);
      if (uniform(0, 299) == 0) y += uniform(-5000, 5000);
      scan_angle = static_cast<int16_t>(scan_angle + uniform(-2, 2));
      if (uniform(0, 999) == 0) point_source = static_cast<uint16_t>(uniform(0, 65535));
      if (format >= 6 && uniform(0, 49) == 0) channel = uniform(0, scanner_channels - 1);
    } else {
      ++return_number;
    }
    y += uniform(-20, 20);
    z += uniform(-30, 30) - (return_number - 1) * 50;
    if (uniform(0, 9) == 0) classification = static_cast<uint8_t>(uniform(0, 99) < 80 ? uniform(1, 6) : uniform(0, 255));
    if (uniform(0, 2) == 0) {
      if (uniform(0, 3) == 0) {  // grey
        rgb[0] = rgb[1] = rgb[2] = static_cast<uint16_t>(uniform(0, 255) * 257);
      } else {
        for (uint16_t& c : rgb) c = static_cast<uint16_t>(std::clamp(c + uniform(-900, 900), 0, 65535));
      }
    }
    const int32_t xyz[3] = {x, y, z};
    for (int axis = 0; axis < 3; ++axis) {
      min[axis] = std::min(min[axis], xyz[axis]);
      max[axis] = std::max(max[axis], xyz[axis]);
    }
    const size_t at = header_bytes + i * record_bytes;
    uint8_t* r = reinterpret_cast<uint8_t*>(las.data() + at);
    Put<int32_t>(&las, at, x);
    Put<int32_t>(&las, at + 4, y);
    Put<int32_t>(&las, at + 8, z);
    Put<uint16_t>(&las, at + 12, static_cast<uint16_t>(uniform(0, 99) < 10 ? 0 : uniform(0, 4000)));
    const int edge = uniform(0, 99) == 0, direction = (i / 500) & 1;
    size_t gps_at, rgb_at = 0;
    if (format < 6) {
      r[14] = static_cast<uint8_t>((return_number & 7) | ((returns & 7) << 3) | (direction << 6) | (edge << 7));
      r[15] = classification;
      r[16] = static_cast<uint8_t>(static_cast<int8_t>(std::clamp(scan_angle / 100, -90, 90)));
      r[17] = static_cast<uint8_t>(uniform(0, 9) == 0 ? uniform(0, 255) : 0);
      Put<uint16_t>(&las, at + 18, point_source);
      gps_at = 20;
      if (format >= 2) rgb_at = format == 2 ? 20 : 28;
    } else {
      r[14] = static_cast<uint8_t>(return_number | (returns << 4));
      r[15] = static_cast<uint8_t>((uniform(0, 49) == 0 ? uniform(0, 15) : 0) | (channel << 4) | (direction << 6) | (edge << 7));
      r[16] = classification;
      r[17] = static_cast<uint8_t>(uniform(0, 9) == 0 ? uniform(0, 255) : 0);
      Put<int16_t>(&las, at + 18, scan_angle);
      Put<uint16_t>(&las, at + 20, point_source);
      gps_at = 22;
      if (format >= 7) rgb_at = 30;
    }
    if (format != 0 && format != 2) Put<double>(&las, at + gps_at, times[line]);
    if (rgb_at != 0) {
      for (int c = 0; c < 3; ++c) Put<uint16_t>(&las, at + rgb_at + 2 * c, rgb[c]);
    }
    if (format == 8) Put<uint16_t>(&las, at + 36, static_cast<uint16_t>(uniform(0, 65535)));
    for (size_t b = 0; b < extra_bytes; ++b) {
      r[StandardBytes(format) + b] = static_cast<uint8_t>(b == 0 ? i & 0xFF : uniform(0, 3));
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    Put<double>(&las, 179 + 16 * axis, max[axis] * scale + offsets[axis]);
    Put<double>(&las, 187 + 16 * axis, min[axis] * scale + offsets[axis]);
  }
  return las;
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
  static std::string Records(const std::string& las) {
    return las.substr(Get<uint32_t>(las, 96));
  }

  void ExpectRoundTrip(int format, size_t points, size_t extra_bytes, const laz::LazWriteOptions& options) {
    SCOPED_TRACE("format " + std::to_string(format) + ", " + std::to_string(points) + " points, " +
                 std::to_string(extra_bytes) + " extra bytes");
    const std::string las = MakeScanLas(format, points, extra_bytes, static_cast<uint32_t>(format + 10 * extra_bytes));
    const std::string laz_path = Write("p" + std::to_string(format) + ".laz", laz::CompressLas(las, options));
    const std::string decoded = DecodeAll(laz_path);
    ASSERT_EQ(decoded.size(), Records(las).size()) << decoded.substr(0, 300);
    const std::string expected = Records(las);
    const size_t record_bytes = Get<uint16_t>(las, 105);
    for (size_t i = 0; i < points; ++i) {
      ASSERT_EQ(decoded.compare(i * record_bytes, record_bytes, expected, i * record_bytes, record_bytes), 0)
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
      {"pointwise_f0", 0, 12000, 0, small_chunks},  {"pointwise_f1", 1, 12000, 0, small_chunks},
      {"pointwise_f2_rgb", 2, 12000, 0, small_chunks}, {"pointwise_f3_rgb", 3, 12000, 0, small_chunks},
      {"pointwise_f3_extra", 3, 12000, 4, small_chunks}, {"layered_f6_channels", 6, 12000, 0, small_chunks, 4},
      {"layered_f7_rgb", 7, 12000, 0, small_chunks},  {"layered_f8_rgbnir", 8, 12000, 0, small_chunks},
      {"layered_f7_extra", 7, 12000, 2, small_chunks}, {"layered_f7_variable", 7, 12000, 0, variable},
      {"copc_f7", 7, 8200, 0, copc},
  };
  for (const Sample& sample : samples) {
    SCOPED_TRACE(sample.name);
    const std::string las = MakeScanLas(sample.format, sample.points, sample.extra_bytes,
                                        static_cast<uint32_t>(sample.points + sample.format),
                                        sample.scanner_channels);
    const std::string stem = dir + "/" + sample.name;
    { std::ofstream(stem + ".las", std::ios::binary) << las; }
    { std::ofstream(stem + ".laz", std::ios::binary) << laz::CompressLas(las, sample.options); }
    EXPECT_EQ(DecodeAll(stem + ".laz"), Records(las));
  }
}

}  // namespace
}  // namespace pb
