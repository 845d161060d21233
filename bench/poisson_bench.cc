// poisson_bench: one screened Poisson reconstruction, measured the same way
// for both candidate implementations, printed as one JSON line.
//   poisson_bench --backend open3d|pcl --depth D --points points.ply
//                 --truth truth_dir [--threads N] [--trim Q] [--out mesh.ply]
// `truth_dir` is a synth.scan truth output (mesh.ply + scene.json). Run it
// once per process: peak RSS is the process's (getrusage), cloud included.
// Both run through ReconstructPoisson, as mesh.poisson's `implementation`
// does: Open3D in pointbake-poisson-open3d.so, PCL (its defaults: point
// weight 4, degree 2, 1.5 samples per node) in pointbake-pcl.so, built when
// libpcl-dev is installed. bench/poisson.sh drives it.
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "stages/geometry/mesh/clean.h"
#include "stages/geometry/mesh/distance.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/mesh/poisson.h"
#include "stages/geometry/mesh/trim.h"
#include "stages/geometry/synth/scene.h"

namespace {

[[noreturn]] void Die(const std::string& message) {
  std::fprintf(stderr, "poisson_bench: %s\n", message.c_str());
  std::exit(1);
}

}  // namespace

int main(int argc, char** argv) {
  std::string backend = "open3d", points_path, truth_dir, out_path;
  int depth = 8, threads = 2;
  double trim = 0;  // Open3D only: density quantile, as mesh.poisson's `trim`
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto next = [&]() -> std::string {
      if (i + 1 >= argc) Die("missing value after " + arg);
      return argv[++i];
    };
    if (arg == "--backend") backend = next();
    else if (arg == "--depth") depth = std::stoi(next());
    else if (arg == "--points") points_path = next();
    else if (arg == "--truth") truth_dir = next();
    else if (arg == "--threads") threads = std::stoi(next());
    else if (arg == "--trim") trim = std::stod(next());
    else if (arg == "--out") out_path = next();
    else Die("unknown argument " + arg);
  }
  if (points_path.empty() || truth_dir.empty()) Die("need --points and --truth");
  if (backend != "open3d" && backend != "pcl") Die("--backend is open3d or pcl");

  auto points = pb::ReadPlyPoints(points_path);
  if (!points.ok()) Die(points.status().message());
  const pb::PointCloud& cloud = points->points;

  const auto start = std::chrono::steady_clock::now();
  if (backend == "pcl" && trim > 0) Die("--trim needs densities: Open3D only");
  pb::PoissonOptions options;
  options.implementation =
      backend == "pcl" ? pb::PoissonImplementation::kPcl : pb::PoissonImplementation::kOpen3d;
  options.depth = depth;
  options.threads = threads;
  auto out = pb::ReconstructPoisson(cloud, options);
  if (!out.ok()) Die(out.status().message());
  pb::Mesh mesh = trim > 0 ? pb::TrimByDensity(std::move(out->mesh), out->densities, trim, nullptr)
                           : std::move(out->mesh);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const double peak_mib = static_cast<double>(usage.ru_maxrss) / 1024.0;

  pb::CleanReport clean;
  auto cleaned = pb::CleanMesh(mesh, pb::CleanOptions(), &clean);
  if (!cleaned.ok()) Die(cleaned.status().message());
  const bool manifold = pb::CheckManifold(mesh).ok();

  auto truth = pb::ReadPlyMesh(truth_dir + "/mesh.ply");
  if (!truth.ok()) Die(truth.status().message());
  auto scene = pb::ReadSynthScene(truth_dir + "/scene.json");
  if (!scene.ok()) Die(scene.status().message());
  pb::MeshDistanceOptions distance_options;
  distance_options.samples = 200000;
  auto distance = pb::MeasureMeshDistance(mesh, truth->mesh, &*scene, distance_options);
  if (!distance.ok()) Die(distance.status().message());
  if (!out_path.empty()) {
    if (auto status = pb::WritePlyMesh(out_path, mesh); !status.ok()) Die(status.message());
  }

  std::printf(
      "{\"backend\": \"%s\", \"depth\": %d, \"trim\": %g, \"threads\": %d, \"points\": %zu, \"seconds\": %.2f, "
      "\"peak_rss_mib\": %.0f, \"faces\": %zu, \"boundary_edges\": %zu, \"manifold\": %s, "
      "\"nonmanifold_edge_faces\": %llu, \"small_components\": %llu, "
      "\"mesh_to_truth_mean_mm\": %.2f, \"mesh_to_truth_p95_mm\": %.2f, "
      "\"truth_to_mesh_mean_mm\": %.2f, \"truth_to_mesh_p95_mm\": %.2f, \"hausdorff_mm\": %.1f}\n",
      backend.c_str(), depth, trim, threads, cloud.size(), seconds, peak_mib, mesh.face_count(),
      static_cast<size_t>(pb::CountBoundaryEdges(mesh)), manifold ? "true" : "false",
      static_cast<unsigned long long>(clean.nonmanifold_edge_faces),
      static_cast<unsigned long long>(clean.small_components),
      distance->mesh_to_truth.mean_m * 1e3, distance->mesh_to_truth.p95_m * 1e3,
      distance->truth_to_mesh.mean_m * 1e3, distance->truth_to_mesh.p95_m * 1e3,
      distance->symmetric.max_m * 1e3);
  return 0;
}
