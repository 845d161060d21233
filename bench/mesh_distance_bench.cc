// mesh_distance_bench: metrics.geometry's distance measurement and
// mesh.clean on a ~10^6-face mesh: the synthetic room's true surface at
// 15.5 mm cells measured against the analytic truth (and its 10 mm mesh),
// then against the 10 mm mesh alone, 200k samples per direction, 2 threads;
// then CleanMesh of the same mesh (docs/mesh.md).
//
//   mesh_distance_bench [SAMPLES=200000] [THREADS=2]
#include <tbb/task_arena.h>

#include <cstdio>
#include <cstdlib>

#include "bench/bench_clock.h"
#include "stages/geometry/mesh/clean.h"
#include "stages/geometry/mesh/distance.h"
#include "stages/geometry/synth/scene.h"

namespace {

int Fail(const pb::Status& status) {
  std::fprintf(stderr, "error: %s\n", status.message().c_str());
  return 1;
}

void Print(const char* what, const pb::MeshDistanceResult& r, double seconds) {
  std::printf("%s: %.2f s; mesh->truth mean %.5f m rms %.5f m p95 %.5f m max %.5f m; "
              "truth->mesh mean %.5f m max %.5f m\n",
              what, seconds, r.mesh_to_truth.mean_m, r.mesh_to_truth.rms_m,
              r.mesh_to_truth.p95_m, r.mesh_to_truth.max_m, r.truth_to_mesh.mean_m,
              r.truth_to_mesh.max_m);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pb;
  MeshDistanceOptions options;
  options.samples = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 200000;
  const int threads = argc > 2 ? std::atoi(argv[2]) : 2;
  Expected<SynthScene> scene = MakeSynthScene("room", 1, {});
  if (!scene.ok()) return Fail(scene.status());
  const Mesh truth = SynthTruthMesh(*scene, 0.01);
  const Mesh mesh = SynthTruthMesh(*scene, 0.0155);
  std::printf("mesh faces %zu, truth mesh faces %zu\n", mesh.face_count(), truth.face_count());
  tbb::task_arena arena(threads);
  for (const bool analytic : {true, false}) {
    Expected<MeshDistanceResult> result = Status::Internal("not run");
    const auto start = bench::Clock::now();
    arena.execute([&] {
      result = MeasureMeshDistance(mesh, truth, analytic ? &*scene : nullptr, options);
    });
    if (!result.ok()) return Fail(result.status());
    Print(analytic ? "analytic truth" : "truth mesh only", *result, bench::Seconds(start));
  }
  CleanReport report;
  const auto start = bench::Clock::now();
  Expected<Mesh> cleaned = CleanMesh(mesh, {}, &report);
  if (!cleaned.ok()) return Fail(cleaned.status());
  std::printf("clean: %.2f s, faces_out %llu, split vertices %llu, small component faces %llu\n",
              bench::Seconds(start), (unsigned long long)report.faces_out,
              (unsigned long long)report.split_vertices,
              (unsigned long long)report.small_component_faces);
  return 0;
}
