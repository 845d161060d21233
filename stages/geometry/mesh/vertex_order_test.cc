#include "stages/geometry/mesh/vertex_order.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <tuple>
#include <vector>

namespace pb {
namespace {

// An (n+1)^2-vertex grid with every attribute, its triangles and vertices
// shuffled (the worst case for both caches), plus one vertex no face uses.
Mesh ShuffledGrid(int n) {
  Mesh mesh;
  const int side = n + 1;
  for (int j = 0; j < side; ++j) {
    for (int i = 0; i < side; ++i) {
      const float u = float(i) / n, v = float(j) / n;
      mesh.positions.insert(mesh.positions.end(), {u, v, 0.1f * u * v});
      mesh.normals.insert(mesh.normals.end(), {0, 0, 1});
      mesh.colors.insert(mesh.colors.end(), {uint8_t(i % 256), uint8_t(j % 256), 7});
      mesh.uvs.insert(mesh.uvs.end(), {u, v});
      mesh.tangents.insert(mesh.tangents.end(), {1, 0, 0, (i + j) % 2 ? 1.0f : -1.0f});
    }
  }
  mesh.positions.insert(mesh.positions.end(), {5, 5, 5});  // unreferenced
  mesh.normals.insert(mesh.normals.end(), {0, 0, 1});
  mesh.colors.insert(mesh.colors.end(), {0, 0, 0});
  mesh.uvs.insert(mesh.uvs.end(), {0, 0});
  mesh.tangents.insert(mesh.tangents.end(), {1, 0, 0, 1});
  std::vector<std::array<uint32_t, 3>> faces;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * side + i, b = a + 1, c = a + side + 1, d = a + side;
      faces.push_back({a, b, c});
      faces.push_back({a, c, d});
    }
  }
  std::mt19937 random(7);
  std::shuffle(faces.begin(), faces.end(), random);
  // Shuffle the vertex order too (all attributes together).
  const size_t count = mesh.vertex_count();
  std::vector<uint32_t> order(count);
  for (uint32_t v = 0; v < count; ++v) order[v] = v;
  std::shuffle(order.begin(), order.end(), random);
  std::vector<uint32_t> new_index(count);
  Mesh shuffled;
  for (uint32_t k = 0; k < count; ++k) {
    const uint32_t v = order[k];
    new_index[v] = k;
    shuffled.positions.insert(shuffled.positions.end(), &mesh.positions[3 * v], &mesh.positions[3 * v + 3]);
    shuffled.normals.insert(shuffled.normals.end(), &mesh.normals[3 * v], &mesh.normals[3 * v + 3]);
    shuffled.colors.insert(shuffled.colors.end(), &mesh.colors[3 * v], &mesh.colors[3 * v + 3]);
    shuffled.uvs.insert(shuffled.uvs.end(), &mesh.uvs[2 * v], &mesh.uvs[2 * v + 2]);
    shuffled.tangents.insert(shuffled.tangents.end(), &mesh.tangents[4 * v], &mesh.tangents[4 * v + 4]);
  }
  for (const auto& f : faces) {
    for (uint32_t v : f) shuffled.indices.push_back(new_index[v]);
  }
  return shuffled;
}

// Every attribute of a vertex, to compare vertices across orders.
using VertexKey = std::tuple<float, float, float, float, float, float, int, int, int, float, float,
                             float, float, float, float>;
VertexKey Key(const Mesh& m, uint32_t v) {
  return {m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2], m.normals[3 * v],
          m.normals[3 * v + 1], m.normals[3 * v + 2], m.colors[3 * v], m.colors[3 * v + 1],
          m.colors[3 * v + 2], m.uvs[2 * v], m.uvs[2 * v + 1], m.tangents[4 * v],
          m.tangents[4 * v + 1], m.tangents[4 * v + 2], m.tangents[4 * v + 3]};
}

// The triangles as vertex-attribute triples, each rotated to start at its
// smallest key (winding kept), sorted.
std::vector<std::array<VertexKey, 3>> Triangles(const Mesh& m) {
  std::vector<std::array<VertexKey, 3>> out;
  for (size_t f = 0; f < m.face_count(); ++f) {
    std::array<VertexKey, 3> t = {Key(m, m.indices[3 * f]), Key(m, m.indices[3 * f + 1]),
                                  Key(m, m.indices[3 * f + 2])};
    const int first = int(std::min_element(t.begin(), t.end()) - t.begin());
    std::rotate(t.begin(), t.begin() + first, t.end());
    out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(VertexOrderTest, KeepsEveryTriangleAndImprovesBothCaches) {
  Mesh mesh = ShuffledGrid(150);
  const auto before = Triangles(mesh);
  const size_t vertices_before = mesh.vertex_count();
  VertexOrderReport report;
  OptimizeVertexOrder(mesh, &report);
  ASSERT_TRUE(Validate(mesh).ok());
  EXPECT_EQ(mesh.vertex_count(), vertices_before - 1);  // the unreferenced one
  EXPECT_EQ(Triangles(mesh), before);
  // A shuffled grid transforms ~3 vertices a triangle; ordered, under 1.
  EXPECT_GT(report.acmr_before, 2.0);
  EXPECT_LT(report.acmr_after, 1.0);
  EXPECT_GT(report.overfetch_before, 2.0 * report.overfetch_after);
  EXPECT_LT(report.overfetch_after, 1.5);
  // Vertices come in first-use order: the first triangle's are among the first three.
  for (int k = 0; k < 3; ++k) EXPECT_LT(mesh.indices[k], 3u);
}

TEST(VertexOrderTest, IsDeterministic) {
  Mesh a = ShuffledGrid(20), b = ShuffledGrid(20);
  OptimizeVertexOrder(a);
  OptimizeVertexOrder(b);
  EXPECT_EQ(a.indices, b.indices);
  EXPECT_EQ(a.positions, b.positions);
}

TEST(VertexOrderTest, MeshWithPositionsOnly) {
  Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  mesh.indices = {1, 3, 2, 0, 1, 2};
  OptimizeVertexOrder(mesh);
  ASSERT_TRUE(Validate(mesh).ok());
  EXPECT_EQ(mesh.vertex_count(), 4u);
  EXPECT_EQ(mesh.face_count(), 2u);
  EXPECT_TRUE(mesh.normals.empty());
}

}  // namespace
}  // namespace pb
