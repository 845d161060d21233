#include "stages/geometry/io/obj.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "stages/geometry/core/tangents.h"
#include "stages/geometry/testing/test_data.h"
#include "base/testing/durable_write_check.h"

namespace pb {
namespace {

// An n x n grid over the unit square, far from the origin, with uvs,
// colors and normals.
Mesh Grid(int n) {
  Mesh mesh;
  mesh.origin = {456789.125, 5432109.5, 312.75};
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      mesh.positions.insert(mesh.positions.end(), {float(i) / n, float(j) / n, 0.001f * float(i * j)});
      mesh.uvs.insert(mesh.uvs.end(), {float(i) / n, float(j) / n});
      mesh.colors.insert(mesh.colors.end(), {uint8_t(i * 255 / n), uint8_t(j * 255 / n), 3});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
    }
  }
  mesh.normals = ComputeVertexNormals(mesh);
  return mesh;
}

const std::vector<uint8_t> kFakePngColor = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n', 1, 2, 3};
const std::vector<uint8_t> kFakePngNormal = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n', 4, 5};

class ObjTest : public testing::TempDirTest {};

TEST_F(ObjTest, TexturedMeshRoundTrips) {
  const Mesh mesh = Grid(6);
  ObjWriteOptions options;
  options.name = "wall";
  options.base_color_png = kFakePngColor;
  options.normal_png = kFakePngNormal;
  ObjWriteReport report;
  const std::string path = Path("model.obj");
  ASSERT_TRUE(WriteObj(path, mesh, options, &report).ok());
  EXPECT_EQ(report.files, (std::vector<std::string>{path, Path("model.mtl"), Path("color.png"),
                                                     Path("normal.png")}));
  uint64_t bytes = 0;
  for (const auto& file : report.files) bytes += std::filesystem::file_size(file);
  EXPECT_EQ(report.bytes, bytes);
  for (const auto& entry : std::filesystem::directory_iterator(dir_)) {
    EXPECT_NE(entry.path().extension(), ".tmp");
  }

  auto model = ReadObj(path);
  ASSERT_TRUE(model.ok()) << model.status().message();
  const Mesh& back = model->mesh;
  EXPECT_EQ(model->material, "wall");
  EXPECT_EQ(back.origin, mesh.origin);
  EXPECT_EQ(back.positions, mesh.positions);  // absolute doubles minus the origin, exactly
  EXPECT_EQ(back.uvs, mesh.uvs);
  EXPECT_EQ(back.normals, mesh.normals);
  EXPECT_EQ(back.colors, mesh.colors);
  EXPECT_EQ(back.indices, mesh.indices);
  EXPECT_EQ(model->base_color_png, kFakePngColor);
  EXPECT_EQ(model->normal_png, kFakePngNormal);
}

// The four files of a textured model: a failure at any of them keeps the
// whole earlier set (nothing is renamed before every file is synced).
TEST_F(ObjTest, FailedWritesKeepTheEarlierFiles) {
  ObjWriteOptions textured;
  textured.base_color_png = kFakePngColor;
  textured.normal_png = kFakePngNormal;
  ASSERT_TRUE(WriteObj(Path("model.obj"), Grid(2), textured).ok());
  ObjWriteOptions other = textured;
  other.name = "other";
  other.base_color_png = kFakePngNormal;
  other.normal_png = kFakePngColor;
  EXPECT_EQ(testing::ExpectFailedWritesKeepEarlierFiles(dir_, [&](Env* env) {
              return WriteObj(Path("model.obj"), Grid(3), other, nullptr, env);
            }),
            4);
}

TEST_F(ObjTest, CoordinatesAreAbsolute) {
  const Mesh mesh = Grid(1);
  ASSERT_TRUE(WriteObj(Path("m.obj"), mesh, ObjWriteOptions{}).ok());
  std::ifstream in(Path("m.obj"));
  std::string line;
  bool found = false;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) {
      EXPECT_EQ(line.substr(0, 31), "v 456789.125 5432109.5 312.75 0") << line;
      found = true;
      break;
    }
  }
  EXPECT_TRUE(found);
  // A file without the origin comment gets its box center rounded to 1 m.
  std::filesystem::remove(Path("m.mtl"));
  auto model = ReadObj(Write("plain.obj", "v 1000.5 2000.25 3 \nv 1001.5 2000.25 3\nv 1000.5 2001.25 3\nf 1 2 3\n"));
  ASSERT_TRUE(model.ok()) << model.status().message();
  EXPECT_EQ(model->mesh.origin, (std::array<double, 3>{1001, 2001, 3}));
  EXPECT_EQ(model->mesh.positions[0], -0.5f);
}

TEST_F(ObjTest, RelativeCoordinatesRoundTrip) {
  const Mesh mesh = Grid(3);
  ObjWriteOptions options;
  options.absolute_coordinates = false;
  ASSERT_TRUE(WriteObj(Path("r.obj"), mesh, options).ok());
  std::ifstream in(Path("r.obj"));
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("# coordinates relative\nmtllib"), std::string::npos);
  EXPECT_NE(text.find("\nv 0 0 0 0 0 0.011764706\n"), std::string::npos);
  auto model = ReadObj(Path("r.obj"));
  ASSERT_TRUE(model.ok()) << model.status().message();
  EXPECT_EQ(model->mesh.origin, mesh.origin);
  EXPECT_EQ(model->mesh.positions, mesh.positions);
}

TEST_F(ObjTest, ForeignIndexLayoutsAreRead) {
  // Quads, separate v/vt/vn indices, negative (relative) indices.
  const std::string obj =
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n"
      "vn 0 0 1\n"
      "f 1/1/1 2/2/1 3/3/1 4/4/1\n"
      "f -4/-1/-1 -3/-1/-1 -2/-1/-1\n";
  auto model = ReadObj(Write("q.obj", obj));
  ASSERT_TRUE(model.ok()) << model.status().message();
  const Mesh& mesh = model->mesh;
  EXPECT_EQ(mesh.face_count(), 3u);
  EXPECT_EQ(mesh.vertex_count(), 7u);  // 4 corners + 3 with the other uv
  ASSERT_EQ(mesh.uvs.size(), 14u);
  EXPECT_EQ(mesh.uvs[2 * mesh.indices[6]], 0.5f);
  EXPECT_EQ(mesh.normals.size(), 21u);

  // A 20-gon: fan-triangulated into 18 triangles, no corner lost.
  std::string polygon;
  for (int i = 0; i < 20; ++i) {
    polygon += "v " + std::to_string(std::cos(i * M_PI / 10)) + " " + std::to_string(std::sin(i * M_PI / 10)) + " 0\n";
  }
  polygon += "f";
  for (int i = 1; i <= 20; ++i) polygon += " " + std::to_string(i);
  auto ngon = ReadObj(Write("ngon.obj", polygon + "\n"));
  ASSERT_TRUE(ngon.ok()) << ngon.status().message();
  EXPECT_EQ(ngon->mesh.face_count(), 18u);
  EXPECT_EQ(ngon->mesh.indices.back(), 19u);
}

TEST_F(ObjTest, ErrorsNameTheFileAndLine) {
  auto bad = ReadObj(Write("bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2 9\n"));
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), Status::Code::kCorrupt);
  EXPECT_NE(bad.status().message().find("bad.obj:3: face index 9 out of range"), std::string::npos)
      << bad.status().message();
  EXPECT_FALSE(ReadObj(Write("v.obj", "v 0 zero 0\n")).ok());
  EXPECT_EQ(ReadObj(Path("none.obj")).status().code(), Status::Code::kNotFound);
  auto no_texture = ReadObj(Write("t.obj", "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_EQ(no_texture.status().code(), Status::Code::kNotFound);  // the missing MTL
}

TEST_F(ObjTest, TextureWithoutUvsIsAnErrorAndNothingIsWritten) {
  Mesh mesh = Grid(2);
  mesh.uvs.clear();
  ObjWriteOptions options;
  options.normal_png = kFakePngNormal;
  const Status status = WriteObj(Path("m.obj"), mesh, options);
  EXPECT_EQ(status.code(), Status::Code::kInvalid);
  EXPECT_NE(status.message().find("uvs"), std::string::npos);
  EXPECT_TRUE(std::filesystem::is_empty(dir_));
  // Without textures a mesh without uvs is fine: f a//a.
  ASSERT_TRUE(WriteObj(Path("m.obj"), mesh, ObjWriteOptions{}).ok());
  auto model = ReadObj(Path("m.obj"));
  ASSERT_TRUE(model.ok()) << model.status().message();
  EXPECT_TRUE(model->mesh.uvs.empty());
  EXPECT_EQ(model->mesh.indices, mesh.indices);
}

TEST_F(ObjTest, UnwritableFolderNamesThePathAndLeavesNoFile) {
  ObjWriteOptions options;
  options.base_color_png = kFakePngColor;
  const std::string path = Path("missing/model.obj");
  const Status status = WriteObj(path, Grid(2), options);
  EXPECT_EQ(status.code(), Status::Code::kIo);
  EXPECT_NE(status.message().find(Path("missing/color.png")), std::string::npos) << status.message();
  EXPECT_TRUE(std::filesystem::is_empty(dir_));
  // A folder in which the texture cannot be renamed into place (a directory
  // is in its way): the texture is renamed first, so the .obj and .mtl never
  // appear, and every temporary is removed.
  std::filesystem::create_directories(Path("out/color.png"));
  const Status blocked = WriteObj(Path("out/model.obj"), Grid(2), options);
  EXPECT_EQ(blocked.code(), Status::Code::kIo);
  EXPECT_NE(blocked.message().find("out/color.png: rename"), std::string::npos) << blocked.message();
  std::vector<std::string> left;
  for (const auto& entry : std::filesystem::directory_iterator(Path("out"))) {
    left.push_back(entry.path().filename().string());
  }
  EXPECT_EQ(left, std::vector<std::string>{"color.png"});
}

}  // namespace
}  // namespace pb
