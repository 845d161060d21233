// bake_from_mesh_bench: bake.from_mesh (ray casting from a high mesh, the
// Remeshing workflow's bake) at the scale of docs/bake-from-mesh.md: a
// 240k-face low mesh, a 5·10^6-face high mesh over the same wavy sheet,
// 4096^2 maps, all cores. Prints the BVH build and ray times (wall and CPU),
// rays per CPU-second, hits and fallbacks.
//
//   bake_from_mesh_bench [SIZE=4096]
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "bench/bench_clock.h"
#include "stages/geometry/bake/from_mesh.h"
#include "stages/geometry/testing/meshes.h"

int main(int argc, char** argv) {
  using namespace pb;
  const auto wave = [](double x, double y) {
    return 0.01 * std::sin(40 * x) * std::cos(31 * y) + 0.002 * std::sin(400 * x + 300 * y);
  };
  const auto start = bench::Clock::now();
  Mesh high = testing::Sheet(-0.01, 1.01, -0.01, 1.01, 1582, wave, [](double x, double y) {
    return std::array<uint8_t, 3>{uint8_t(std::clamp(x, 0.0, 1.0) * 255),
                                  uint8_t(std::clamp(y, 0.0, 1.0) * 255),
                                  uint8_t(128 + 100 * std::sin(90 * x))};
  });
  Mesh low = testing::LowGrid(346);
  for (size_t v = 0; v < low.vertex_count(); ++v) {
    low.positions[3 * v + 2] = float(wave(low.positions[3 * v], low.positions[3 * v + 1]));
  }
  const double make_s = bench::Seconds(start);
  BakeOptions options;
  options.size = argc > 1 ? std::atoi(argv[1]) : 4096;
  options.threads = 0;
  FromMeshReport report;
  const auto bake_start = bench::Clock::now();
  auto result = BakeFromMesh(std::move(low), high, options, {}, &report);
  const double bake_s = bench::Seconds(bake_start);
  if (!result.ok()) {
    std::fprintf(stderr, "%s\n", result.status().message().c_str());
    return 1;
  }
  std::printf(
      "low %zu faces, high %zu faces, %d^2: meshes made in %.2f s; bake %.2f s wall (BVH %.2f s "
      "wall, %.2f s CPU; rays %.2f s wall, %.2f s CPU for %zu rays = %.1f Mrays per CPU-second); "
      "hit %zu, fallback %zu, mean distance %.5f m, gutter %zu\n",
      result->mesh.face_count(), high.face_count(), options.size, make_s, bake_s,
      report.build_seconds, report.build_cpu_seconds, report.ray_seconds, report.ray_cpu_seconds,
      report.rays_cast, report.rays_cast / report.ray_cpu_seconds * 1e-6, report.texels_hit,
      report.texels_fallback, report.mean_hit_distance_m, result->gutter_texels);
  return 0;
}
