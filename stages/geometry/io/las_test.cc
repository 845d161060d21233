#include "stages/geometry/io/las.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "stages/geometry/testing/test_data.h"

namespace pb {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

// --- A minimal LAS writer, for these tests only ------------------------------

struct TestPoint {
  double x, y, z;  // meters, quantized by the writer
  uint16_t intensity;
  uint16_t red, green, blue;
};

struct LasSpec {
  int minor = 2;  // version 1.minor
  int format = 0;
  int extra_record_bytes = 0;  // beyond the format's standard size
  int vlr_payload_bytes = 0;   // one VLR of this payload between header and points
  std::array<double, 3> scale = {0.001, 0.001, 0.001};
  std::array<double, 3> offset = {652000, 5412000, 0};
  bool legacy_count = true;  // 1.4: also fill the 32-bit count
  bool bbox = true;          // false: leave min/max zero
};

size_t StandardRecordBytes(int format) {
  static constexpr size_t kSizes[] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  return kSizes[format];
}

int RgbOffset(int format) {
  static constexpr int kOffsets[] = {-1, -1, 20, 28, -1, 28, -1, 30, 30, -1, 30};
  return kOffsets[format];
}

template <typename T>
void Put(std::string* bytes, size_t offset, T value) {
  static_assert(std::endian::native == std::endian::little, "test writer assumes little-endian");
  std::memcpy(bytes->data() + offset, &value, sizeof(T));
}

int32_t Quantize(double value, double scale, double offset) {
  return static_cast<int32_t>(std::llround((value - offset) / scale));
}

// The coordinate the file stores for `value`, as a reader must decode it.
double Stored(double value, int axis, const LasSpec& spec) {
  return Quantize(value, spec.scale[axis], spec.offset[axis]) * spec.scale[axis] +
         spec.offset[axis];
}

std::string MakeLas(const LasSpec& spec, const std::vector<TestPoint>& points) {
  const size_t header_bytes = spec.minor >= 4 ? 375 : spec.minor == 3 ? 235 : 227;
  const size_t vlr_bytes = spec.vlr_payload_bytes > 0 ? 54 + spec.vlr_payload_bytes : 0;
  const size_t record_bytes = StandardRecordBytes(spec.format) + spec.extra_record_bytes;
  std::string bytes(header_bytes + vlr_bytes + record_bytes * points.size(), '\0');
  std::memcpy(bytes.data(), "LASF", 4);
  bytes[24] = 1;
  bytes[25] = static_cast<char>(spec.minor);
  std::memcpy(bytes.data() + 26, "pointbake test", 14);
  Put<uint16_t>(&bytes, 94, header_bytes);
  Put<uint32_t>(&bytes, 96, header_bytes + vlr_bytes);
  Put<uint32_t>(&bytes, 100, vlr_bytes > 0 ? 1 : 0);
  bytes[104] = static_cast<char>(spec.format);
  Put<uint16_t>(&bytes, 105, record_bytes);
  Put<uint32_t>(&bytes, 107, spec.legacy_count ? points.size() : 0);
  std::array<double, 3> min_m = {1e300, 1e300, 1e300}, max_m = {-1e300, -1e300, -1e300};
  for (const TestPoint& p : points) {
    const double xyz[3] = {p.x, p.y, p.z};
    for (int axis = 0; axis < 3; ++axis) {
      min_m[axis] = std::min(min_m[axis], Stored(xyz[axis], axis, spec));
      max_m[axis] = std::max(max_m[axis], Stored(xyz[axis], axis, spec));
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    Put<double>(&bytes, 131 + 8 * axis, spec.scale[axis]);
    Put<double>(&bytes, 155 + 8 * axis, spec.offset[axis]);
    Put<double>(&bytes, 179 + 16 * axis, spec.bbox ? max_m[axis] : 0.0);
    Put<double>(&bytes, 187 + 16 * axis, spec.bbox ? min_m[axis] : 0.0);
  }
  if (spec.minor >= 4) Put<uint64_t>(&bytes, 247, points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const size_t start = header_bytes + vlr_bytes + i * record_bytes;
    // Fields the reader must ignore (returns, classification, GPS time,
    // waveform, NIR, extra bytes) hold a recognizable junk pattern.
    std::fill(bytes.begin() + start, bytes.begin() + start + record_bytes, '\xAB');
    const TestPoint& p = points[i];
    Put<int32_t>(&bytes, start + 0, Quantize(p.x, spec.scale[0], spec.offset[0]));
    Put<int32_t>(&bytes, start + 4, Quantize(p.y, spec.scale[1], spec.offset[1]));
    Put<int32_t>(&bytes, start + 8, Quantize(p.z, spec.scale[2], spec.offset[2]));
    Put<uint16_t>(&bytes, start + 12, p.intensity);
    if (RgbOffset(spec.format) >= 0) {
      Put<uint16_t>(&bytes, start + RgbOffset(spec.format), p.red);
      Put<uint16_t>(&bytes, start + RgbOffset(spec.format) + 2, p.green);
      Put<uint16_t>(&bytes, start + RgbOffset(spec.format) + 4, p.blue);
    }
  }
  return bytes;
}

const std::vector<TestPoint> kPoints = {
    {652341.125, 5412345.678, 312.5, 0, 0x0000, 0x1234, 0xFFFF},
    {652343.001, 5412340.002, 310.25, 65535, 0x8000, 0x7F00, 0x0100},
    {652339.999, 5412349.5, 315.004, 1000, 0xFF00, 0x00FF, 0x4321},
};

class LasTest : public pb::testing::TempDirTest {
 protected:
  std::string ErrorOf(const std::string& contents, const std::string& name = "bad.las") const {
    auto read = ReadLas(Write(name, contents), {});
    return read.ok() ? "" : read.status().message();
  }

  // Writes kPoints with `spec` and checks everything the reader returns.
  void ExpectPointsRead(const LasSpec& spec) {
    SCOPED_TRACE("LAS 1." + std::to_string(spec.minor) + " format " + std::to_string(spec.format));
    auto read = ReadLas(Write("p.las", MakeLas(spec, kPoints)), {});
    ASSERT_TRUE(read.ok()) << read.status().message();
    const PointCloud& cloud = read->points;
    EXPECT_EQ(read->format,
              "las 1." + std::to_string(spec.minor) + " format " + std::to_string(spec.format));
    ASSERT_EQ(cloud.size(), kPoints.size());
    EXPECT_TRUE(read->warnings.empty());
    EXPECT_FALSE(cloud.has_stations());
    // Header box: x 652339.999..652343.001, y 5412340.002..5412349.5,
    // z 310.25..315.004; centers rounded to 1 m.
    EXPECT_EQ(cloud.origin, (std::array<double, 3>{652342, 5412345, 313}));
    for (size_t i = 0; i < kPoints.size(); ++i) {
      const double xyz[3] = {kPoints[i].x, kPoints[i].y, kPoints[i].z};
      for (int axis = 0; axis < 3; ++axis) {
        const double expected = Stored(xyz[axis], axis, spec);
        EXPECT_NEAR(cloud.origin[axis] + cloud.positions[3 * i + axis], expected, 1e-6);
        EXPECT_NEAR(expected, xyz[axis], 1e-9 + spec.scale[axis] / 2);
      }
    }
    EXPECT_THAT(cloud.intensities, ElementsAre(0.0f, 1.0f, static_cast<float>(1000 / 65535.0)));
    if (RgbOffset(spec.format) >= 0) {
      // 16-bit values (some exceed 255) shifted to 8 bits.
      EXPECT_THAT(cloud.colors, ElementsAre(0x00, 0x12, 0xFF, 0x80, 0x7F, 0x01, 0xFF, 0x00, 0x43));
    } else {
      EXPECT_FALSE(cloud.has_colors());
    }
    EXPECT_TRUE(Validate(cloud).ok());
  }
};

// --- Valid files --------------------------------------------------------------

TEST_F(LasTest, Version12Formats0To3) {
  for (int format : {0, 1, 2, 3}) {
    LasSpec spec;
    spec.format = format;
    ExpectPointsRead(spec);
  }
}

TEST_F(LasTest, Version14AllFormats) {
  for (int format = 0; format <= 10; ++format) {
    LasSpec spec;
    spec.minor = 4;
    spec.format = format;
    spec.legacy_count = format < 6;  // 1.4 leaves the legacy count 0 for formats 6+
    ExpectPointsRead(spec);
  }
}

TEST_F(LasTest, Version13WithVlrAndExtraBytes) {
  LasSpec spec;
  spec.minor = 3;
  spec.format = 3;
  spec.vlr_payload_bytes = 17;
  spec.extra_record_bytes = 9;
  ExpectPointsRead(spec);
}

TEST_F(LasTest, EightBitColorsAreKept) {
  LasSpec spec;
  spec.format = 2;
  auto read = ReadLas(
      Write("c.las", MakeLas(spec, {{1, 2, 3, 0, 10, 20, 255}, {4, 5, 6, 0, 0, 128, 1}})), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_THAT(read->points.colors, ElementsAre(10, 20, 255, 0, 128, 1));
}

TEST_F(LasTest, LateSixteenBitColorRescalesEarlierPoints) {
  LasSpec spec;
  spec.format = 7;
  spec.minor = 4;
  // The first point alone looks 8-bit; the second proves the file is 16-bit.
  auto read = ReadLas(Write("c.las", MakeLas(spec, {{1, 2, 3, 0, 200, 255, 3},
                                                    {4, 5, 6, 0, 0x1000, 0xFFFF, 0x0200}})),
                      {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_THAT(read->points.colors, ElementsAre(0, 0, 0, 0x10, 0xFF, 0x02));
}

TEST_F(LasTest, MissingBoundingBoxFallsBackToTheFirstPoint) {
  LasSpec spec;
  spec.bbox = false;
  auto read = ReadLas(Write("b.las", MakeLas(spec, kPoints)), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.origin, (std::array<double, 3>{652341, 5412346, 313}));
  EXPECT_THAT(read->warnings, ElementsAre(HasSubstr("bounding box does not contain")));
  EXPECT_NEAR(read->points.origin[1] + read->points.positions[4], 5412340.002, 1e-6);
}

TEST_F(LasTest, EmptyFileIsAnEmptyCloud) {
  auto read = ReadLas(Write("e.las", MakeLas(LasSpec{}, {})), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_TRUE(read->points.empty());
}

TEST_F(LasTest, StreamsManyChunksAndReportsProgress) {
  // 120,000 format-0 points = 2.4 MB: three 1 MiB chunks.
  std::vector<TestPoint> points;
  for (int i = 0; i < 120000; ++i) {
    points.push_back({652000.0 + i * 0.001, 5412000.0 - i * 0.002, i * 0.0005,
                      static_cast<uint16_t>(i), 0, 0, 0});
  }
  double last = -1;
  ScanReadOptions options;
  options.progress = [&](double fraction) { last = fraction; };
  auto read = ReadLas(Write("big.las", MakeLas(LasSpec{}, points)), options);
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  ASSERT_EQ(cloud.size(), 120000u);
  const size_t i = 119999;
  // 120 m from the origin (652060, 5411880, 30) float32 steps are 7.6 um.
  EXPECT_EQ(cloud.origin, (std::array<double, 3>{652060, 5411880, 30}));
  EXPECT_NEAR(cloud.origin[0] + cloud.positions[3 * i], 652119.999, 4e-6);
  EXPECT_NEAR(cloud.origin[1] + cloud.positions[3 * i + 1], 5411760.002, 4e-6);
  EXPECT_NEAR(cloud.origin[2] + cloud.positions[3 * i + 2], 60.0, 4e-6);  // 59.9995 quantized
  EXPECT_FLOAT_EQ(cloud.intensities[i], static_cast<float>((i & 0xFFFF) / 65535.0));
  EXPECT_EQ(last, 1.0);
}

// --- Malformed input ----------------------------------------------------------

TEST_F(LasTest, MissingFileIsNotFound) {
  auto read = ReadLas((dir_ / "absent.las").string(), {});
  ASSERT_FALSE(read.ok());
  EXPECT_EQ(read.status().code(), Status::Code::kNotFound);
}

TEST_F(LasTest, BadSignature) {
  std::string bytes = MakeLas(LasSpec{}, kPoints);
  bytes[3] = 'X';
  EXPECT_THAT(ErrorOf(bytes),
              HasSubstr("bad.las: not a LAS file (expected signature 'LASF' at byte 0)"));
  EXPECT_THAT(ErrorOf("LA"), HasSubstr("not a LAS file"));
}

TEST_F(LasTest, TruncatedHeader) {
  EXPECT_THAT(ErrorOf(MakeLas(LasSpec{}, kPoints).substr(0, 200)),
              HasSubstr("bad.las: truncated header: 200 bytes, a LAS header has at least 227"));
  LasSpec spec;
  spec.minor = 4;
  EXPECT_THAT(ErrorOf(MakeLas(spec, {}).substr(0, 300)),
              HasSubstr("bad.las: truncated header: 300 bytes, the header declares 375"));
}

TEST_F(LasTest, TruncatedPointsNameThePoint) {
  const std::string bytes = MakeLas(LasSpec{}, kPoints);  // 227 + 3 * 20 bytes
  EXPECT_THAT(ErrorOf(bytes.substr(0, bytes.size() - 5)),
              HasSubstr("bad.las: truncated: point 2 of 3 at byte 267 (file has 282 bytes)"));
}

TEST_F(LasTest, RecordLengthTooShortForTheFormat) {
  LasSpec spec;
  spec.format = 3;
  std::string bytes = MakeLas(spec, kPoints);
  bytes[105] = 30;
  bytes[106] = 0;
  EXPECT_THAT(ErrorOf(bytes), HasSubstr("bad.las: point record length 30 (byte 105) is smaller "
                                        "than the 34 bytes point format 3 needs"));
}

TEST_F(LasTest, ContentNotNameDecidesCompression) {
  // An uncompressed file named .LAZ reads as LAS (LAZ itself: laz_test.cc).
  auto read = ReadLas(Write("scan.LAZ", MakeLas(LasSpec{}, kPoints)), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.size(), kPoints.size());
  EXPECT_EQ(read->format, "las 1.2 format 0");
}

TEST_F(LasTest, CompressionBitWithoutLaszipVlr) {
  for (uint8_t bit : {0x80, 0x40}) {
    LasSpec spec;
    spec.format = 3;
    spec.vlr_payload_bytes = 10;  // one VLR, not the laszip one
    std::string bytes = MakeLas(spec, kPoints);
    bytes[104] = static_cast<char>(3 | bit);
    auto read = ReadLas(Write("compressed.las", bytes), {});
    ASSERT_FALSE(read.ok());
    EXPECT_EQ(read.status().code(), Status::Code::kCorrupt);
    EXPECT_THAT(read.status().message(),
                HasSubstr("compressed.las: compressed point format 3 (byte 104 has a compression "
                          "bit, 0x80 or 0x40, set) but "
                          "none of the 1 VLRs is the laszip VLR"));
  }
}

TEST_F(LasTest, Version20IsUnsupported) {
  std::string bytes = MakeLas(LasSpec{}, kPoints);
  bytes[24] = 2;
  bytes[25] = 0;
  EXPECT_THAT(ErrorOf(bytes), HasSubstr("bad.las: LAS version 2.0 is not supported (byte 24; "
                                        "expected 1.0 to 1.4)"));
}

TEST_F(LasTest, UnknownPointFormat) {
  std::string bytes = MakeLas(LasSpec{}, kPoints);
  bytes[104] = 11;
  EXPECT_THAT(ErrorOf(bytes), HasSubstr("bad.las: point data record format 11 (byte 104) is not "
                                        "defined by LAS 1.4"));
}

TEST_F(LasTest, PointOffsetInsideHeader) {
  std::string bytes = MakeLas(LasSpec{}, kPoints);
  Put<uint32_t>(&bytes, 96, 100);
  EXPECT_THAT(ErrorOf(bytes), HasSubstr("bad.las: offset to point data 100 (byte 96) lies inside "
                                        "the 227-byte header"));
}

TEST_F(LasTest, HeaderSizeTooSmall) {
  std::string bytes = MakeLas(LasSpec{}, kPoints);
  Put<uint16_t>(&bytes, 94, 100);
  EXPECT_THAT(ErrorOf(bytes),
              HasSubstr("bad.las: header size 100 (byte 94) is smaller than the minimum 227"));
}

TEST_F(LasTest, ZeroScale) {
  std::string bytes = MakeLas(LasSpec{}, kPoints);
  Put<double>(&bytes, 139, 0.0);
  EXPECT_THAT(ErrorOf(bytes), HasSubstr("bad.las: y scale 0.000000 or offset 5412000.000000 "
                                        "(bytes 139, 163) is not a finite non-zero number"));
}

TEST_F(LasTest, CountLargerThanTheFile) {
  std::string bytes = MakeLas(LasSpec{}, kPoints);
  Put<uint32_t>(&bytes, 107, 4000000000u);
  EXPECT_THAT(ErrorOf(bytes), HasSubstr("bad.las: truncated: point 3 of 4000000000 at byte 287"));
}

}  // namespace
}  // namespace pb
