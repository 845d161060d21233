#include "stages/geometry/io/ply.h"

#include "stages/geometry/io/grid_sweep_test_util.h"
#include "stages/geometry/testing/test_data.h"
#include "base/testing/durable_write_check.h"
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

namespace pb {
namespace {

using ::testing::HasSubstr;

class PlyTest : public pb::testing::TempDirTest {
 protected:

};

std::string SharedData() { return pb::testing::SharedDataDir(); }

template <typename T>
void AppendRaw(std::string* out, T value, bool big_endian) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(bytes, bytes + sizeof(T));
  out->append(bytes, sizeof(T));
}

TEST_F(PlyTest, PointsRoundTripWithAllAttributes) {
  PointCloud cloud;
  cloud.origin = {652341.0, 5412345.25, 312.5};
  cloud.positions = {0.f, 0.f, 0.f, 1.5f, -2.25f, 3.125f, 1e-4f, 1e4f, -7.f};
  cloud.normals = {0, 0, 1, 0, 1, 0, 0.6f, 0.8f, 0};
  cloud.colors = {0, 0, 0, 255, 128, 1, 10, 20, 30};
  cloud.intensities = {0.f, 0.5f, 1.f};
  cloud.stations = {{652340.5, 5412344.0, 313.75}, {652342.0, 5412346.0, 311.0}};
  cloud.station_ids = {1, 0, 1};
  ASSERT_TRUE(WritePlyPoints(Path("p.ply"), cloud).ok());

  auto read = ReadPlyPoints(Path("p.ply"));
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.origin, cloud.origin);
  EXPECT_EQ(read->points.positions, cloud.positions);
  EXPECT_EQ(read->points.normals, cloud.normals);
  EXPECT_EQ(read->points.colors, cloud.colors);
  EXPECT_EQ(read->points.intensities, cloud.intensities);
  EXPECT_EQ(read->points.stations, cloud.stations);
  EXPECT_EQ(read->points.station_ids, cloud.station_ids);
  EXPECT_EQ(read->report.format, "binary_little_endian");
  EXPECT_EQ(read->report.pointbake_kind, "points");
  EXPECT_EQ(read->report.pointbake_version, 2);

  // The header is what the format documentation promises.
  std::ifstream in(Path("p.ply"));
  std::string line1, line2, line3, line4;
  std::getline(in, line1);
  std::getline(in, line2);
  std::getline(in, line3);
  std::getline(in, line4);
  EXPECT_EQ(line1, "ply");
  EXPECT_EQ(line2, "format binary_little_endian 1.0");
  EXPECT_EQ(line3, "comment pointbake points 2");
  EXPECT_EQ(line4, "comment origin 652341 5412345.25 312.5");
}

TEST_F(PlyTest, PointsWithoutOptionalAttributes) {
  PointCloud cloud;
  cloud.positions = {1, 2, 3};
  ASSERT_TRUE(WritePlyPoints(Path("p.ply"), cloud).ok());
  auto read = ReadPlyPoints(Path("p.ply"));
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.positions, cloud.positions);
  EXPECT_FALSE(read->points.has_normals());
  EXPECT_FALSE(read->points.has_colors());
}

TEST_F(PlyTest, MeshRoundTripWithAllAttributes) {
  Mesh mesh;
  mesh.origin = {1.0, -2.0, 1e6};
  mesh.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  mesh.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  mesh.colors = {255, 0, 0, 0, 255, 0, 0, 0, 255, 9, 9, 9};
  mesh.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  mesh.tangents = {1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, -1, 1, 0, 0, 1};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  ASSERT_TRUE(WritePlyMesh(Path("m.ply"), mesh).ok());

  auto read = ReadPlyMesh(Path("m.ply"));
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->mesh.origin, mesh.origin);
  EXPECT_EQ(read->mesh.positions, mesh.positions);
  EXPECT_EQ(read->mesh.normals, mesh.normals);
  EXPECT_EQ(read->mesh.colors, mesh.colors);
  EXPECT_EQ(read->mesh.uvs, mesh.uvs);
  EXPECT_EQ(read->mesh.tangents, mesh.tangents);
  EXPECT_EQ(read->mesh.indices, mesh.indices);
  EXPECT_EQ(read->report.pointbake_kind, "mesh");
  EXPECT_EQ(read->report.faces_in_file, 2u);

  // Reading a mesh as points keeps the vertices only.
  auto points = ReadPlyPoints(Path("m.ply"));
  ASSERT_TRUE(points.ok()) << points.status().message();
  EXPECT_EQ(points->points.size(), 4u);
  EXPECT_EQ(points->points.colors, mesh.colors);
}

// Per-vertex scalars (MeshLab's `quality`): declared after the mesh's
// attributes, one float each at the end of every vertex record; our reader
// skips them and reads the mesh as without.
TEST_F(PlyTest, MeshWithVertexScalars) {
  Mesh mesh;
  mesh.origin = {1.0, -2.0, 1e6};
  mesh.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0};
  mesh.colors = {255, 0, 0, 0, 255, 0, 0, 0, 255};
  mesh.indices = {0, 1, 2};
  const std::vector<float> quality = {0.5f, 1.5f, -2.25f}, invented = {0, 1, 0};
  const PlyVertexScalar scalars[] = {{"quality", quality}, {"invented", invented}};
  ASSERT_TRUE(WritePlyMeshWithScalars(Path("q.ply"), mesh, scalars).ok());
  std::ifstream in(Path("q.ply"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_THAT(bytes, HasSubstr("property uchar blue\nproperty float quality\nproperty float invented\nelement face 1\n"));
  const size_t body = bytes.find("end_header\n") + 11;
  constexpr size_t kRecord = 3 * 4 + 3 + 2 * 4;
  ASSERT_EQ(bytes.size(), body + 3 * kRecord + 1 + 3 * 4);
  for (size_t v = 0; v < 3; ++v) {
    float q, flag;
    std::memcpy(&q, &bytes[body + v * kRecord + 15], 4);
    std::memcpy(&flag, &bytes[body + v * kRecord + 19], 4);
    EXPECT_EQ(q, quality[v]);
    EXPECT_EQ(flag, invented[v]);
  }
  auto read = ReadPlyMesh(Path("q.ply"));
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->mesh.positions, mesh.positions);
  EXPECT_EQ(read->mesh.colors, mesh.colors);
  EXPECT_EQ(read->mesh.indices, mesh.indices);

  const std::vector<float> two = {1, 2};
  const PlyVertexScalar short_one[] = {{"quality", two}};
  EXPECT_THAT(WritePlyMeshWithScalars(Path("bad.ply"), mesh, short_one).message(),
              HasSubstr("'quality' has 2 values for 3 vertices"));
  const PlyVertexScalar clash[] = {{"red", quality}};
  EXPECT_THAT(WritePlyMeshWithScalars(Path("bad.ply"), mesh, clash).message(), HasSubstr("name 'red'"));
  const PlyVertexScalar spaced[] = {{"a b", quality}};
  EXPECT_THAT(WritePlyMeshWithScalars(Path("bad.ply"), mesh, spaced).message(), HasSubstr("name 'a b'"));
  EXPECT_FALSE(std::filesystem::exists(Path("bad.ply")));
}

TEST_F(PlyTest, WriterRejectsMismatchedAttributes) {
  PointCloud cloud;
  cloud.positions = {1, 2, 3, 4, 5, 6};
  cloud.colors = {1, 2, 3};
  const Status status = WritePlyPoints(Path("bad.ply"), cloud);
  EXPECT_EQ(status.code(), Status::Code::kInvalid);
  EXPECT_THAT(status.message(), HasSubstr("3 color bytes for 2 points"));

  Mesh mesh;
  mesh.positions = {0, 0, 0};
  mesh.indices = {0, 0, 1};
  EXPECT_THAT(WritePlyMesh(Path("bad2.ply"), mesh).message(), HasSubstr("refers to vertex 1"));
}

TEST_F(PlyTest, AsciiWithQuadAndUnknownElementsAndProperties) {
  const std::string path = Write("a.ply",
                                 "ply\n"
                                 "format ascii 1.0\n"
                                 "comment made by hand\n"
                                 "obj_info scanner 7\n"
                                 "element range_grid 2\n"
                                 "property list uchar int vertex_indices\n"
                                 "element vertex 4\n"
                                 "property double x\n"
                                 "property double y\n"
                                 "property double z\n"
                                 "property float confidence\n"
                                 "property float nx\n"
                                 "property float ny\n"
                                 "property float nz\n"
                                 "property ushort red\n"
                                 "property ushort green\n"
                                 "property ushort blue\n"
                                 "property uchar alpha\n"
                                 "property float texture_u\n"
                                 "property float texture_v\n"
                                 "element face 1\n"
                                 "property uchar flags\n"
                                 "property list uchar int vertex_index\n"
                                 "end_header\n"
                                 "1 0\n"
                                 "0\n"
                                 "1000.5 2000.25 10 0.9 0 0 1 65535 0 32768 255 0 0\n"
                                 "1001.5 2000.25 10 0.9 0 0 1 0 65535 0 255 1 0\n"
                                 "1001.5 2001.25 10 0.9 0 0 1 0 0 0 255 1 1\n"
                                 "1000.5 2001.25 10 0.9 0 0 1 257 514 771 255 0 1\n"
                                 "7 4 0 1 2 3\n");
  auto read = ReadPlyMesh(path);
  ASSERT_TRUE(read.ok()) << read.status().message();
  const Mesh& mesh = read->mesh;
  EXPECT_EQ(read->report.format, "ascii");
  ASSERT_EQ(mesh.vertex_count(), 4u);
  // Doubles are re-centered on their bounding-box center rounded to 1 m.
  EXPECT_EQ(mesh.origin, (std::array<double, 3>{1001, 2001, 10}));
  EXPECT_FLOAT_EQ(mesh.positions[0], -0.5f);
  EXPECT_FLOAT_EQ(mesh.positions[1], -0.75f);
  EXPECT_FLOAT_EQ(mesh.positions[2], 0.f);
  EXPECT_FLOAT_EQ(mesh.positions[6], 0.5f);
  EXPECT_FLOAT_EQ(mesh.positions[7], 0.25f);
  EXPECT_EQ(mesh.normals.size(), 12u);
  EXPECT_EQ(mesh.colors, (std::vector<uint8_t>{255, 0, 128, 0, 255, 0, 0, 0, 0, 1, 2, 3}));
  EXPECT_EQ(mesh.uvs, (std::vector<float>{0, 0, 1, 0, 1, 1, 0, 1}));
  EXPECT_TRUE(mesh.tangents.empty());
  // The quad is fan-triangulated.
  EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_EQ(read->report.comments, (std::vector<std::string>{"made by hand", "scanner 7"}));
}

TEST_F(PlyTest, FloatColorsAndCrLf) {
  const std::string path = Write("c.ply",
                                 "ply\r\nformat ascii 1.0\r\nelement vertex 2\r\n"
                                 "property float x\r\nproperty float y\r\nproperty float z\r\n"
                                 "property float red\r\nproperty float green\r\nproperty float blue\r\n"
                                 "end_header\r\n"
                                 "1 2 3 1.0 0.5 0\r\n"
                                 "4 5 6 2.0 -1 0.2\r\n");
  auto read = ReadPlyPoints(path);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.origin, (std::array<double, 3>{0, 0, 0}));
  EXPECT_EQ(read->points.positions, (std::vector<float>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(read->points.colors, (std::vector<uint8_t>{255, 128, 0, 255, 0, 51}));
}

std::string BigEndianFile(bool truncate) {
  std::string data =
      "ply\n"
      "format binary_big_endian 1.0\n"
      "element vertex 3\n"
      "property float x\n"
      "property float y\n"
      "property float z\n"
      "property int16 extra\n"
      "property uchar red\n"
      "property uchar green\n"
      "property uchar blue\n"
      "element face 1\n"
      "property list uchar uint vertex_indices\n"
      "end_header\n";
  for (int i = 0; i < 3; ++i) {
    AppendRaw<float>(&data, 1.5f * i, true);
    AppendRaw<float>(&data, -2.0f, true);
    AppendRaw<float>(&data, 1000.25f, true);
    AppendRaw<int16_t>(&data, -7, true);
    data += static_cast<char>(10 * i);
    data += static_cast<char>(20);
    data += static_cast<char>(200);
  }
  data += static_cast<char>(3);
  AppendRaw<uint32_t>(&data, 2, true);
  AppendRaw<uint32_t>(&data, 1, true);
  AppendRaw<uint32_t>(&data, 0, true);
  if (truncate) data.resize(data.size() - 30);
  return data;
}

TEST_F(PlyTest, BinaryBigEndian) {
  auto read = ReadPlyMesh(Write("be.ply", BigEndianFile(false)));
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->report.format, "binary_big_endian");
  EXPECT_EQ(read->mesh.positions,
            (std::vector<float>{0, -2, 1000.25f, 1.5f, -2, 1000.25f, 3, -2, 1000.25f}));
  EXPECT_EQ(read->mesh.colors, (std::vector<uint8_t>{0, 20, 200, 10, 20, 200, 20, 20, 200}));
  EXPECT_EQ(read->mesh.indices, (std::vector<uint32_t>{2, 1, 0}));
}

TEST_F(PlyTest, TruncatedBinaryNamesElementAndByte) {
  // Vertices are 17 bytes, the face 13: cutting 30 of 64 bytes leaves 34,
  // so vertex 2 (at 34) is the first incomplete record.
  const std::string data = BigEndianFile(true);
  const size_t header_bytes = data.find("end_header\n") + 11;
  auto read = ReadPlyPoints(Write("t.ply", data));
  ASSERT_FALSE(read.ok());
  EXPECT_EQ(read.status().code(), Status::Code::kCorrupt);
  EXPECT_THAT(read.status().message(),
              HasSubstr("t.ply: truncated: vertex 2 of 3 at byte " + std::to_string(header_bytes + 34)));
}

TEST_F(PlyTest, TruncatedAsciiNamesLine) {
  const std::string path = Write("t.ply",
                                 "ply\nformat ascii 1.0\nelement vertex 3\n"
                                 "property float x\nproperty float y\nproperty float z\nend_header\n"
                                 "1 2 3\n4 5 6\n7 8\n");
  auto read = ReadPlyPoints(path);
  ASSERT_FALSE(read.ok());
  EXPECT_THAT(read.status().message(), HasSubstr("t.ply:10: truncated: vertex 2 of 3"));
}

TEST_F(PlyTest, CountMismatchExtraData) {
  std::string data = BigEndianFile(false);
  data += "garbage bytes";
  auto read = ReadPlyPoints(Write("x.ply", data));
  ASSERT_FALSE(read.ok());
  EXPECT_THAT(read.status().message(), HasSubstr("13 bytes of unexpected data after the last element"));
  EXPECT_THAT(read.status().message(), HasSubstr("vertex 3, face 1"));

  const std::string ascii = Write("y.ply",
                                  "ply\nformat ascii 1.0\nelement vertex 1\n"
                                  "property float x\nproperty float y\nproperty float z\nend_header\n"
                                  "1 2 3\n4 5 6\n");
  auto read_ascii = ReadPlyPoints(ascii);
  ASSERT_FALSE(read_ascii.ok());
  EXPECT_THAT(read_ascii.status().message(), HasSubstr("y.ply:9: unexpected data '4' after the last element"));
}

TEST_F(PlyTest, HeaderErrorsNameTheLine) {
  struct Case {
    std::string contents;
    std::string expected;
  };
  const Case cases[] = {
      {"", ": empty file"},
      {"PK\x03\x04zip", ":1: expected 'ply'"},
      {"ply\nformat binary 1.0\n", ":2: expected 'format ascii 1.0'"},
      {"ply\nformat ascii 1.0\nelement vertex many\n", ":3: expected 'element <name> <count>'"},
      {"ply\nformat ascii 1.0\nproperty float x\n", ":3: 'property' before any 'element'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty half x\n", ":4: unknown property type 'half'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", ":4: missing 'end_header'"},
      {"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nend_header\n",
       ":3: element 'vertex' has no property 'z'"},
      {"ply\nformat ascii 1.0\nelement face 0\nend_header\n", ": no 'vertex' element"},
      {"ply\nformat ascii 1.0\ncomment pointbake points 3\nend_header\n",
       ":3: pointbake points format version 3; this build reads version 2"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n1 2 abc\n",
       ":8: vertex 0: expected a number for 'z', got 'abc'"},
  };
  int index = 0;
  for (const Case& c : cases) {
    // Appended piecewise: "h" + to_string(...) trips GCC 12's -Wrestrict.
    std::string name = "h";
    name += std::to_string(index++);
    name += ".ply";
    auto read = ReadPlyPoints(Write(name, c.contents));
    ASSERT_FALSE(read.ok()) << name;
    EXPECT_THAT(read.status().message(), HasSubstr(name + c.expected)) << name;
  }
  auto missing = ReadPlyPoints(Path("missing.ply"));
  EXPECT_EQ(missing.status().code(), Status::Code::kNotFound);
}

TEST_F(PlyTest, NonFiniteCoordinatesFailOrAreDropped) {
  const std::string path = Write("n.ply",
                                 "ply\nformat ascii 1.0\nelement vertex 4\n"
                                 "property float x\nproperty float y\nproperty float z\n"
                                 "element face 2\nproperty list uchar int vertex_indices\n"
                                 "end_header\n"
                                 "0 0 0\n1 0 0\nnan 1 0\n0 1 inf\n"
                                 "3 0 1 3\n3 0 1 2\n");
  auto failed = ReadPlyMesh(path);
  ASSERT_FALSE(failed.ok());
  EXPECT_THAT(failed.status().message(), HasSubstr("n.ply:12: vertex 2 has a non-finite coordinate"));

  PlyReadOptions options;
  options.drop_invalid_points = true;
  auto dropped = ReadPlyMesh(path, options);
  ASSERT_TRUE(dropped.ok()) << dropped.status().message();
  EXPECT_EQ(dropped->report.dropped_points, 2u);
  EXPECT_EQ(dropped->report.dropped_triangles, 2u);
  EXPECT_EQ(dropped->mesh.positions, (std::vector<float>{0, 0, 0, 1, 0, 0}));
  EXPECT_TRUE(dropped->mesh.indices.empty());

  // Binary: the error names the byte.
  std::string binary =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\n"
      "property float x\nproperty float y\nproperty float z\nend_header\n";
  const size_t header_bytes = binary.size();
  for (float v : {1.f, 2.f, 3.f, 4.f, std::numeric_limits<float>::quiet_NaN(), 6.f}) {
    AppendRaw<float>(&binary, v, false);
  }
  auto failed_binary = ReadPlyPoints(Write("nb.ply", binary));
  ASSERT_FALSE(failed_binary.ok());
  EXPECT_THAT(failed_binary.status().message(),
              HasSubstr("vertex 1 has a non-finite coordinate (4 nan 6)"));
  EXPECT_THAT(failed_binary.status().message(), HasSubstr("at byte " + std::to_string(header_bytes + 12)));
  auto dropped_binary = ReadPlyPoints(Path("nb.ply"), options);
  ASSERT_TRUE(dropped_binary.ok());
  EXPECT_EQ(dropped_binary->points.size(), 1u);
  EXPECT_EQ(dropped_binary->report.dropped_points, 1u);
}

TEST_F(PlyTest, FaceIndexOutOfRange) {
  const std::string path = Write("f.ply",
                                 "ply\nformat ascii 1.0\nelement vertex 3\n"
                                 "property float x\nproperty float y\nproperty float z\n"
                                 "element face 1\nproperty list uchar int vertex_indices\n"
                                 "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  auto read = ReadPlyMesh(path);
  ASSERT_FALSE(read.ok());
  EXPECT_THAT(read.status().message(),
              HasSubstr("f.ply:13: face 0 refers to vertex 3 but the file has 3 vertices"));
}

TEST_F(PlyTest, ProgressReachesOne) {
  PointCloud cloud;
  cloud.positions.assign(3 * 200000, 1.0f);
  ASSERT_TRUE(WritePlyPoints(Path("big.ply"), cloud).ok());
  std::vector<double> fractions;
  PlyReadOptions options;
  options.progress = [&](double fraction) { fractions.push_back(fraction); };
  auto read = ReadPlyPoints(Path("big.ply"), options);
  ASSERT_TRUE(read.ok());
  EXPECT_EQ(read->points.size(), 200000u);
  ASSERT_GE(fractions.size(), 2u);
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
}

TEST_F(PlyTest, StanfordBunny) {
  const std::string data = SharedData();
  if (data.empty()) GTEST_SKIP() << "shared data not found";
  const std::string path = data + "/bunny/bun_zipper.ply";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not found";
  auto read = ReadPlyPoints(path);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.size(), 35947u);
  EXPECT_FALSE(read->points.has_colors());
  EXPECT_EQ(read->report.faces_in_file, 69451u);
  const Bounds bounds = AbsoluteBounds(read->points);
  EXPECT_NEAR(bounds.min_m[0], -0.0947, 1e-3);
  EXPECT_NEAR(bounds.max_m[1], 0.1877, 1e-3);

  auto mesh = ReadPlyMesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_EQ(mesh->mesh.face_count(), 69451u);
}

}  // namespace
}  // namespace pb

namespace pb {
namespace {

// A failed write (full disk, I/O error) keeps the earlier file and leaves no
// file that looks complete.
TEST(PlyDurableWriteTest, FailedWritesKeepTheEarlierFile) {
  Mesh older;
  older.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0};
  older.indices = {0, 1, 2};
  Mesh newer = older;
  newer.positions[0] = 0.5f;
  newer.colors = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  testing::TempDir meshes;
  ASSERT_TRUE(WritePlyMesh(meshes.Path("mesh.ply"), older).ok());
  EXPECT_EQ(testing::ExpectFailedWritesKeepEarlierFiles(meshes.path(), [&](Env* env) {
              return WritePlyMesh(meshes.Path("mesh.ply"), newer, env);
            }),
            1);

  PointCloud older_cloud, newer_cloud;
  older_cloud.positions = {0, 0, 0, 1, 2, 3};
  newer_cloud.positions = {4, 5, 6, 7, 8, 9};
  newer_cloud.normals = {0, 0, 1, 0, 1, 0};
  testing::TempDir clouds;
  ASSERT_TRUE(WritePlyPoints(clouds.Path("points.ply"), older_cloud).ok());
  EXPECT_EQ(testing::ExpectFailedWritesKeepEarlierFiles(clouds.path(), [&](Env* env) {
              return WritePlyPoints(clouds.Path("points.ply"), newer_cloud, env);
            }),
            1);
}

TEST(PlyStationsTest, StationIndexBeyondTheListIsAnError) {
  testing::TempDir dir;
  const std::string path = dir.Path("s.ply");
  std::ofstream(path) << "ply\nformat ascii 1.0\ncomment station 0 1 2 3\nelement vertex 2\n"
                         "property float x\nproperty float y\nproperty float z\n"
                         "property ushort station\nend_header\n0 0 0 0\n1 1 1 3\n";
  auto read = ReadPlyPoints(path);
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.status().message().find("vertex 1 names station 3 but the header lists 1"),
            std::string::npos)
      << read.status().message();
  std::ofstream(path) << "ply\nformat ascii 1.0\ncomment station 1 1 2 3\nelement vertex 0\n"
                         "property float x\nproperty float y\nproperty float z\nend_header\n";
  auto misnumbered = ReadPlyPoints(path);
  ASSERT_FALSE(misnumbered.ok());
  EXPECT_NE(misnumbered.status().message().find("s.ply:3: expected 'comment station 0 X Y Z'"),
            std::string::npos)
      << misnumbered.status().message();
}

// A vertex property of the fast-path tests: PLY type name, property name and
// the value of vertex k (representable in the type).
struct TestProperty {
  std::string type, name;
  std::function<double(int)> value;
};

void AppendValue(std::string* out, const std::string& type, double value, bool big_endian) {
  if (type == "char") AppendRaw<int8_t>(out, static_cast<int8_t>(value), big_endian);
  if (type == "uchar") AppendRaw<uint8_t>(out, static_cast<uint8_t>(value), big_endian);
  if (type == "short") AppendRaw<int16_t>(out, static_cast<int16_t>(value), big_endian);
  if (type == "ushort") AppendRaw<uint16_t>(out, static_cast<uint16_t>(value), big_endian);
  if (type == "int") AppendRaw<int32_t>(out, static_cast<int32_t>(value), big_endian);
  if (type == "uint") AppendRaw<uint32_t>(out, static_cast<uint32_t>(value), big_endian);
  if (type == "float") AppendRaw<float>(out, static_cast<float>(value), big_endian);
  if (type == "double") AppendRaw<double>(out, value, big_endian);
}

// The same vertices (and a face per 3 vertices) as "ascii",
// "binary_little_endian" or "binary_big_endian".
std::string FastPathFile(const std::string& format, const std::vector<TestProperty>& properties,
                         int vertices) {
  std::string data = "ply\nformat " + format + " 1.0\ncomment station 0 1 2 3\n"
                     "comment station 1 4 5 6\nelement vertex " + std::to_string(vertices) + "\n";
  for (const TestProperty& property : properties) {
    data += "property " + property.type + " " + property.name + "\n";
  }
  const int faces = vertices / 3;
  data += "element face " + std::to_string(faces) +
          "\nproperty list uchar int vertex_indices\nend_header\n";
  const bool big_endian = format == "binary_big_endian";
  for (int k = 0; k < vertices; ++k) {
    for (const TestProperty& property : properties) {
      if (format == "ascii") {
        char text[40];
        std::snprintf(text, sizeof text, "%.17g ", property.value(k));
        data += text;
      } else {
        AppendValue(&data, property.type, property.value(k), big_endian);
      }
    }
    if (format == "ascii") data += "\n";
  }
  for (int f = 0; f < faces; ++f) {
    if (format == "ascii") {
      data += "3 " + std::to_string(3 * f) + " " + std::to_string(3 * f + 1) + " " +
              std::to_string(3 * f + 2) + "\n";
    } else {
      data += static_cast<char>(3);
      for (int c = 0; c < 3; ++c) AppendRaw<int32_t>(&data, 3 * f + c, big_endian);
    }
  }
  return data;
}

// A structured scan as converters write it (row and col per point, no
// station): grid_sweep_test_util.h's sweep from `station`, 60 rows by 40
// columns, column-major; float, double (re-centred) or ascii. With
// `named`, the file also names that station (a comment and a ushort
// `station` 0 per point).
std::string SweptGridFile(const std::string& format, const std::string& coordinate,
                          const double station[3], bool named = false) {
  const int rows = 60, columns = 40;
  char comment[120] = "";
  if (named) {
    std::snprintf(comment, sizeof comment, "comment station 0 %.17g %.17g %.17g\n", station[0],
                  station[1], station[2]);
  }
  std::string data = "ply\nformat " + format + " 1.0\ncomment converted from E57\n" + comment +
                     "element vertex " + std::to_string(rows * columns) + "\nproperty " +
                     coordinate + " x\nproperty " + coordinate + " y\nproperty " + coordinate +
                     " z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n" +
                     "property float intensity\n" + (named ? "property ushort station\n" : "") +
                     "property int row\nproperty int col\nend_header\n";
  for (int column = 0; column < columns; ++column) {
    for (int row = 0; row < rows; ++row) {
      const std::array<double, 3> p = pb::testing::SweptPoint(station, row, column);
      if (format == "ascii") {
        char text[160];
        std::snprintf(text, sizeof text, "%.9g %.9g %.9g 10 20 30 0.5 %s%d %d\n", p[0], p[1],
                      p[2], named ? "0 " : "", row, column);
        data += text;
        continue;
      }
      for (double v : p) AppendValue(&data, coordinate, v, /*big_endian=*/false);
      data += std::string("\x0a\x14\x1e", 3);
      AppendRaw<float>(&data, 0.5f, false);
      if (named) AppendRaw<uint16_t>(&data, 0, false);
      AppendRaw<int32_t>(&data, row, false);
      AppendRaw<int32_t>(&data, column, false);
    }
  }
  return data;
}

TEST(PlyStationsTest, AStructuredScanSweptFromItsOriginGetsItsScannerThere) {
  testing::TempDir dir;
  const double origin[3] = {0, 0, 0};
  for (const auto& [format, coordinate] :
       {std::pair<std::string, std::string>{"binary_little_endian", "float"},
        {"binary_little_endian", "double"},
        {"ascii", "float"}}) {
    SCOPED_TRACE(format + " " + coordinate);
    const std::string path = dir.Path("grid.ply");
    std::ofstream(path, std::ios::binary) << SweptGridFile(format, coordinate, origin);
    auto read = ReadPlyPoints(path);
    ASSERT_TRUE(read.ok()) << read.status().message();
    EXPECT_EQ(read->points.size(), 2400u);
    EXPECT_EQ(read->points.stations, (std::vector<std::array<double, 3>>{{0, 0, 0}}));
    EXPECT_EQ(read->points.station_ids, std::vector<uint16_t>(2400, 0));
    EXPECT_TRUE(Validate(read->points).ok());
    ASSERT_EQ(read->report.warnings.size(), 1u);
    EXPECT_THAT(read->report.warnings[0],
                HasSubstr("structured scan (row and column per point) without a station: its "
                          "scanner taken at its frame's origin (seen from there, 100.0 % of the"));
  }
  // The same sweep with its registration baked in (the scanner 40 cm off):
  // no station, and the warning says how to give one.
  const double moved[3] = {0.4, -0.2, 0.1};
  const std::string path = dir.Path("moved.ply");
  std::ofstream(path, std::ios::binary) << SweptGridFile("binary_little_endian", "float", moved);
  auto read = ReadPlyPoints(path);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_FALSE(read->points.has_stations());
  ASSERT_EQ(read->report.warnings.size(), 1u);
  EXPECT_THAT(read->report.warnings[0],
              HasSubstr("no scanner station: structured scan (row and column per point) without "
                        "a station, and its grid does not show its frame's origin as its "
                        "scanner's"));
  EXPECT_THAT(read->report.warnings[0], HasSubstr("io.read_points `station` can declare"));
  // The caller sets the stations itself: no test, no station, no warning.
  PlyReadOptions declared_by_caller;
  declared_by_caller.infer_stations = false;
  for (const char* file : {"grid.ply", "moved.ply"}) {
    auto caller = ReadPlyPoints(dir.Path(file), declared_by_caller);
    ASSERT_TRUE(caller.ok()) << caller.status().message();
    EXPECT_FALSE(caller->points.has_stations()) << file;
    EXPECT_TRUE(caller->report.warnings.empty()) << file;
    EXPECT_EQ(caller->points.size(), 2400u) << file;
  }
  // Stations named in the file win: no grid test, no warning.
  for (const std::string format : {"ascii", "binary_little_endian"}) {
    SCOPED_TRACE(format);
    std::ofstream(path, std::ios::binary) << SweptGridFile(format, "float", moved, /*named=*/true);
    auto declared = ReadPlyPoints(path);
    ASSERT_TRUE(declared.ok()) << declared.status().message();
    EXPECT_EQ(declared->points.stations, (std::vector<std::array<double, 3>>{{0.4, -0.2, 0.1}}));
    EXPECT_TRUE(declared->report.warnings.empty());
  }
  // A mesh's reader does not look for a scanner.
  std::ofstream(path, std::ios::binary) << SweptGridFile("binary_little_endian", "float", origin);
  auto mesh = ReadPlyMesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_TRUE(mesh->report.warnings.empty());
}

// The shared pump scan as its decoded PLY (row and col, no pose): its
// scanner at the origin, as the E57 reader finds from the same grid.
TEST(PlyStationsTest, ThePumpScansGridPutsItsScannerAtItsOrigin) {
  const std::string data = SharedData();
  const std::string path = data + "/pump_e57/pumpA.ply";
  if (data.empty() || !std::filesystem::exists(path)) GTEST_SKIP() << path << " not found";
  auto read = ReadPlyPoints(path);
  ASSERT_TRUE(read.ok()) << read.status().message();
  const PointCloud& cloud = read->points;
  EXPECT_EQ(cloud.size(), 155201u);
  EXPECT_TRUE(cloud.has_colors());
  ASSERT_TRUE(cloud.has_intensities());
  EXPECT_EQ(cloud.stations, (std::vector<std::array<double, 3>>{{0, 0, 0}}));
  EXPECT_EQ(cloud.station_ids, std::vector<uint16_t>(cloud.size(), 0));
  ASSERT_EQ(read->report.warnings.size(), 1u);
  EXPECT_THAT(read->report.warnings[0],
              HasSubstr("its scanner taken at its frame's origin (seen from there, 99.9 % of the "
                        "303204 steps"));
  EXPECT_TRUE(Validate(cloud).ok());
}

// Every scalar type, both byte orders, an unread property, a role given twice
// (the last wins), NaN coordinates in several blocks: the binary fast path
// must give exactly what the generic ascii path gives.
TEST_F(PlyTest, BinaryFastPathMatchesAsciiForEveryTypeAndByteOrder) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const std::string coordinate_type : {"float", "double", "int"}) {
    const bool has_nan = coordinate_type != "int";  // integers cannot hold NaN
    auto invalid = [&](int k) { return has_nan && (k == 1234 || k == 4097 || k == 4098); };
    const std::vector<TestProperty> properties = {
        {"uchar", "flags", [](int k) { return k % 7; }},
        {coordinate_type, "x",
         [&](int k) {
           if (invalid(k)) return nan;
           if (coordinate_type == "double") return 652341.25 + 0.5 * k;
           return coordinate_type == "int" ? (k % 1000) - 100.0 : 0.5 * (k % 1000) - 100;
         }},
        {coordinate_type, "y", [](int k) { return (k % 37) * 2.0; }},
        {coordinate_type == "int" ? "short" : "float", "z", [](int k) { return -(k % 11); }},
        {"double", "nx", [](int k) { return 0.001 * k; }},
        {"char", "ny", [](int k) { return (k % 200) - 100; }},
        {"uint", "nz", [](int k) { return 4000000000.0 - k; }},
        {"ushort", "red", [](int k) { return (k * 97) % 65536; }},
        {"float", "green", [](int k) { return (k % 9) * 0.125 - 0.125; }},
        {"uchar", "blue", [](int k) { return k % 256; }},
        {"short", "s", [](int k) { return -k; }},
        {"float", "t", [](int k) { return k * 0.25; }},
        {"float", "u", [](int k) { return k * 0.75; }},  // wins over "s"
        {"double", "intensity", [](int k) { return (k % 100) / 100.0; }},
        {"uchar", "station", [](int k) { return k % 2; }},
        {"int", "extra", [](int k) { return k; }},
    };
    const int n = 5000;  // several fast-path blocks
    Write("a.ply", FastPathFile("ascii", properties, n));
    Write("le.ply", FastPathFile("binary_little_endian", properties, n));
    Write("be.ply", FastPathFile("binary_big_endian", properties, n));
    for (bool drop : {false, true}) {
      SCOPED_TRACE(coordinate_type + (drop ? " dropping" : ""));
      PlyReadOptions options;
      options.drop_invalid_points = drop;
      auto ascii = ReadPlyMesh(Path("a.ply"), options);
      auto ascii_points = ReadPlyPoints(Path("a.ply"), options);
      if (!drop && has_nan) {
        ASSERT_FALSE(ascii.ok());
        for (const std::string name : {"le.ply", "be.ply"}) {
          auto binary = ReadPlyPoints(Path(name), options);
          ASSERT_FALSE(binary.ok());
          EXPECT_THAT(binary.status().message(),
                      HasSubstr(name + ": vertex 1234 has a non-finite coordinate (nan"));
        }
        continue;
      }
      ASSERT_TRUE(ascii.ok()) << ascii.status().message();
      ASSERT_TRUE(ascii_points.ok()) << ascii_points.status().message();
      const size_t dropped = has_nan ? 3 : 0;
      EXPECT_EQ(ascii->report.dropped_points, dropped);
      EXPECT_EQ(ascii->report.dropped_triangles, dropped);  // faces 411, 1365, 1366
      EXPECT_EQ(ascii->mesh.positions.size(), 3 * (n - dropped));
      for (const std::string name : {"le.ply", "be.ply"}) {
        auto binary = ReadPlyMesh(Path(name), options);
        ASSERT_TRUE(binary.ok()) << binary.status().message();
        EXPECT_EQ(binary->mesh.origin, ascii->mesh.origin);
        EXPECT_EQ(binary->mesh.positions, ascii->mesh.positions);
        EXPECT_EQ(binary->mesh.normals, ascii->mesh.normals);
        EXPECT_EQ(binary->mesh.colors, ascii->mesh.colors);
        EXPECT_EQ(binary->mesh.uvs, ascii->mesh.uvs);
        EXPECT_EQ(binary->mesh.indices, ascii->mesh.indices);
        EXPECT_EQ(binary->report.dropped_points, dropped);
        EXPECT_EQ(binary->report.dropped_triangles, dropped);
        auto points = ReadPlyPoints(Path(name), options);
        ASSERT_TRUE(points.ok()) << points.status().message();
        EXPECT_EQ(points->points.positions, ascii_points->points.positions);
        EXPECT_EQ(points->points.intensities, ascii_points->points.intensities);
        EXPECT_EQ(points->points.station_ids, ascii_points->points.station_ids);
      }
      // Spot checks of the oracle itself.
      EXPECT_EQ(ascii_points->points.station_ids[1235], has_nan ? 0 : 1);  // vertex 1236 if shifted
      EXPECT_EQ(ascii->mesh.uvs[0], 0.f);
      EXPECT_EQ(ascii->mesh.uvs[2], 0.75f);  // "u" of vertex 1
      EXPECT_EQ(ascii->mesh.colors[3 * 2 + 1], 32);  // green 0.125 * 255 = 31.875
    }
  }
}

TEST_F(PlyTest, BinaryFastPathErrorsNameVertexAndByte) {
  const std::vector<TestProperty> properties = {
      {"float", "x", [](int k) { return k == 3001 ? std::numeric_limits<double>::infinity() : k; }},
      {"float", "y", [](int) { return 1; }},
      {"float", "z", [](int) { return 2; }},
      {"ushort", "station", [](int k) { return k == 2000 || k == 3001 ? 7 : 0; }},
  };
  std::string data = FastPathFile("binary_little_endian", properties, 5000);
  const size_t header_bytes = data.find("end_header\n") + 11;
  const size_t record = 14;
  auto read = ReadPlyPoints(Write("s.ply", data));
  ASSERT_FALSE(read.ok());
  EXPECT_THAT(read.status().message(),
              HasSubstr("s.ply: vertex 2000 names station 7 but the header lists 2 (at byte " +
                        std::to_string(header_bytes + 2000 * record) + ")"));

  // A non-finite coordinate is reported before a bad station of the same vertex.
  data = FastPathFile("binary_little_endian",
                      {properties[0], properties[1], properties[2],
                       {"ushort", "station", [](int k) { return k == 3001 ? 7 : 0; }}},
                      5000);
  auto nonfinite = ReadPlyPoints(Write("n.ply", data));
  ASSERT_FALSE(nonfinite.ok());
  EXPECT_THAT(nonfinite.status().message(),
              HasSubstr("n.ply: vertex 3001 has a non-finite coordinate (inf 1 2)"));
  EXPECT_THAT(nonfinite.status().message(),
              HasSubstr("(at byte " + std::to_string(header_bytes + 3001 * record) + ")"));

  // Cut inside vertex 3000: its byte offset, whatever the block size.
  data.resize(header_bytes + 3000 * record + 5);
  auto truncated = ReadPlyPoints(Write("t.ply", data));
  ASSERT_FALSE(truncated.ok());
  EXPECT_THAT(truncated.status().message(),
              HasSubstr("t.ply: truncated: vertex 3000 of 5000 at byte " +
                        std::to_string(header_bytes + 3000 * record)));
  // A count far beyond the file fails as truncation, without a huge allocation.
  std::string huge = data;
  huge.replace(huge.find("vertex 5000"), 11, "vertex 999999999999");
  const size_t huge_header = huge.find("end_header\n") + 11;
  auto corrupt = ReadPlyPoints(Write("h.ply", huge));
  ASSERT_FALSE(corrupt.ok());
  EXPECT_THAT(corrupt.status().message(),
              HasSubstr("h.ply: truncated: vertex 3000 of 999999999999 at byte " +
                        std::to_string(huge_header + 3000 * record)));
}

}  // namespace
}  // namespace pb
