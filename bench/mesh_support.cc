// mesh_support: how much of a mesh the scan supports, the figures of issue
// 15 (docs/mesh-real-scans.md): invented area (the fraction of the mesh's
// area farther than max(3 x local spacing, mean edge length) from every scan
// point; MeasureSupport in stages/geometry/mesh/trim.h), boundary edges per
// 1000 faces, faces.
//   build/bench/mesh_support POINTS.ply MESH.ply [MESH.ply ...]
// Prints one JSON line per mesh.
#include <cstdio>
#include <string>

#include "stages/geometry/io/ply.h"
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
    std::printf(
        "{\"mesh\": \"%s\", \"faces\": %llu, \"area_m2\": %.4f, \"invented_fraction\": %.4f, "
        "\"boundary_edges\": %llu, \"boundary_edges_per_1000_faces\": %.1f, "
        "\"mean_edge_m\": %.4f}\n",
        argv[i], static_cast<unsigned long long>(support->faces), support->area_m2,
        support->invented_fraction, static_cast<unsigned long long>(support->boundary_edges),
        support->boundary_edges_per_1000_faces, support->mean_edge_m);
  }
  return 0;
}
