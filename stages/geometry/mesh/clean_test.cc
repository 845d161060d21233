#include "stages/geometry/mesh/clean.h"

#include <gtest/gtest.h>

namespace pb {
namespace {

// An nx x ny grid of unit squares in the z = 0 plane, two triangles each,
// vertices colored by index; vertex (i, j) has index j * (nx + 1) + i.
Mesh Grid(int nx, int ny, float x0 = 0) {
  Mesh mesh;
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      mesh.positions.insert(mesh.positions.end(), {x0 + i, static_cast<float>(j), 0.f});
      const uint8_t c = static_cast<uint8_t>(mesh.colors.size() / 3);
      mesh.colors.insert(mesh.colors.end(), {c, c, c});
    }
  }
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const uint32_t a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, d, a, d, c});
    }
  }
  return mesh;
}

// Appends a mesh (its vertices and faces) to another.
void Append(Mesh* to, const Mesh& from) {
  const uint32_t base = static_cast<uint32_t>(to->vertex_count());
  to->positions.insert(to->positions.end(), from.positions.begin(), from.positions.end());
  to->colors.insert(to->colors.end(), from.colors.begin(), from.colors.end());
  for (uint32_t i : from.indices) to->indices.push_back(base + i);
}

uint32_t AddVertex(Mesh* mesh, float x, float y, float z) {
  mesh->positions.insert(mesh->positions.end(), {x, y, z});
  mesh->colors.insert(mesh->colors.end(), {200, 100, 50});
  return static_cast<uint32_t>(mesh->vertex_count() - 1);
}

CleanOptions NoComponentFilter() {
  CleanOptions options;
  options.min_component_faces = 0;
  return options;
}

TEST(MeshCleanTest, CleanGridIsUnchanged) {
  const Mesh grid = Grid(10, 10);
  CleanReport report;
  Expected<Mesh> out = CleanMesh(grid, CleanOptions{}, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(out->indices, grid.indices);
  EXPECT_EQ(out->positions, grid.positions);
  EXPECT_EQ(out->colors, grid.colors);
  EXPECT_EQ(report.faces_in, 200u);
  EXPECT_EQ(report.faces_out, 200u);
  EXPECT_EQ(report.vertices_out, 121u);
  EXPECT_TRUE(CheckManifold(*out).ok());
}

TEST(MeshCleanTest, RemovesDegenerateFaces) {
  Mesh mesh = Grid(3, 3);
  mesh.indices.insert(mesh.indices.end(), {0, 0, 1});  // repeated index
  const uint32_t a = AddVertex(&mesh, 0, 0, 1), b = AddVertex(&mesh, 1, 0, 1),
                 c = AddVertex(&mesh, 2, 0, 1);
  mesh.indices.insert(mesh.indices.end(), {a, b, c});  // collinear: zero area
  CleanReport report;
  Expected<Mesh> out = CleanMesh(mesh, NoComponentFilter(), &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(report.degenerate_faces, 2u);
  EXPECT_EQ(report.unreferenced_vertices, 3u);  // a, b, c orphaned
  EXPECT_EQ(out->face_count(), 18u);
  EXPECT_EQ(out->vertex_count(), 16u);
  EXPECT_EQ(out->colors.size(), 48u);
}

TEST(MeshCleanTest, MinAreaThreshold) {
  Mesh mesh = Grid(2, 1);
  const uint32_t a = AddVertex(&mesh, 0, 0, 2), b = AddVertex(&mesh, 0.001f, 0, 2),
                 c = AddVertex(&mesh, 0, 0.001f, 2);  // area 5e-7 m^2
  mesh.indices.insert(mesh.indices.end(), {a, b, c});
  CleanOptions options = NoComponentFilter();
  CleanReport report;
  ASSERT_TRUE(CleanMesh(mesh, options, &report).ok());
  EXPECT_EQ(report.degenerate_faces, 0u);
  options.min_area_m2 = 1e-6;
  ASSERT_TRUE(CleanMesh(mesh, options, &report).ok());
  EXPECT_EQ(report.degenerate_faces, 1u);
  EXPECT_EQ(report.faces_out, 4u);
}

TEST(MeshCleanTest, RemovesDuplicateFacesEitherOrientation) {
  Mesh mesh = Grid(3, 3);
  mesh.indices.insert(mesh.indices.end(), {mesh.indices[0], mesh.indices[1], mesh.indices[2]});
  mesh.indices.insert(mesh.indices.end(), {mesh.indices[5], mesh.indices[4], mesh.indices[3]});
  mesh.indices.insert(mesh.indices.end(), {mesh.indices[1], mesh.indices[2], mesh.indices[0]});
  CleanReport report;
  Expected<Mesh> out = CleanMesh(mesh, NoComponentFilter(), &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(report.duplicate_faces, 3u);
  EXPECT_EQ(out->indices, Grid(3, 3).indices);  // the first copies are kept, in order
}

TEST(MeshCleanTest, RemovesUnreferencedVerticesAndCompactsAttributes) {
  Mesh mesh;
  AddVertex(&mesh, 5, 5, 5);  // unused
  const uint32_t a = AddVertex(&mesh, 0, 0, 0), b = AddVertex(&mesh, 1, 0, 0);
  AddVertex(&mesh, 7, 7, 7);  // unused
  const uint32_t c = AddVertex(&mesh, 0, 1, 0);
  mesh.colors[3 * c] = 9;
  mesh.normals.assign(3 * mesh.vertex_count(), 0.f);
  for (size_t v = 0; v < mesh.vertex_count(); ++v) mesh.normals[3 * v + 2] = 1;
  mesh.uvs.assign(2 * mesh.vertex_count(), 0.f);
  mesh.uvs[2 * c] = 0.75f;
  mesh.indices = {a, b, c};
  CleanReport report;
  Expected<Mesh> out = CleanMesh(mesh, NoComponentFilter(), &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(report.unreferenced_vertices, 2u);
  EXPECT_EQ(out->indices, (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_EQ(out->positions, (std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0}));
  EXPECT_EQ(out->colors[6], 9);
  EXPECT_EQ(out->normals.size(), 9u);
  EXPECT_EQ(out->uvs, (std::vector<float>{0, 0, 0, 0, 0.75f, 0}));
}

TEST(MeshCleanTest, RemovesSmallComponentsByCount) {
  Mesh mesh = Grid(10, 10);       // 200 faces
  Append(&mesh, Grid(1, 1, 20));  // 2 faces
  Append(&mesh, Grid(5, 5, 30));  // 50 faces: kept (not fewer than 50)
  CleanOptions options;
  options.min_component_area_m2 = 1e9;  // count alone decides here
  CleanReport report;
  Expected<Mesh> out = CleanMesh(mesh, options, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(report.small_components, 1u);
  EXPECT_EQ(report.small_component_faces, 2u);
  EXPECT_EQ(report.unreferenced_vertices, 4u);
  EXPECT_EQ(out->face_count(), 250u);
}

// A decimated flat wall can be a 2-face component: few faces alone do not make
// a speck, small area must too.
TEST(MeshCleanTest, FewFacedButLargeComponentsAreKept) {
  Mesh mesh = Grid(10, 10);       // 200 faces, 100 m^2
  Append(&mesh, Grid(1, 1, 20));  // 2 faces, 1 m^2: a wall, kept
  Mesh speck = Grid(1, 1, 40);    // 2 faces, 1 mm^2: removed
  for (size_t v = 0; v < speck.vertex_count(); ++v) {
    speck.positions[3 * v] = 40 + (speck.positions[3 * v] - 40) * 1e-3f;
    speck.positions[3 * v + 1] *= 1e-3f;
  }
  Append(&mesh, speck);
  CleanReport report;
  Expected<Mesh> out = CleanMesh(mesh, CleanOptions{}, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(report.small_components, 1u);
  EXPECT_EQ(report.small_component_faces, 2u);
  EXPECT_EQ(out->face_count(), 202u);
}

TEST(MeshCleanTest, RemovesSmallComponentsByFraction) {
  Mesh mesh = Grid(10, 10);       // 200 faces
  Append(&mesh, Grid(3, 3, 20));  // 18 faces < 0.1 * 200
  Append(&mesh, Grid(5, 2, 30));  // 20 faces: kept
  CleanOptions options = NoComponentFilter();
  options.min_component_fraction = 0.1;
  options.min_component_area_m2 = 1e9;
  CleanReport report;
  Expected<Mesh> out = CleanMesh(mesh, options, &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(report.small_components, 1u);
  EXPECT_EQ(report.small_component_faces, 18u);
  EXPECT_EQ(out->face_count(), 220u);
}

TEST(MeshCleanTest, NonManifoldEdgeKeepsTwoLargestFaces) {
  Mesh mesh = Grid(3, 3);                             // face 0 = (0, 1, 5), area 0.5, uses edge 0-1
  const uint32_t big = AddVertex(&mesh, 0.5f, 0, 2);  // fin of area 1
  const uint32_t small = AddVertex(&mesh, 0.5f, 0, -0.5f);  // fin of area 0.25
  // Both fins run edge 0-1 against the grid face, so the two kept are
  // consistently oriented.
  mesh.indices.insert(mesh.indices.end(), {1, 0, small, 1, 0, big});
  EXPECT_EQ(CheckManifold(mesh).message(), "non-manifold edge 0-1: in more than two faces");
  CleanReport report;
  Expected<Mesh> out = CleanMesh(mesh, NoComponentFilter(), &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(report.nonmanifold_edge_faces, 1u);
  EXPECT_EQ(report.unreferenced_vertices, 1u);  // the small fin's apex
  ASSERT_EQ(out->face_count(), 19u);
  EXPECT_EQ(out->indices[0], 0u);  // the grid face survives
  const size_t last = 3 * 18;
  EXPECT_EQ(out->positions[3 * out->indices[last + 2] + 2], 2.f);  // the big fin survives
  EXPECT_TRUE(CheckManifold(*out).ok()) << CheckManifold(*out).message();
}

TEST(MeshCleanTest, SplitsNonManifoldVertexIntoFans) {
  // Two triangles touching at vertex 0 only (a bowtie), plus a third fan of two
  // triangles sharing an edge, also at vertex 0.
  Mesh mesh;
  const uint32_t o = AddVertex(&mesh, 0, 0, 0);
  mesh.colors[0] = 77;
  mesh.normals.assign(3, 0.f);
  const uint32_t a = AddVertex(&mesh, 1, 0, 0), b = AddVertex(&mesh, 1, 1, 0);
  const uint32_t c = AddVertex(&mesh, -1, 0, 0), d = AddVertex(&mesh, -1, -1, 0);
  const uint32_t e = AddVertex(&mesh, 0, 0, 1), f = AddVertex(&mesh, 0, 1, 1),
                 g = AddVertex(&mesh, 0, -1, 1);
  mesh.normals.assign(3 * mesh.vertex_count(), 0.5f);
  mesh.indices = {o, a, b, o, c, d, o, e, f, o, g, e};
  EXPECT_EQ(CheckManifold(mesh).message(),
            "non-manifold vertex 0: its faces form more than one fan");
  CleanReport report;
  Expected<Mesh> out = CleanMesh(mesh, NoComponentFilter(), &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(report.split_vertices, 2u);
  ASSERT_EQ(out->vertex_count(), 10u);
  EXPECT_EQ(out->indices[0], 0u);  // the first fan keeps the vertex
  EXPECT_EQ(out->indices[3], 8u);
  EXPECT_EQ(out->indices[6], 9u);
  EXPECT_EQ(out->indices[9], 9u);  // same fan as face 2
  for (uint32_t v : {8u, 9u}) {
    EXPECT_EQ(out->positions[3 * v], 0.f);
    EXPECT_EQ(out->colors[3 * v], 77);
    EXPECT_EQ(out->normals[3 * v], 0.5f);
  }
  EXPECT_TRUE(CheckManifold(*out).ok()) << CheckManifold(*out).message();
}

TEST(MeshCleanTest, EverythingAtOnceGivesManifoldOutput) {
  Mesh mesh = Grid(8, 8);
  const uint32_t apex = AddVertex(&mesh, 4, 4, 3);
  for (uint32_t v : {0u, 1u, 2u}) mesh.indices.insert(mesh.indices.end(), {v + 1, v, apex});
  mesh.indices.insert(mesh.indices.end(), {mesh.indices[6], mesh.indices[7], mesh.indices[8]});
  mesh.indices.insert(mesh.indices.end(), {3, 3, 4});
  Append(&mesh, Grid(1, 1, 20));
  // A second sheet touching the grid at vertex 40 only.
  const uint32_t p = AddVertex(&mesh, 4, 4, -1), q = AddVertex(&mesh, 5, 4, -1);
  mesh.indices.insert(mesh.indices.end(), {40, p, q});
  ASSERT_FALSE(CheckManifold(mesh).ok());
  CleanReport report;
  Expected<Mesh> out = CleanMesh(mesh, NoComponentFilter(), &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(report.degenerate_faces, 1u);
  EXPECT_EQ(report.duplicate_faces, 1u);
  EXPECT_EQ(report.split_vertices, 1u);  // vertex 40
  EXPECT_TRUE(CheckManifold(*out).ok()) << CheckManifold(*out).message();
}

TEST(MeshCleanTest, DropsTheSmallerFaceOfAMisorientedEdge) {
  // A fin on edge 0-1 of the grid running it the same way as grid face 0
  // (area 0.5): a fold, which mesh.decimate would take for two border
  // edges. The smaller face goes; with hole filling its hole closes again.
  Mesh mesh = Grid(3, 3);
  const uint32_t fin = AddVertex(&mesh, 0.5f, 0, 0.5f);  // area 0.25
  mesh.indices.insert(mesh.indices.end(), {0, 1, fin});
  CleanReport report;
  Expected<Mesh> out = CleanMesh(mesh, NoComponentFilter(), &report);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_EQ(report.misoriented_faces, 1u);
  EXPECT_EQ(out->face_count(), 18u);
  EXPECT_EQ(report.unreferenced_vertices, 1u);  // the fin's apex
  EXPECT_TRUE(CheckManifold(*out).ok());
}

TEST(MeshCleanTest, RejectsInvalidInput) {
  Mesh mesh = Grid(1, 1);
  mesh.indices.push_back(0);
  mesh.indices.push_back(1);
  mesh.indices.push_back(99);
  Expected<Mesh> out = CleanMesh(mesh, CleanOptions{}, nullptr);
  ASSERT_FALSE(out.ok());
  CleanOptions bad;
  bad.min_component_fraction = 2;
  Expected<Mesh> out2 = CleanMesh(Grid(1, 1), bad, nullptr);
  ASSERT_FALSE(out2.ok());
  EXPECT_NE(out2.status().message().find("min_component_fraction in [0, 1]"), std::string::npos);
}

}  // namespace
}  // namespace pb
