// decimate_bench: mesh.decimate on ~5·10^6 faces down to 2.5·10^5: a unit
// icosphere (5,242,880 faces) and the synthetic room's true surface at 7 mm
// cells. Prints the time and peak RSS of the decimation alone (the peak is
// reset after generating the input, where the kernel allows it), the
// collapse counts, and whether the result is manifold (docs/mesh.md).
//
//   decimate_bench [TARGET_FACES=250000]
#include <cstdio>
#include <cstdlib>

#include "bench/bench_clock.h"
#include "stages/geometry/mesh/clean.h"
#include "stages/geometry/mesh/decimate.h"
#include "stages/geometry/synth/scene.h"
#include "stages/geometry/testing/meshes.h"

namespace {

void MeasureLarge(const char* name, const pb::Mesh& mesh, size_t target_faces) {
  pb::bench::ResetPeakRss();
  const auto start = pb::bench::Clock::now();
  pb::DecimateReport report;
  pb::DecimateOptions options;
  options.target_faces = target_faces;
  const pb::Expected<pb::Mesh> decimated = pb::DecimateMesh(mesh, options, &report);
  const double seconds = pb::bench::Seconds(start);
  if (!decimated.ok()) {
    std::printf("%s: %s\n", name, decimated.status().message().c_str());
    return;
  }
  const pb::Mesh& out = *decimated;
  const pb::Status manifold = pb::CheckManifold(out);
  std::printf(
      "%s: %zu -> %zu faces in %.2f s, peak RSS %.0f MiB (collapses %llu, rejected link %llu "
      "flip %llu degenerate %llu), %s\n",
      name, mesh.face_count(), out.face_count(), seconds,
      pb::bench::StatusBytes("VmHWM:") / (1 << 20),
      static_cast<unsigned long long>(report.collapses),
      static_cast<unsigned long long>(report.rejected_link),
      static_cast<unsigned long long>(report.rejected_flip),
      static_cast<unsigned long long>(report.rejected_degenerate),
      manifold.ok() ? "manifold" : manifold.message().c_str());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  const size_t target = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 250000;
  MeasureLarge("icosphere", pb::testing::Icosphere(9), target);
  auto scene = pb::MakeSynthScene("room", 1, {});
  if (!scene.ok()) {
    std::fprintf(stderr, "%s\n", scene.status().message().c_str());
    return 1;
  }
  MeasureLarge("synth room, 7 mm cells", pb::SynthTruthMesh(*scene, 0.007), target);
  return 0;
}
