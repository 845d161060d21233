// WriteVtp read back by VTK 9's own reader (vtkXMLPolyDataReader): the
// oracle for "ParaView opens it". Links VTK; nothing else in pointbake does.
#include "stages/geometry/io/vtp.h"

#include <gtest/gtest.h>
#include <vtkCellArray.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkXMLPolyDataReader.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "base/testing/durable_write_check.h"
#include "stages/geometry/testing/test_data.h"
#include "stages/geometry/testing/vtk_read.h"

namespace pb {
namespace {

using testing::ReadVtpWithVtk;
using testing::VtkFieldString;

// An n x n grid far from the origin with every attribute the writer knows.
Mesh Grid(int n) {
  Mesh mesh;
  mesh.origin = {456789.125, 5432109.5, 312.75};
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      mesh.positions.insert(mesh.positions.end(),
                            {float(i) / n, float(j) / n, 0.001f * float(i * j)});
      mesh.normals.insert(mesh.normals.end(), {0.f, 0.f, 1.f});
      mesh.uvs.insert(mesh.uvs.end(), {float(i) / n, 1.f - float(j) / n});
      mesh.colors.insert(mesh.colors.end(), {uint8_t(i * 255 / n), uint8_t(j * 255 / n), 7});
      mesh.tangents.insert(mesh.tangents.end(), {1.f, 0.f, 0.f, j % 2 ? -1.f : 1.f});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
    }
  }
  return mesh;
}

class VtpTest : public testing::TempDirTest {};

TEST_F(VtpTest, VtkReadsPointsCellsAndEveryArray) {
  // 200 x 200 cells: every block spans more than one 1 MiB write chunk.
  const Mesh mesh = Grid(200);
  const size_t n = mesh.vertex_count();
  std::vector<float> distance(n);
  std::vector<uint8_t> flag(n);
  for (size_t v = 0; v < n; ++v) {
    distance[v] = 0.001f * float(v % 997);
    flag[v] = uint8_t(v % 3 == 0);
  }
  VtpWriteOptions options;
  options.point_arrays = {{"distance_to_scan_m", 1, distance, {}}, {"invented", 1, {}, flag}};
  options.active_scalars = "distance_to_scan_m";
  options.field_data = {{"BaseColorTexture", "color.png"}, {"Note", "a <b> & \"c\" é"}};
  uint64_t bytes = 0;
  const std::string path = Path("errors.vtp");
  ASSERT_TRUE(WriteVtp(path, mesh, options, &bytes).ok());
  EXPECT_EQ(bytes, std::filesystem::file_size(path));

  const testing::VtkRead read = ReadVtpWithVtk(path);
  ASSERT_EQ(read.errors, 0) << read.last_error;
  vtkPolyData* poly = read.poly;
  ASSERT_EQ(poly->GetNumberOfPoints(), vtkIdType(n));
  ASSERT_EQ(poly->GetNumberOfPolys(), vtkIdType(mesh.face_count()));
  EXPECT_EQ(poly->GetNumberOfVerts() + poly->GetNumberOfLines() + poly->GetNumberOfStrips(), 0);
  EXPECT_EQ(poly->GetPoints()->GetDataType(), VTK_DOUBLE);
  for (size_t v = 0; v < n; ++v) {
    double p[3];
    poly->GetPoint(vtkIdType(v), p);
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(p[k], mesh.origin[k] + double(mesh.positions[3 * v + k])) << v;
  }
  vtkNew<vtkIdList> ids;
  vtkCellArray* polys = poly->GetPolys();
  polys->InitTraversal();
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    ASSERT_TRUE(polys->GetNextCell(ids));
    ASSERT_EQ(ids->GetNumberOfIds(), 3);
    for (int k = 0; k < 3; ++k) ASSERT_EQ(ids->GetId(k), vtkIdType(mesh.indices[3 * f + k])) << f;
  }

  vtkPointData* pd = poly->GetPointData();
  ASSERT_NE(pd->GetNormals(), nullptr);
  ASSERT_NE(pd->GetTCoords(), nullptr);
  ASSERT_NE(pd->GetScalars(), nullptr);
  EXPECT_STREQ(pd->GetNormals()->GetName(), "Normals");
  EXPECT_STREQ(pd->GetTCoords()->GetName(), "TCoords");
  EXPECT_STREQ(pd->GetScalars()->GetName(), "distance_to_scan_m");
  vtkDataArray* colors = pd->GetArray("Colors");
  vtkDataArray* tangents = pd->GetArray("Tangents");
  vtkDataArray* invented = pd->GetArray("invented");
  ASSERT_TRUE(colors && tangents && invented);
  EXPECT_EQ(colors->GetDataType(), VTK_UNSIGNED_CHAR);
  EXPECT_EQ(invented->GetDataType(), VTK_UNSIGNED_CHAR);
  EXPECT_EQ(pd->GetScalars()->GetDataType(), VTK_FLOAT);
  EXPECT_EQ(tangents->GetNumberOfComponents(), 4);
  for (size_t v = 0; v < n; ++v) {
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(pd->GetNormals()->GetComponent(vtkIdType(v), k), mesh.normals[3 * v + k]);
      ASSERT_EQ(colors->GetComponent(vtkIdType(v), k), mesh.colors[3 * v + k]);
    }
    for (int k = 0; k < 2; ++k)
      ASSERT_EQ(pd->GetTCoords()->GetComponent(vtkIdType(v), k), mesh.uvs[2 * v + k]);
    for (int k = 0; k < 4; ++k)
      ASSERT_EQ(tangents->GetComponent(vtkIdType(v), k), mesh.tangents[4 * v + k]);
    ASSERT_EQ(pd->GetScalars()->GetComponent(vtkIdType(v), 0), distance[v]) << v;
    ASSERT_EQ(invented->GetComponent(vtkIdType(v), 0), flag[v]) << v;
  }
  EXPECT_EQ(VtkFieldString(poly, "BaseColorTexture"), "color.png");
  EXPECT_EQ(VtkFieldString(poly, "Note"), "a <b> & \"c\" é");
}

TEST_F(VtpTest, BareMeshAndEmptyMesh) {
  Mesh bare = Grid(2);
  bare.normals.clear();
  bare.uvs.clear();
  bare.colors.clear();
  bare.tangents.clear();
  ASSERT_TRUE(WriteVtp(Path("bare.vtp"), bare, {}).ok());
  testing::VtkRead read = ReadVtpWithVtk(Path("bare.vtp"));
  ASSERT_EQ(read.errors, 0) << read.last_error;
  EXPECT_EQ(read.poly->GetNumberOfPoints(), 9);
  EXPECT_EQ(read.poly->GetNumberOfPolys(), 8);
  EXPECT_EQ(read.poly->GetPointData()->GetNumberOfArrays(), 0);
  EXPECT_EQ(read.poly->GetPointData()->GetNormals(), nullptr);

  ASSERT_TRUE(WriteVtp(Path("empty.vtp"), Mesh{}, {}).ok());
  read = ReadVtpWithVtk(Path("empty.vtp"));
  ASSERT_EQ(read.errors, 0) << read.last_error;
  EXPECT_EQ(read.poly->GetNumberOfPoints(), 0);
  EXPECT_EQ(read.poly->GetNumberOfPolys(), 0);
}

TEST_F(VtpTest, StartsWithTheSignature) {
  ASSERT_TRUE(WriteVtp(Path("m.vtp"), Grid(1), {}).ok());
  std::ifstream in(Path("m.vtp"));
  std::string first, second;
  std::getline(in, first);
  std::getline(in, second);
  EXPECT_EQ(first, "<?xml version=\"1.0\"?>");
  EXPECT_EQ(second, "<!-- pointbake vtp 1 -->");
}

TEST_F(VtpTest, RefusesArraysThatDoNotFit) {
  const Mesh mesh = Grid(2);  // 9 vertices
  const std::vector<float> eight(8, 0.f), nine(9, 0.f);
  const std::vector<uint8_t> nine_bytes(9, 0);
  const auto error = [&](const VtpWriteOptions& options) {
    const Status s = WriteVtp(Path("bad.vtp"), mesh, options);
    if (s.ok()) {
      std::filesystem::remove(Path("bad.vtp"));
      return std::string("ok");
    }
    EXPECT_FALSE(std::filesystem::exists(Path("bad.vtp")));
    return s.message();
  };
  const auto message = [&](std::vector<VtpPointArray> arrays, std::string active = "") {
    VtpWriteOptions o;
    o.point_arrays = std::move(arrays);
    o.active_scalars = std::move(active);
    return error(o);
  };
  EXPECT_NE(message({{"d", 1, eight, {}}}).find("'d': 8 values for 9 vertices x 1 components"),
            std::string::npos)
      << message({{"d", 1, eight, {}}});
  EXPECT_NE(message({{"d", 1, nine, nine_bytes}}).find("exactly one of"), std::string::npos);
  EXPECT_NE(message({{"d", 1, nine, {}}, {"d", 1, {}, nine_bytes}})
                .find("two point arrays are named 'd'"),
            std::string::npos);
  EXPECT_NE(message({{"Normals", 1, nine, {}}}).find("named 'Normals'"), std::string::npos);
  EXPECT_NE(message({{"d", 1, nine, {}}}, "e").find("active_scalars 'e'"), std::string::npos);
  EXPECT_NE(message({{"", 1, nine, {}}}).find("no name"), std::string::npos);
  EXPECT_EQ(message({{"d", 1, nine, {}}}, "d"), "ok");
}

// The .vtp and its textures are one durable set: a failure at any of them
// keeps the earlier set whole.
TEST_F(VtpTest, FailedWritesKeepTheEarlierFiles) {
  const std::vector<uint8_t> png_a = {0x89, 'P', 'N', 'G', 1, 2, 3},
                             png_b = {0x89, 'P', 'N', 'G', 4, 5};
  const auto options = [&](const std::vector<uint8_t>& color, const std::vector<uint8_t>& normal) {
    VtpWriteOptions o;
    o.companions = {{Path("color.png"), color}, {Path("normal.png"), normal}};
    o.field_data = {{"BaseColorTexture", "color.png"}};
    return o;
  };
  ASSERT_TRUE(WriteVtp(Path("model.vtp"), Grid(2), options(png_a, png_b)).ok());
  EXPECT_EQ(testing::ExpectFailedWritesKeepEarlierFiles(
                dir_,
                [&](Env* env) {
                  return WriteVtp(Path("model.vtp"), Grid(3), options(png_b, png_a), nullptr, env);
                }),
            3);
}

}  // namespace
}  // namespace pb
