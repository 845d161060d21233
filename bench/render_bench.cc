// render_bench: the reference renderer (stages/geometry/render/render.h) on an
// HPM-size mesh and a textured LPM-size mesh of the synthetic room, and the
// analytic truth, from the room scene's three viewpoints
// (configs/scenes/synthetic-room.yaml). Figures in docs/render.md.
//
//   render_bench [cell_m=0.0065] [threads=2] [size=1024] [out_dir]
//
// cell_m 0.0065 gives the room's truth mesh 5.5 M faces. With out_dir, the
// frames are written there as PNGs.
#include <tbb/task_arena.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "stages/geometry/core/image.h"
#include "bench/bench_clock.h"
#include "stages/geometry/render/render.h"
#include "stages/geometry/synth/scene.h"
#include "stages/geometry/core/tangents.h"

namespace {

using pb::bench::Clock;
using pb::bench::CpuSeconds;
using pb::bench::Seconds;

struct Viewpoint {
  const char* name;
  std::array<double, 3> eye, target;
  double fov_deg;
};

const Viewpoint kViews[] = {{"door", {-1.2, -1.9, 1.6}, {1.5, 1.5, 1.2}, 75},
                            {"corner", {2.6, 1.9, 2.4}, {-1.5, -1.0, 0.8}, 70},
                            {"window_wall", {0.0, -1.5, 1.5}, {0.0, 2.25, 1.6}, 60}};

pb::Image Noise(int size, uint32_t seed, bool normal) {
  pb::Image image = pb::Image::Make(size, size, 3, pb::Image::PixelType::kU8);
  for (size_t i = 0; i < image.data.size(); ++i) {
    seed = seed * 1664525u + 1013904223u;
    image.data[i] = normal ? uint8_t(i % 3 == 2 ? 240 : 108 + (seed >> 27)) : uint8_t(seed >> 24);
  }
  return image;
}

}  // namespace

int main(int argc, char** argv) {
  const double cell_m = argc > 1 ? std::atof(argv[1]) : 0.0065;
  const int threads = argc > 2 ? std::atoi(argv[2]) : 2;
  const int size = argc > 3 ? std::atoi(argv[3]) : 1024;
  const std::string out_dir = argc > 4 ? argv[4] : "";
  const pb::SynthScene scene = pb::MakeSynthScene("room", 1).value();
  tbb::task_arena arena(threads);

  auto start = Clock::now();
  pb::Mesh hpm;
  arena.execute([&] { hpm = pb::SynthTruthMesh(scene, cell_m); });
  std::printf("truth mesh at %.4f m: %zu faces, %zu vertices (%.2f s to build)\n", cell_m, hpm.face_count(),
              hpm.vertex_count(), Seconds(start));

  // LPM-like: the room at 5 cm cells with planar uvs and a 4096^2 color and
  // normal map (noise: the cost does not depend on the content).
  pb::Mesh lpm = pb::SynthTruthMesh(scene, 0.05);
  for (size_t v = 0; v < lpm.vertex_count(); ++v) {
    const float* p = &lpm.positions[v * 3];
    lpm.uvs.push_back((p[0] + p[1]) / 12.0f + 0.5f);
    lpm.uvs.push_back(p[2] / 4.0f + (p[0] - p[1]) / 24.0f);
  }
  lpm.tangents = pb::ComputeTangents(lpm).value();
  start = Clock::now();
  pb::MipTexture color, normal;
  arena.execute([&] {
    color = pb::BuildColorTexture(Noise(4096, 1, false)).value();
    normal = pb::BuildNormalTexture(Noise(4096, 2, true)).value();
  });
  std::printf("LPM-like mesh: %zu faces; 4096^2 color + normal mip chains built in %.2f s\n", lpm.face_count(),
              Seconds(start));

  pb::RenderOptions options;  // supersample 2 (4 samples), lambert
  pb::RenderOptions truth_options = options;
  truth_options.supersample = 4;
  double total_hpm = 0, total_lpm = 0, total_truth = 0;
  double cpu[3] = {0, 0, 0};
  for (const Viewpoint& view : kViews) {
    pb::RenderCamera camera;
    camera.eye = view.eye;
    camera.target = view.target;
    camera.fov_deg = view.fov_deg;
    camera.size = size;
    pb::Image images[3];
    double seconds[3];
    for (int k = 0; k < 3; ++k) {
      start = Clock::now();
      const double cpu_start = CpuSeconds();
      arena.execute([&] {
        if (k == 0) images[k] = pb::RenderMesh(hpm, {}, camera, options).value();
        if (k == 1) images[k] = pb::RenderMesh(lpm, {&color, &normal}, camera, options).value();
        if (k == 2) images[k] = pb::RenderSynthScene(scene, camera, truth_options).value();
      });
      seconds[k] = Seconds(start);
      cpu[k] += CpuSeconds() - cpu_start;
    }
    total_hpm += seconds[0];
    total_lpm += seconds[1];
    total_truth += seconds[2];
    std::printf("%-12s HPM %.3f s   LPM textured %.3f s   truth (16 spp) %.3f s\n", view.name, seconds[0],
                seconds[1], seconds[2]);
    if (!out_dir.empty()) {
      const char* kinds[3] = {"hpm", "lpm", "truth"};
      for (int k = 0; k < 3; ++k)
        (void)pb::WritePng(out_dir + "/" + view.name + "_" + kinds[k] + ".png", images[k]);
    }
  }
  std::printf("3 viewpoints, %d^2, %d threads: HPM %.2f s, LPM textured %.2f s, truth %.2f s\n", size, threads,
              total_hpm, total_lpm, total_truth);
  std::printf("CPU time (all threads): HPM %.2f s, LPM textured %.2f s, truth %.2f s\n", cpu[0], cpu[1], cpu[2]);
  return 0;
}
