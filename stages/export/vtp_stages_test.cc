// The stages that write VTK XML PolyData, their files read back by VTK's own
// reader (vtkXMLPolyDataReader): export.vtp, and metrics.geometry's error
// maps (errors.vtp, with errors.ply's `quality` checked against it). The one
// stage test binary that links VTK.
#include <gtest/gtest.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkXMLPolyDataReader.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "stages/builtin.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/testing/vtk_read.h"
#include "stages/stage_test_util.h"

namespace pb {
namespace {

vtkSmartPointer<vtkPolyData> ReadWithVtk(const std::string& path) {
  testing::VtkRead read = testing::ReadVtpWithVtk(path);
  EXPECT_EQ(read.errors, 0) << path << ": " << read.last_error;
  return read.poly;
}

std::string FileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The float vertex properties of a binary PLY whose vertex properties are all
// float (no colors): name -> one value per vertex.
std::map<std::string, std::vector<float>> PlyFloatProperties(const std::string& path) {
  const std::string bytes = FileBytes(path);
  const size_t body = bytes.find("end_header\n") + 11;
  std::istringstream header(bytes.substr(0, body));
  std::vector<std::string> names;
  size_t vertices = 0;
  bool in_vertex = false;
  for (std::string line; std::getline(header, line);) {
    std::istringstream words(line);
    std::string keyword, a, b;
    words >> keyword >> a >> b;
    if (keyword == "element") {
      in_vertex = a == "vertex";
      if (in_vertex) vertices = std::stoul(b);
    } else if (keyword == "property" && in_vertex) {
      EXPECT_EQ(a, "float") << b;
      names.push_back(b);
    }
  }
  std::map<std::string, std::vector<float>> values;
  for (size_t v = 0; v < vertices; ++v) {
    for (size_t p = 0; p < names.size(); ++p) {
      float x;
      std::memcpy(&x, &bytes[body + 4 * (v * names.size() + p)], 4);
      values[names[p]].push_back(x);
    }
  }
  return values;
}

// A 1 m square of 2 x 10 x 10 faces at z = 0.
Mesh Square() {
  Mesh mesh;
  for (int j = 0; j <= 10; ++j)
    for (int i = 0; i <= 10; ++i)
      mesh.positions.insert(mesh.positions.end(), {i / 10.0f, j / 10.0f, 0.0f});
  for (uint32_t j = 0; j < 10; ++j)
    for (uint32_t i = 0; i < 10; ++i) {
      const uint32_t a = j * 11 + i;
      mesh.indices.insert(mesh.indices.end(), {a, a + 1, a + 12, a, a + 12, a + 11});
    }
  return mesh;
}

class VtpStagesTest : public StageTest {
 protected:
  void SetUp() override {
    StageTest::SetUp();
    RegisterBuiltinStages(registry_);
  }
};

// With a truth 2 cm above the square and a scan of its left 30 cm (1 cm
// grid): every vertex is 2 cm from the truth; a vertex at x is max(0,
// x - 0.3) from the scan, invented from x = 0.5 on (the threshold is the
// mesh's mean edge, 0.114 m, above 3 spacings).
TEST_F(VtpStagesTest, GeometryErrorMapsOpenInVtkAndAgreeWithThePly) {
  Mesh truth = Square();
  for (size_t v = 0; v < truth.vertex_count(); ++v) truth.positions[3 * v + 2] = 0.02f;
  PointCloud scan;
  for (int j = 0; j <= 100; ++j)
    for (int i = 0; i <= 30; ++i)
      scan.positions.insert(scan.positions.end(), {i * 0.01f, j * 0.01f, 0.0f});
  // uvs and tangents stay out of the maps (CloudCompare drops the scalar
  // fields of a PLY with tangents).
  Mesh square = Square();
  for (size_t v = 0; v < square.vertex_count(); ++v) {
    square.uvs.insert(square.uvs.end(), {square.positions[3 * v], square.positions[3 * v + 1]});
    square.tangents.insert(square.tangents.end(), {1, 0, 0, 1});
  }
  FakeContext ctx(dir_, {{"samples", 20000}, {"k", 4}});
  ctx.AddInput("mesh", "mesh", WriteInputMesh("square", square));
  ctx.AddInput("truth", "mesh", WriteInputMesh("truth", truth));
  ctx.AddInput("points", "points", WriteInputPoints("scan", scan));
  const Status status = Run("metrics.geometry", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(ctx.files_.count("errors/errors.vtp"), 1u);
  ASSERT_EQ(ctx.files_.count("errors/errors.ply"), 1u);

  vtkSmartPointer<vtkPolyData> poly = ReadWithVtk(ctx.files_.at("errors/errors.vtp"));
  ASSERT_EQ(poly->GetNumberOfPoints(), 121);
  ASSERT_EQ(poly->GetNumberOfPolys(), 200);
  vtkPointData* pd = poly->GetPointData();
  ASSERT_NE(pd->GetScalars(), nullptr);
  EXPECT_STREQ(pd->GetScalars()->GetName(), "distance_to_truth_m");
  vtkDataArray* to_truth = pd->GetArray("distance_to_truth_m");
  vtkDataArray* to_scan = pd->GetArray("distance_to_scan_m");
  vtkDataArray* invented = pd->GetArray("invented");
  ASSERT_TRUE(to_truth && to_scan && invented);
  EXPECT_EQ(testing::VtkFieldString(poly, "truth"), "mesh");
  EXPECT_EQ(testing::VtkFieldString(poly, "quality"), "distance_to_truth_m");
  for (vtkIdType v = 0; v < 121; ++v) {
    const int i = int(v % 11);
    EXPECT_NEAR(to_truth->GetComponent(v, 0), 0.02, 1e-6) << v;
    EXPECT_NEAR(to_scan->GetComponent(v, 0), std::max(0.0, i / 10.0 - 0.3), 1e-6) << v;
    EXPECT_EQ(invented->GetComponent(v, 0), i >= 5 ? 1 : 0) << v;
  }
  EXPECT_EQ(ctx.counters_.at("invented_vertices"), 6 * 11);

  EXPECT_EQ(pd->GetArray("Tangents"), nullptr);
  EXPECT_EQ(pd->GetTCoords(), nullptr);
  const auto ply = PlyFloatProperties(ctx.files_.at("errors/errors.ply"));
  EXPECT_EQ(ply.count("tx") + ply.count("s"), 0u);
  ASSERT_EQ(ply.count("quality"), 1u);
  ASSERT_EQ(ply.at("quality").size(), 121u);
  for (vtkIdType v = 0; v < 121; ++v) {
    EXPECT_EQ(ply.at("quality")[v], float(to_truth->GetComponent(v, 0)));
    EXPECT_EQ(ply.at("scalar_distance_to_truth_m")[v], float(to_truth->GetComponent(v, 0)));
    EXPECT_EQ(ply.at("scalar_distance_to_scan_m")[v], float(to_scan->GetComponent(v, 0)));
    EXPECT_EQ(ply.at("scalar_invented")[v], float(invented->GetComponent(v, 0)));
  }
  EXPECT_EQ(ctx.meta_.at("errors").at("quality"), "distance_to_truth_m");
}

// Without truth, the scan's distance is the active scalar and the quality.
TEST_F(VtpStagesTest, GeometryErrorMapsWithTheScanOnly) {
  PointCloud scan;
  for (int j = 0; j <= 100; ++j)
    for (int i = 0; i <= 100; ++i)
      scan.positions.insert(scan.positions.end(), {i * 0.01f, j * 0.01f, 0.03f});
  FakeContext ctx(dir_, {{"samples", 5000}});
  ctx.AddInput("mesh", "mesh", WriteInputMesh("square", Square()));
  ctx.AddInput("points", "points", WriteInputPoints("scan", scan));
  ASSERT_TRUE(Run("metrics.geometry", ctx).ok());
  vtkSmartPointer<vtkPolyData> poly = ReadWithVtk(ctx.files_.at("errors/errors.vtp"));
  ASSERT_NE(poly->GetPointData()->GetScalars(), nullptr);
  EXPECT_STREQ(poly->GetPointData()->GetScalars()->GetName(), "distance_to_scan_m");
  EXPECT_EQ(poly->GetPointData()->GetArray("distance_to_truth_m"), nullptr);
  EXPECT_EQ(testing::VtkFieldString(poly, "truth"), "<missing>");
  const auto ply = PlyFloatProperties(ctx.files_.at("errors/errors.ply"));
  for (float q : ply.at("quality")) EXPECT_NEAR(q, 0.03, 1e-6);
}

TEST_F(VtpStagesTest, ExportVtpWritesTheMeshItsAttributesAndItsMaps) {
  Mesh mesh = Square();
  mesh.origin = {350000.5, 5800000.25, 42.0};
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    mesh.uvs.insert(mesh.uvs.end(), {mesh.positions[3 * v], 1 - mesh.positions[3 * v + 1]});
    mesh.normals.insert(mesh.normals.end(), {0, 0, 1});
    mesh.colors.insert(mesh.colors.end(), {uint8_t(v), 9, 200});
  }
  Image color = Image::Make(8, 4, 3, Image::PixelType::kU8),
        normal = Image::Make(4, 4, 3, Image::PixelType::kU8);
  for (int c = 0; c < 3; ++c) normal.at_u8(1, 1, c) = 128;
  const std::string color_path = (dir_ / "color_in.png").string(),
                    normal_path = (dir_ / "normal_in.png").string();
  ASSERT_TRUE(WriteImage(color_path, color).ok());
  ASSERT_TRUE(WriteImage(normal_path, normal).ok());
  FakeContext ctx(dir_, nlohmann::json::object());
  ctx.AddInput("mesh", "mesh", WriteInputMesh("square", mesh));
  ctx.AddInput("color", "image", color_path);
  ctx.AddInput("normal", "image", normal_path);
  const Status status = Run("export.vtp", ctx);
  ASSERT_TRUE(status.ok()) << status.message();
  vtkSmartPointer<vtkPolyData> poly = ReadWithVtk(ctx.files_.at("model/model.vtp"));
  ASSERT_EQ(poly->GetNumberOfPoints(), 121);
  ASSERT_EQ(poly->GetNumberOfPolys(), 200);
  vtkPointData* pd = poly->GetPointData();
  ASSERT_TRUE(pd->GetTCoords() && pd->GetNormals() && pd->GetArray("Colors"));
  for (vtkIdType v = 0; v < 121; ++v) {
    double p[3];
    poly->GetPoint(v, p);
    EXPECT_EQ(p[0], mesh.origin[0] + mesh.positions[3 * v]);
    EXPECT_EQ(p[1], mesh.origin[1] + mesh.positions[3 * v + 1]);
    EXPECT_EQ(pd->GetTCoords()->GetComponent(v, 1), mesh.uvs[2 * v + 1]);
    EXPECT_EQ(pd->GetArray("Colors")->GetComponent(v, 0), mesh.colors[3 * v]);
  }
  EXPECT_EQ(testing::VtkFieldString(poly, "BaseColorTexture"), "color.png");
  EXPECT_EQ(testing::VtkFieldString(poly, "NormalTexture"), "normal.png");
  EXPECT_EQ(FileBytes(ctx.files_.at("model/color.png")), FileBytes(color_path));
  EXPECT_EQ(FileBytes(ctx.files_.at("model/normal.png")), FileBytes(normal_path));
  EXPECT_EQ(ctx.meta_.at("model").at("format"), "vtp");
  EXPECT_EQ(
      ctx.counters_.at("bytes"),
      double(std::filesystem::file_size(ctx.files_.at("model/model.vtp")) +
             std::filesystem::file_size(color_path) + std::filesystem::file_size(normal_path)));

  // Maps need uvs.
  mesh.uvs.clear();
  FakeContext no_uvs(dir_, nlohmann::json::object());
  no_uvs.AddInput("mesh", "mesh", WriteInputMesh("no_uvs", mesh));
  no_uvs.AddInput("color", "image", color_path);
  const Status refused = Run("export.vtp", no_uvs);
  EXPECT_FALSE(refused.ok());
  EXPECT_NE(refused.message().find("textures need uvs"), std::string::npos) << refused.message();
}

}  // namespace
}  // namespace pb
