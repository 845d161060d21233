// mesh_support: how much of a mesh the scan supports, the figures of issue
// 15 (docs/mesh-real-scans.md): invented area (the fraction of the mesh's
// area farther than max(3 x local spacing, mean edge length) from every scan
// point; MeasureSupport in stages/geometry/mesh/trim.h), boundary edges per
// 1000 faces, faces.
//   build/bench/mesh_support POINTS.ply MESH.ply [MESH.ply ...]
// Prints one JSON line per mesh.
#include <cstdio>
#include <string>

#include <algorithm>
#include <cmath>
#include <vector>

#include "stages/geometry/io/ply.h"
#include "stages/geometry/mesh/holes.h"
#include "stages/geometry/mesh/trim.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s POINTS.ply MESH.ply [MESH.ply ...]\n", argv[0]);
    return 2;
  }
  auto points = pb::ReadPlyPoints(argv[1]);
  if (!points.ok()) {
    std::fprintf(stderr, "%s: %s\n", argv[1], points.status().message().c_str());
    return 1;
  }
  for (int i = 2; i < argc; ++i) {
    auto mesh = pb::ReadPlyMesh(argv[i]);
    if (!mesh.ok()) {
      std::fprintf(stderr, "%s: %s\n", argv[i], mesh.status().message().c_str());
      return 1;
    }
    auto support = pb::MeasureSupport(mesh->mesh, points->points, pb::SupportOptions());
    if (!support.ok()) {
      std::fprintf(stderr, "%s: %s\n", argv[i], support.status().message().c_str());
      return 1;
    }
    // Boundary loops by perimeter: holes a viewer sees as pin-holes (under
    // 10 cm) and the rest.
    const pb::Mesh& m = mesh->mesh;
    int small_loops = 0, loops = 0;
    size_t loop_edges = 0;
    for (const auto& loop : pb::BoundaryLoops(m)) {
      double perimeter = 0;
      for (size_t k = 0; k < loop.size(); ++k) {
        const uint32_t a = loop[k], b = loop[(k + 1) % loop.size()];
        double d2 = 0;
        for (int c = 0; c < 3; ++c) {
          const double d = double{m.positions[3 * size_t{a} + c]} - m.positions[3 * size_t{b} + c];
          d2 += d * d;
        }
        perimeter += std::sqrt(d2);
      }
      ++loops;
      loop_edges += loop.size();
      small_loops += perimeter < 0.1;
    }
    // Connected components (faces sharing vertices).
    std::vector<uint32_t> parent(m.vertex_count());
    for (size_t v = 0; v < parent.size(); ++v) parent[v] = static_cast<uint32_t>(v);
    const auto find = [&](uint32_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    for (size_t f = 0; f < m.face_count(); ++f) {
      for (int k = 1; k < 3; ++k) {
        const uint32_t a = find(m.indices[3 * f]), b = find(m.indices[3 * f + k]);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
    }
    int components = 0;
    for (size_t v = 0; v < parent.size(); ++v) components += find(static_cast<uint32_t>(v)) == v;
    std::printf("{\"components\": %d, ", components);
    std::printf(
        "\"mesh\": \"%s\", \"faces\": %llu, \"area_m2\": %.4f, \"invented_fraction\": %.4f, "
        "\"boundary_edges\": %llu, \"boundary_edges_per_1000_faces\": %.1f, "
        "\"mean_edge_m\": %.4f, \"boundary_loops\": %d, \"loops_under_10cm\": %d, \"edges_in_loops\": %zu}\n",
        argv[i], static_cast<unsigned long long>(support->faces), support->area_m2,
        support->invented_fraction, static_cast<unsigned long long>(support->boundary_edges),
        support->boundary_edges_per_1000_faces, support->mean_edge_m, loops, small_loops, loop_edges);
  }
  return 0;
}
