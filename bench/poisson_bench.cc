// poisson_bench: one screened Poisson reconstruction, measured the same way
// for both candidate implementations, printed as one JSON line.
//   poisson_bench --backend open3d|pcl --depth D --points points.ply
//                 --truth truth_dir [--threads N] [--point-weight W]
//                 [--samples-per-node S] [--trim Q] [--out mesh.ply]
// `truth_dir` is a synth.scan truth output (mesh.ply + scene.json). Run it
// once per process: peak RSS is the process's (getrusage), cloud included.
// Built with -DPB_BENCH_PCL=ON (needs libpcl-dev); bench/poisson.sh drives it.
#include <pcl/point_types.h>
#include <pcl/surface/poisson.h>
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
#include "stages/geometry/synth/scene.h"

namespace {

[[noreturn]] void Die(const std::string& message) {
  std::fprintf(stderr, "poisson_bench: %s\n", message.c_str());
  std::exit(1);
}

pb::Mesh RunPcl(const pb::PointCloud& cloud, int depth, int threads, float point_weight,
                float samples_per_node) {
  auto input = std::make_shared<pcl::PointCloud<pcl::PointNormal>>();
  input->resize(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    pcl::PointNormal& p = (*input)[i];
    p.x = cloud.positions[3 * i];
    p.y = cloud.positions[3 * i + 1];
    p.z = cloud.positions[3 * i + 2];
    p.normal_x = cloud.normals[3 * i];
    p.normal_y = cloud.normals[3 * i + 1];
    p.normal_z = cloud.normals[3 * i + 2];
  }
  pcl::Poisson<pcl::PointNormal> poisson;
  poisson.setDepth(depth);
  poisson.setThreads(threads);
  poisson.setPointWeight(point_weight);
  poisson.setSamplesPerNode(samples_per_node);
  poisson.setScale(1.1f);
  poisson.setInputCloud(input);
  pcl::PointCloud<pcl::PointNormal> vertices;
  std::vector<pcl::Vertices> polygons;
  poisson.reconstruct(vertices, polygons);
  pb::Mesh mesh;
  mesh.origin = cloud.origin;
  for (const pcl::PointNormal& v : vertices) {
    mesh.positions.insert(mesh.positions.end(), {v.x, v.y, v.z});
  }
  for (const pcl::Vertices& polygon : polygons) {
    for (size_t k = 1; k + 1 < polygon.vertices.size(); ++k) {
      for (const size_t corner : {size_t{0}, k, k + 1}) {
        mesh.indices.push_back(static_cast<uint32_t>(polygon.vertices[corner]));
      }
    }
  }
  return mesh;
}

size_t BoundaryEdges(const pb::Mesh& mesh) {
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  edges.reserve(mesh.indices.size());
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    for (int k = 0; k < 3; ++k) {
      uint32_t a = mesh.indices[3 * f + k], b = mesh.indices[3 * f + (k + 1) % 3];
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  size_t boundary = 0;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    boundary += j - i == 1;
    i = j;
  }
  return boundary;
}

}  // namespace

int main(int argc, char** argv) {
  std::string backend = "open3d", points_path, truth_dir, out_path;
  int depth = 8, threads = 2;
  float point_weight = 4, samples_per_node = 1.5f;
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
    else if (arg == "--point-weight") point_weight = std::stof(next());
    else if (arg == "--samples-per-node") samples_per_node = std::stof(next());
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
  pb::Mesh mesh;
  if (backend == "open3d") {
    pb::PoissonOptions options;
    options.depth = depth;
    options.threads = threads;
    auto out = pb::ReconstructPoisson(cloud, options);
    if (!out.ok()) Die(out.status().message());
    mesh = pb::TrimByDensity(std::move(out->mesh), out->densities, trim, nullptr);
  } else {
    if (trim > 0) Die("--trim needs densities: Open3D only");
    mesh = RunPcl(cloud, depth, threads, point_weight, samples_per_node);
  }
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
      BoundaryEdges(mesh), manifold ? "true" : "false",
      static_cast<unsigned long long>(clean.nonmanifold_edge_faces),
      static_cast<unsigned long long>(clean.small_components),
      distance->mesh_to_truth.mean_m * 1e3, distance->mesh_to_truth.p95_m * 1e3,
      distance->truth_to_mesh.mean_m * 1e3, distance->truth_to_mesh.p95_m * 1e3,
      distance->symmetric.max_m * 1e3);
  return 0;
}
