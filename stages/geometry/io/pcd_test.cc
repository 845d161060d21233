#include "stages/geometry/io/pcd.h"

#include "stages/geometry/testing/test_data.h"
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace pb {
namespace {

using ::testing::HasSubstr;

class PcdTest : public pb::testing::TempDirTest {
 protected:
  std::string Write(const std::string& contents, const std::string& name = "scan.pcd") const {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << contents;
    return path;
  }
  // Reads and expects an error whose message contains `fragment`.
  void ExpectError(const std::string& contents, const std::string& fragment) const {
    const auto read = ReadPcd(Write(contents), {});
    ASSERT_FALSE(read.ok()) << "expected an error containing: " << fragment;
    EXPECT_THAT(read.status().message(), HasSubstr(fragment));
  }

};

std::string SharedData() { return pb::testing::SharedDataDir(); }

template <typename T>
void Append(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // PCD binary is little-endian, as this host
  out->append(bytes, sizeof(T));
}

float PackedRgb(uint8_t r, uint8_t g, uint8_t b) {
  const uint32_t packed = uint32_t{r} << 16 | uint32_t{g} << 8 | b;
  float value;
  std::memcpy(&value, &packed, sizeof value);
  return value;
}

// A valid LZF stream for `data`: literal runs, plus back references to the
// previous byte or the previous 4-byte value (enough to exercise literal,
// short and extended references).
std::string LzfCompress(const std::string& data) {
  std::string out;
  std::string literal;
  auto flush_literal = [&]() {
    for (size_t k = 0; k < literal.size(); k += 32) {
      const size_t n = std::min<size_t>(32, literal.size() - k);
      out.push_back(static_cast<char>(n - 1));
      out.append(literal, k, n);
    }
    literal.clear();
  };
  size_t i = 0;
  while (i < data.size()) {
    size_t best = 0, best_distance = 0;
    for (size_t distance : {1, 4}) {
      size_t run = 0;
      while (i >= distance && i + run < data.size() && run < 264 &&
             data[i + run] == data[i + run - distance]) {
        ++run;
      }
      if (run > best) best = run, best_distance = distance;
    }
    if (best < 3) {
      literal.push_back(data[i++]);
      continue;
    }
    flush_literal();
    const size_t len = best - 2;
    const size_t d = best_distance - 1;
    if (len < 7) {
      out.push_back(static_cast<char>(len << 5 | d >> 8));
    } else {
      out.push_back(static_cast<char>(7 << 5 | d >> 8));
      out.push_back(static_cast<char>(len - 7));
    }
    out.push_back(static_cast<char>(d & 255));
    i += best;
  }
  flush_literal();
  return out;
}

std::string CompressedBody(const std::string& soa) {
  const std::string lzf = LzfCompress(soa);
  std::string body;
  Append(&body, static_cast<uint32_t>(lzf.size()));
  Append(&body, static_cast<uint32_t>(soa.size()));
  return body + lzf;
}

TEST_F(PcdTest, AsciiWithNormalsSeparateColorsAndIntensity) {
  const std::string path = Write(
      "# .PCD v0.6 - Point Cloud Data file format\n"
      "VERSION 0.6\n"
      "FIELDS x y z normal_x normal_y normal_z r g b intensity label\n"
      "SIZE 4 4 4 4 4 4 1 1 1 1 4\n"
      "TYPE F F F F F F U U U U U\n"
      "COUNT 1 1 1 1 1 1 1 1 1 1 1\n"
      "WIDTH 2\n"
      "HEIGHT 1\n"
      "POINTS 2\n"
      "DATA ascii\n"
      "1.5 -2.25 3 0 0 1 255 128 0 255 7\n"
      "\n"
      "-0.125 4 5e-1 0.6 0.8 0 1 2 3 51 8\n");
  const auto read = ReadPcd(path, {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  EXPECT_EQ(read->format, "pcd ascii");
  EXPECT_EQ(cloud.origin, (std::array<double, 3>{0, 0, 0}));
  EXPECT_EQ(cloud.positions, (std::vector<float>{1.5f, -2.25f, 3, -0.125f, 4, 0.5f}));
  EXPECT_EQ(cloud.normals, (std::vector<float>{0, 0, 1, 0.6f, 0.8f, 0}));
  EXPECT_EQ(cloud.colors, (std::vector<uint8_t>{255, 128, 0, 1, 2, 3}));
  EXPECT_EQ(cloud.intensities, (std::vector<float>{1.0f, 0.2f}));
  EXPECT_FALSE(cloud.has_stations());  // v0.6: no VIEWPOINT
  EXPECT_EQ(read->dropped_points, 0u);
}

TEST_F(PcdTest, AsciiPackedRgbAsFloatOrAsInteger) {
  // Older PCL writes the packed float, newer PCL the bits as an integer.
  char packed_float[64];
  std::snprintf(packed_float, sizeof packed_float, "%.9g", PackedRgb(10, 20, 30));
  const auto read = ReadPcd(Write(std::string("FIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\n"
                                              "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n"
                                              "0 0 0 ") +
                                  packed_float + "\n1 1 1 4278255360\n"),
                            {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.colors, (std::vector<uint8_t>{10, 20, 30, 0, 255, 0}));
}

TEST_F(PcdTest, BinarySkipsUnknownFieldsIncludingCountGreaterThanOne) {
  std::string file =
      "VERSION 0.7\n"
      "FIELDS x y z rgb fpfh normal_x normal_y normal_z curvature\n"
      "SIZE 4 4 4 4 4 4 4 4 4\n"
      "TYPE F F F F F F F F F\n"
      "COUNT 1 1 1 1 33 1 1 1 1\n"
      "WIDTH 2\n"
      "HEIGHT 1\n"
      "VIEWPOINT 0 0 0 1 0 0 0\n"
      "POINTS 2\n"
      "DATA binary\n";
  for (int i = 0; i < 2; ++i) {
    Append(&file, 1.0f + i);
    Append(&file, -2.0f);
    Append(&file, 0.25f * i);
    Append(&file, PackedRgb(200, 100 + i, 50));
    for (int k = 0; k < 33; ++k) Append(&file, 99.0f);
    Append(&file, 0.0f);
    Append(&file, 1.0f);
    Append(&file, 0.0f);
    Append(&file, 0.5f);
  }
  const auto read = ReadPcd(Write(file), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  EXPECT_EQ(read->format, "pcd binary");
  EXPECT_EQ(cloud.positions, (std::vector<float>{1, -2, 0, 2, -2, 0.25f}));
  EXPECT_EQ(cloud.normals, (std::vector<float>{0, 1, 0, 0, 1, 0}));
  EXPECT_EQ(cloud.colors, (std::vector<uint8_t>{200, 100, 50, 200, 101, 50}));
  EXPECT_FALSE(cloud.has_intensities());
  // The identity VIEWPOINT (PCL's default) names no sensor position.
  EXPECT_FALSE(cloud.has_stations());
  EXPECT_TRUE(cloud.stations.empty());
}

TEST_F(PcdTest, BinaryCompressedIsFieldByFieldAndOrganizedNanPointsAreDropped) {
  // 2 x 2 organized cloud, one "no return" point; x y z F4 + rgba U4.
  const float xs[] = {1, 2, std::numeric_limits<float>::quiet_NaN(), 4};
  const float ys[] = {0, 0, 0, 0};
  const float zs[] = {-1, -1, -1, -1};
  const uint32_t rgba[] = {0xff010203, 0xff040506, 0, 0xff0a0b0c};
  std::string soa;
  for (float v : xs) Append(&soa, v);
  for (float v : ys) Append(&soa, v);
  for (float v : zs) Append(&soa, v);
  for (uint32_t v : rgba) Append(&soa, v);
  const std::string header =
      "VERSION 0.7\nFIELDS x y z rgba\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
      "WIDTH 2\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA binary_compressed\n";
  const auto read = ReadPcd(Write(header + CompressedBody(soa)), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  EXPECT_EQ(read->format, "pcd binary_compressed");
  EXPECT_EQ(read->no_return_points, 1u);  // organized: a NaN is a cell without a return
  EXPECT_EQ(read->dropped_points, 0u);
  EXPECT_EQ(cloud.positions, (std::vector<float>{1, 0, -1, 2, 0, -1, 4, 0, -1}));
  EXPECT_EQ(cloud.colors, (std::vector<uint8_t>{1, 2, 3, 4, 5, 6, 10, 11, 12}));
  EXPECT_FALSE(cloud.has_stations());  // identity VIEWPOINT
  EXPECT_TRUE(cloud.stations.empty());
}

TEST_F(PcdTest, BinaryCompressedLongRunsUseExtendedBackReferences) {
  // 300 points at the same place: long runs of equal bytes in every field.
  const int n = 300;
  std::string soa;
  for (int axis = 0; axis < 3; ++axis) {
    for (int i = 0; i < n; ++i) Append(&soa, axis == 0 ? 0.0f : (i < 150 ? 7.0f : -3.5f));
  }
  const std::string body = CompressedBody(soa);
  ASSERT_LT(body.size(), soa.size() / 4);  // the back references did compress
  const auto read = ReadPcd(Write("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 300\nHEIGHT 1\n"
                                  "POINTS 300\nDATA binary_compressed\n" + body),
                            {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  ASSERT_EQ(read->points.size(), 300u);
  EXPECT_EQ(read->points.positions[3 * 149 + 1], 7.0f);
  EXPECT_EQ(read->points.positions[3 * 150 + 2], -3.5f);
  EXPECT_EQ(read->points.positions[3 * 299 + 0], 0.0f);
}

// The same cloud as binary (point records) and as binary_compressed (fields
// one after another), with fields of 1, 2, 4 and 8 bytes so that values
// straddle the decoder's output chunks, a skipped field with COUNT 3, and
// each recognized field decoded straight into its output array.
std::string MixedCloud(int n, bool compressed) {
  const std::string header =
      "FIELDS x label y z rgb normal_x normal_y normal_z fpfh intensity\n"
      "SIZE 4 2 4 4 4 4 4 4 8 1\nTYPE F U F F U F F F F U\nCOUNT 1 1 1 1 1 1 1 1 3 1\n"
      "WIDTH " + std::to_string(n) + "\nHEIGHT 1\nPOINTS " + std::to_string(n) +
      "\nDATA " + (compressed ? "binary_compressed\n" : "binary\n");
  auto value = [](int i, int field) -> double {
    switch (field) {
      case 0: return 0.001 * (i % 7919) - 3;
      case 1: return i % 65536;
      case 2: return 0.25 * (i % 331);
      case 3: return -0.5 * (i % 17);
      case 4: return (i * 2654435761u) & 0xffffffu;
      case 5: return (i % 3) == 0;
      case 6: return (i % 3) == 1;
      case 7: return (i % 3) == 2;
      case 8: return 1e300 * (i % 5);
      default: return i % 256;
    }
  };
  auto append = [&](std::string* out, int i, int field) {
    const double v = value(i, field);
    if (field == 1) Append(out, static_cast<uint16_t>(v));
    else if (field == 4) Append(out, static_cast<uint32_t>(v));
    else if (field == 8) for (int k = 0; k < 3; ++k) Append(out, v);
    else if (field == 9) Append(out, static_cast<uint8_t>(v));
    else Append(out, static_cast<float>(v));
  };
  std::string body;
  if (compressed) {
    for (int field = 0; field < 10; ++field) {
      for (int i = 0; i < n; ++i) append(&body, i, field);
    }
    return header + CompressedBody(body);
  }
  for (int i = 0; i < n; ++i) {
    for (int field = 0; field < 10; ++field) append(&body, i, field);
  }
  return header + body;
}

TEST_F(PcdTest, BinaryCompressedStreamsFieldsIntoTheSameCloudAsBinary) {
  const int n = 30011;  // > 64 KiB per field
  const auto binary = ReadPcd(Write(MixedCloud(n, false), "binary.pcd"), {});
  const auto compressed = ReadPcd(Write(MixedCloud(n, true), "compressed.pcd"), {});
  ASSERT_TRUE(binary.ok()) << binary.status().message();
  ASSERT_TRUE(compressed.ok()) << compressed.status().message();
  ASSERT_EQ(compressed->points.size(), static_cast<size_t>(n));
  EXPECT_EQ(compressed->points.positions, binary->points.positions);
  EXPECT_EQ(compressed->points.normals, binary->points.normals);
  EXPECT_EQ(compressed->points.colors, binary->points.colors);
  EXPECT_EQ(compressed->points.intensities, binary->points.intensities);
  // Spot checks against the values written.
  const int i = 12345;
  EXPECT_EQ(compressed->points.positions[3 * i], static_cast<float>(0.001 * (i % 7919) - 3));
  EXPECT_EQ(compressed->points.positions[3 * i + 1], 0.25f * (i % 331));
  EXPECT_EQ(compressed->points.positions[3 * i + 2], -0.5f * (i % 17));
  const uint32_t rgb = (i * 2654435761u) & 0xffffffu;
  EXPECT_EQ(compressed->points.colors[3 * i], rgb >> 16);
  EXPECT_EQ(compressed->points.colors[3 * i + 2], rgb & 255);
  EXPECT_EQ(compressed->points.normals[3 * i], 1.0f);  // i % 3 == 0: normal (1, 0, 0)
  EXPECT_EQ(compressed->points.normals[3 * i + 2], 0.0f);
  EXPECT_EQ(compressed->points.intensities[i], static_cast<float>((i % 256) / 255.0));
}

TEST_F(PcdTest, BinaryCompressedDoubleCoordinatesWithNoReturnsAndTranslation) {
  // 2 x 2 organized, F8; point 0 is "no return" (x y z NaN), point 2 has only
  // z NaN. VIEWPOINT translates by whole and half meters.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double xs[] = {nan, 652341.125, 652343.0, 652343.0};
  const double ys[] = {nan, 5412345.5, 5412347.0, 5412347.0};
  const double zs[] = {nan, 312.25, nan, 313.0};
  std::string soa;
  for (const double* axis : {xs, ys, zs}) {
    for (int i = 0; i < 4; ++i) Append(&soa, axis[i]);
  }
  const std::string header =
      "FIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nWIDTH 2\nHEIGHT 2\n"
      "VIEWPOINT 10 -0.5 0 1 0 0 0\nPOINTS 4\nDATA binary_compressed\n";
  const auto read = ReadPcd(Write(header + CompressedBody(soa)), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  EXPECT_EQ(read->no_return_points, 2u);
  EXPECT_EQ(read->dropped_points, 0u);
  EXPECT_EQ(cloud.origin, (std::array<double, 3>{652352, 5412346, 313}));
  EXPECT_EQ(cloud.positions, (std::vector<float>{-0.875f, -1, -0.75f, 1, 0.5f, 0}));
  EXPECT_EQ(cloud.stations, (std::vector<std::array<double, 3>>{{10, -0.5, 0}}));
}

TEST_F(PcdTest, BinaryCompressedUnorganizedNanIsAnErrorUnlessDropped) {
  std::string soa;
  for (float v : {0.f, std::numeric_limits<float>::infinity(), 2.f, 0.f, 1.f, 2.f, 0.f, 1.f,
                  std::numeric_limits<float>::quiet_NaN()}) {
    Append(&soa, v);
  }
  const std::string file = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
                           "WIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA binary_compressed\n" +
                           CompressedBody(soa);
  ExpectError(file, "scan.pcd: point 1 has a non-finite coordinate (inf 1 1)");
  ScanReadOptions options;
  options.drop_invalid_points = true;
  const auto read = ReadPcd(Write(file), options);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->dropped_points, 2u);
  EXPECT_EQ(read->no_return_points, 0u);  // unorganized: no grid cells
  EXPECT_EQ(read->points.positions, (std::vector<float>{0, 0, 0}));
}

TEST_F(PcdTest, IdentityViewpointMakesNoStationWhateverTheQuaternionScale) {
  // qw = -2: the identity once normalized; the points stay bit for bit.
  const auto read = ReadPcd(Write("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\n"
                                  "VIEWPOINT 0 0 0 -2 0 0 0\nPOINTS 1\nDATA ascii\n1.5 -2 3\n"),
                            {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.origin, (std::array<double, 3>{0, 0, 0}));
  EXPECT_EQ(read->points.positions, (std::vector<float>{1.5f, -2, 3}));
  EXPECT_TRUE(read->points.stations.empty());
  EXPECT_TRUE(read->points.station_ids.empty());
}

TEST_F(PcdTest, ViewpointPoseIsAppliedAndBecomesTheStation) {
  // qw=0 qx=1: 180 degrees about x, so (x, y, z) -> (x, -y, -z), then + t.
  const auto read = ReadPcd(Write("FIELDS x y z normal_x normal_y normal_z\nSIZE 4 4 4 4 4 4\n"
                                  "TYPE F F F F F F\nWIDTH 2\nHEIGHT 1\n"
                                  "VIEWPOINT 1000 2000 30 0 1 0 0\nPOINTS 2\nDATA ascii\n"
                                  "1 2 3 0 0.6 0.8\n3 4 5 1 0 0\n"),
                            {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  ASSERT_EQ(cloud.size(), 2u);
  const double expected[2][3] = {{1001, 1998, 27}, {1003, 1996, 25}};
  for (int i = 0; i < 2; ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      EXPECT_EQ(cloud.origin[axis] + cloud.positions[3 * i + axis], expected[i][axis]);
    }
  }
  EXPECT_EQ(cloud.origin, (std::array<double, 3>{1002, 1997, 26}));  // bbox center, rounded
  EXPECT_NEAR(cloud.normals[1], -0.6f, 1e-6);
  EXPECT_NEAR(cloud.normals[2], -0.8f, 1e-6);
  EXPECT_NEAR(cloud.normals[3], 1.0f, 1e-6);
  EXPECT_EQ(cloud.stations, (std::vector<std::array<double, 3>>{{1000, 2000, 30}}));
  EXPECT_EQ(cloud.station_ids, (std::vector<uint16_t>{0, 0}));
}

TEST_F(PcdTest, DoubleCoordinatesAreRecentered) {
  std::string file = "FIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nWIDTH 2\nPOINTS 2\nDATA binary\n";
  for (double v : {652341.125, 5412345.5, 312.25, 652343.0, 5412347.0, 313.0}) Append(&file, v);
  const auto read = ReadPcd(Write(file), {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  EXPECT_EQ(cloud.origin, (std::array<double, 3>{652342, 5412346, 313}));
  EXPECT_EQ(cloud.positions, (std::vector<float>{-0.875f, -0.5f, -0.75f, 1, 1, 0}));
}

TEST_F(PcdTest, UnorganizedNanIsAnErrorUnlessDropped) {
  const std::string file =
      "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA ascii\n"
      "0 0 0\nnan 1 1\n2 2 2\n";
  ExpectError(file, "scan.pcd:9: point 1 has a non-finite coordinate (nan 1 1)");
  ScanReadOptions options;
  options.drop_invalid_points = true;
  const auto read = ReadPcd(Write(file), options);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.size(), 2u);
  EXPECT_EQ(read->dropped_points, 1u);
}

TEST_F(PcdTest, FloatIntensityOutsideUnitRangeIsScaledWithAWarning) {
  const auto read = ReadPcd(Write("FIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\n"
                                  "WIDTH 2\nPOINTS 2\nDATA ascii\n0 0 0 100\n1 1 1 400\n"),
                            {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.intensities, (std::vector<float>{0.25f, 1.0f}));
  ASSERT_EQ(read->warnings.size(), 1u);
  EXPECT_THAT(read->warnings[0], HasSubstr("intensity range [0, 400] scaled"));
}

TEST_F(PcdTest, IntensityThatOverflowsFloatBecomesZero) {
  // Found by pcd_fuzz: an F8 intensity beyond float range became inf, then NaN.
  const auto read = ReadPcd(Write("FIELDS x y z intensity\nSIZE 4 4 4 8\nTYPE F F F F\n"
                                  "WIDTH 2\nPOINTS 2\nDATA ascii\n0 0 0 1e300\n1 1 1 2\n"),
                            {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.intensities, (std::vector<float>{0, 1}));
}

// ---------------------------------------------------------------------------
// Malformed input.

const char kXyzHeader[] = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";

TEST_F(PcdTest, ErrorEmptyFile) { ExpectError("", "scan.pcd: empty file"); }

TEST_F(PcdTest, ErrorBadPointsLine) {
  ExpectError(std::string(kXyzHeader) + "WIDTH 1\nHEIGHT 1\nPOINTS many\nDATA ascii\n0 0 0\n",
              "scan.pcd:8: expected 'POINTS <count>', got 'POINTS many'");
}

TEST_F(PcdTest, ErrorSizeListShorterThanFields) {
  ExpectError("FIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nDATA ascii\n0 0 0\n",
              "scan.pcd:2: SIZE has 2 values but FIELDS (line 1) names 3 fields");
}

TEST_F(PcdTest, ErrorUnknownTypeAndBadFloatSize) {
  ExpectError("FIELDS x y z\nSIZE 4 4 4\nTYPE F F Q\nWIDTH 1\nDATA ascii\n0 0 0\n",
              "scan.pcd:3: field 'z': TYPE must be F, I or U, got 'Q'");
  ExpectError("FIELDS x y z\nSIZE 4 4 2\nTYPE F F F\nWIDTH 1\nDATA ascii\n0 0 0\n",
              "scan.pcd:2: field 'z': TYPE F needs SIZE 4 or 8, got 2");
  ExpectError("FIELDS x y z\nSIZE 4 4 4\nTYPE F F U\nWIDTH 1\nDATA ascii\n0 0 0\n",
              "scan.pcd:3: field 'z' must be TYPE F");
}

TEST_F(PcdTest, ErrorUnknownKeywordAndMissingData) {
  ExpectError("ply\nformat ascii 1.0\n", "scan.pcd:1: unknown header keyword 'ply'");
  ExpectError(std::string(kXyzHeader) + "WIDTH 1\nHEIGHT 1\nPOINTS 1\n",
              "scan.pcd:8: missing 'DATA ascii|binary|binary_compressed'");
  ExpectError(std::string(kXyzHeader) + "WIDTH 1\nDATA gzip\n",
              "scan.pcd:7: expected 'DATA ascii', 'DATA binary' or 'DATA binary_compressed'");
}

TEST_F(PcdTest, ErrorMissingCoordinateAndRecognizedFieldWithCount) {
  ExpectError("FIELDS x y\nSIZE 4 4\nTYPE F F\nWIDTH 1\nDATA ascii\n0 0\n",
              "scan.pcd:1: no field 'z' in FIELDS");
  ExpectError("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 2 1\nWIDTH 1\nDATA ascii\n0 0 0 0\n",
              "scan.pcd:4: field 'y' must have COUNT 1, got 2");
}

TEST_F(PcdTest, ErrorPointsDisagreesWithWidthTimesHeight) {
  ExpectError(std::string(kXyzHeader) + "WIDTH 2\nHEIGHT 2\nPOINTS 5\nDATA ascii\n",
              "scan.pcd:8: size mismatch: POINTS 5 but WIDTH 2 x HEIGHT 2 (line 6)");
}

TEST_F(PcdTest, ErrorTruncatedBinaryNamesPointAndByte) {
  std::string file = std::string(kXyzHeader) + "WIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA binary\n";
  const size_t header_bytes = file.size();
  for (int i = 0; i < 8; ++i) Append(&file, 1.0f);  // 2 points and 2/3 of the third
  ExpectError(file, "scan.pcd: truncated: point 2 of 3 at byte " +
                        std::to_string(header_bytes + 24));
}

TEST_F(PcdTest, ErrorAsciiValueCountAndNonNumber) {
  const std::string head = std::string(kXyzHeader) + "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n";
  ExpectError(head + "0 0 0\n1 1\n", "scan.pcd:11: point 1: expected 3 values");
  ExpectError(head + "0 zero 0\n1 1 1\n",
              "scan.pcd:10: point 0: expected a number for field 'y', got 'zero'");
  ExpectError(head + "0 0 0\n", "scan.pcd: truncated: point 1 of 2 (the file ends at line 10)");
  ExpectError(head + "0 0 0\n1 1 1\n2 2 2\n", "scan.pcd:12: unexpected data after the last");
}

TEST_F(PcdTest, ErrorCompressedSizesDisagreeWithPoints) {
  std::string soa;
  for (int i = 0; i < 6; ++i) Append(&soa, 1.0f);  // 2 points
  const std::string head = std::string(kXyzHeader) + "WIDTH 3\nHEIGHT 1\nPOINTS 3\n"
                                                     "DATA binary_compressed\n";
  ExpectError(head + CompressedBody(soa),
              "size mismatch: binary_compressed block at byte " + std::to_string(head.size()) +
                  " declares 24 uncompressed bytes, but POINTS 3 x 12 bytes per point = 36");
}

TEST_F(PcdTest, ErrorCorruptLzfStreams) {
  const std::string head = std::string(kXyzHeader) + "WIDTH 1\nHEIGHT 1\nPOINTS 1\n"
                                                     "DATA binary_compressed\n";
  auto block = [](uint32_t compressed, uint32_t uncompressed, const std::string& lzf) {
    std::string body;
    Append(&body, compressed);
    Append(&body, uncompressed);
    return body + lzf;
  };
  // A back reference as the very first instruction.
  ExpectError(head + block(2, 12, std::string("\x20\x04", 2)),
              "corrupt LZF block: back reference of 5 bytes at output byte 0 reaches before the "
              "start (compressed byte 0, file byte " + std::to_string(head.size() + 8) + ")");
  // A literal run longer than the declared output.
  ExpectError(head + block(14, 12, std::string("\x0c") + std::string(13, 'a')),
              "corrupt LZF block: literal run of 13 bytes at output byte 0 overruns the declared "
              "12 bytes");
  // A stream that stops short.
  ExpectError(head + block(5, 12, std::string("\x03") + std::string(4, 'a')),
              "corrupt LZF block: the block yields 4 of the declared 12 bytes");
  // An instruction cut off by the block's end.
  ExpectError(head + block(4, 12, std::string("\x01zz\xe0", 4)),
              "corrupt LZF block: instruction cut off by the end of the block (compressed byte 3");
  // A block larger than the file.
  ExpectError(head + block(1000, 12, std::string("\x0b") + std::string(12, 'a')),
              "truncated: binary_compressed block of 1000 bytes at byte " +
                  std::to_string(head.size() + 8) + ", but only 13 bytes remain");
  // More output than 88x the input is impossible for LZF.
  ExpectError(std::string(kXyzHeader) + "WIDTH 100\nHEIGHT 1\nPOINTS 100\n"
                                        "DATA binary_compressed\n" +
                  block(2, 1200, std::string("\x00\x00", 2)),
              "2 compressed bytes cannot expand to 1200");
}

// ---------------------------------------------------------------------------
// Shared sample data.

TEST_F(PcdTest, OfficeKinectBinaryCompressed) {
  const std::string data = SharedData();
  if (data.empty()) GTEST_SKIP() << "shared data not found";
  int progress_calls = 0;
  ScanReadOptions options;
  options.progress = [&](double) { ++progress_calls; };
  const auto read = ReadPcd(data + "/office_kinect/office1.pcd", options);
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  EXPECT_EQ(read->format, "pcd binary_compressed");
  EXPECT_EQ(cloud.size(), 254456u);
  EXPECT_EQ(read->no_return_points, 307200u - 254456u);
  EXPECT_EQ(read->dropped_points, 0u);
  EXPECT_GT(progress_calls, 0);
  ASSERT_TRUE(cloud.has_colors());
  EXPECT_FALSE(cloud.has_normals());
  ASSERT_TRUE(Validate(cloud).ok());
  size_t nonzero = 0;
  std::array<size_t, 3> distinct_channel{};
  for (size_t i = 0; i < cloud.size(); ++i) {
    const uint8_t* rgb = &cloud.colors[3 * i];
    nonzero += rgb[0] != 0 || rgb[1] != 0 || rgb[2] != 0;
    for (int c = 0; c < 3; ++c) distinct_channel[c] += rgb[c] != rgb[(c + 1) % 3];
  }
  EXPECT_GT(nonzero, cloud.size() * 9 / 10);
  EXPECT_GT(distinct_channel[0], 0u);  // not a gray image: r, g, b were all decoded
  // VIEWPOINT 0 0 0 0 1 0 0 turns the camera frame (y down, z forward) around
  // x: every point lies in front of the sensor at negative z.
  const Bounds bounds = LocalBounds(cloud);
  EXPECT_LT(bounds.max_m[2], 0);
  // Not the identity, so the pose is kept as the one station.
  EXPECT_EQ(cloud.stations, (std::vector<std::array<double, 3>>{{0, 0, 0}}));
  EXPECT_EQ(cloud.station_ids.size(), cloud.size());
}

// An organized depth frame, 40 x 30 pixels of a pinhole 60 degrees across
// looking down -z, over two depths, moved by `shift`; NaN (no return) at
// every 9th pixel. x y z as F4 (F8 with `doubles`) in DATA `data`, with the
// identity VIEWPOINT (or none, `viewpoint` false).
std::string OrganizedFrame(const std::string& data, const std::array<float, 3>& shift,
                           bool doubles = false, bool viewpoint = true) {
  const int width = 40, height = 30;
  const double focal = 20.0 / std::tan(M_PI / 6);
  std::vector<std::array<float, 3>> points;
  for (int row = 0; row < height; ++row) {
    for (int column = 0; column < width; ++column) {
      const double depth = (row / 6 + column / 8) % 2 == 0 ? 1.5 : 3.2;
      const double x = (column - 19.5) / focal * depth, y = (row - 14.5) / focal * depth;
      points.push_back({float(x) + shift[0], float(y) + shift[1], float(-depth) + shift[2]});
      if ((row * width + column) % 9 == 4)
        points.back()[1] = std::numeric_limits<float>::quiet_NaN();
    }
  }
  std::string body;
  if (data == "ascii") {
    for (const auto& p : points) {
      body += std::isnan(p[1]) ? std::string("nan nan nan\n")
                               : std::to_string(p[0]) + " " + std::to_string(p[1]) + " " +
                                     std::to_string(p[2]) + "\n";
    }
  } else if (data == "binary") {
    for (const auto& p : points)
      for (float v : p) doubles ? Append(&body, double(v)) : Append(&body, v);
  } else {
    std::string soa;
    for (int axis = 0; axis < 3; ++axis)
      for (const auto& p : points) doubles ? Append(&soa, double(p[axis])) : Append(&soa, p[axis]);
    body = CompressedBody(soa);
  }
  return std::string("VERSION 0.7\nFIELDS x y z\n") + (doubles ? "SIZE 8 8 8\n" : "SIZE 4 4 4\n") +
         "TYPE F F F\nCOUNT 1 1 1\nWIDTH 40\n" + "HEIGHT 30\n" +
         (viewpoint ? "VIEWPOINT 0 0 0 1 0 0 0\n" : "") + "POINTS 1200\nDATA " + data + "\n" + body;
}

TEST_F(PcdTest, AnOrganizedFrameInItsSensorsFrameHasItsSensorAtTheOrigin) {
  // The identity VIEWPOINT makes no station by itself (a fused cloud has it
  // too); an image grid swept from the origin does (grid_station.h).
  struct Case {
    std::string data;
    bool doubles = false, viewpoint = true;
  };
  // F8 coordinates are streamed relative to a per-axis origin (1 m away
  // here) and must reach the test as read; a v0.6-style file has no VIEWPOINT.
  for (const Case& c : {Case{"ascii"}, Case{"binary"}, Case{"binary_compressed"},
                        Case{"binary_compressed", true}, Case{"binary", false, false}}) {
    SCOPED_TRACE(c.data + (c.doubles ? " F8" : "") + (c.viewpoint ? "" : " no VIEWPOINT"));
    const std::string data = c.data;
    const auto read = ReadPcd(Write(OrganizedFrame(data, {0, 0, 0}, c.doubles, c.viewpoint)), {});
    ASSERT_TRUE(read.ok()) << read.status().message();
    EXPECT_EQ(read->no_return_points, 133u);
    EXPECT_EQ(read->points.stations, (std::vector<std::array<double, 3>>{{0, 0, 0}}));
    EXPECT_EQ(read->points.station_ids, std::vector<uint16_t>(1200 - 133, 0));
    EXPECT_THAT(read->warnings, ::testing::Contains(HasSubstr(
                                    "organized cloud without a VIEWPOINT pose: its sensor "
                                    "taken at its frame's origin (seen from there")));
    // The same frame moved 25 cm: the origin is not the sensor's.
    const auto moved = ReadPcd(
        Write(OrganizedFrame(data, {0.25f, 0, 0}, c.doubles, c.viewpoint), "moved.pcd"), {});
    ASSERT_TRUE(moved.ok()) << moved.status().message();
    EXPECT_TRUE(moved->points.stations.empty());
    EXPECT_TRUE(moved->points.station_ids.empty());
    EXPECT_THAT(moved->warnings,
                ::testing::Contains(HasSubstr("no sensor station: organized cloud without a "
                                              "VIEWPOINT pose, and its grid does not show its "
                                              "frame's origin as its sensor's (seen from")));
    // The caller sets the stations itself: no test, no station, no warning.
    ScanReadOptions declared;
    declared.infer_stations = false;
    for (const char* file : {"scan.pcd", "moved.pcd"}) {
      const auto read_declared = ReadPcd((dir_ / file).string(), declared);
      ASSERT_TRUE(read_declared.ok()) << read_declared.status().message();
      EXPECT_TRUE(read_declared->points.stations.empty()) << file;
      EXPECT_TRUE(read_declared->warnings.empty()) << file;
      EXPECT_EQ(read_declared->points.size(), 1200u - 133u) << file;
    }
  }
}

TEST_F(PcdTest, LivingroomFragmentBinaryWithNormals) {
  const std::string data = SharedData();
  if (data.empty()) GTEST_SKIP() << "shared data not found";
  const auto read = ReadPcd(data + "/livingroom_fragment/fragment.pcd", {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  EXPECT_EQ(read->format, "pcd binary");
  EXPECT_EQ(cloud.size(), 113662u);
  EXPECT_EQ(read->dropped_points, 0u);
  ASSERT_TRUE(cloud.has_normals());
  ASSERT_TRUE(cloud.has_colors());
  ASSERT_TRUE(Validate(cloud).ok());
  EXPECT_TRUE(read->warnings.empty());
  // VIEWPOINT 0 0 0 1 0 0 0, PCL's default for a fused cloud: no station.
  EXPECT_FALSE(cloud.has_stations());
  EXPECT_TRUE(cloud.stations.empty());
  size_t nonzero = 0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    nonzero += cloud.colors[3 * i] != 0 || cloud.colors[3 * i + 1] != 0 ||
               cloud.colors[3 * i + 2] != 0;
    const float* n = &cloud.normals[3 * i];
    ASSERT_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0f, 1e-3) << "point " << i;
  }
  EXPECT_GT(nonzero, cloud.size() * 3 / 4);  // 100,975 are not black
}

}  // namespace
}  // namespace pb
