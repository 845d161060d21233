// point_assign_bench: AssignPointsToFaces (stages/geometry/bake/point_assign.h) on
// the synthetic room, for docs/bench-point-assign.md.
//
//   point_assign_bench prepare DIR POINTS [FACES]
//     scans the "room" preset with the simulated scanner (POINTS returns),
//     gives every point its true surface normal (SampleSurface), measures the
//     point spacing (spacing.h), builds the low mesh (SynthTruthMesh at 2 cm,
//     DecimateMesh to FACES, default 250000, UnwrapMesh at 4096) and writes
//     DIR/cloud.ply, DIR/low.ply and DIR/info.txt (the spacing).
//   point_assign_bench run DIR SPACINGS ANGLE_DEG [THREADS] [SIZE]
//     reads them, drops the station ids (the cloud is then positions +
//     normals + colors, 27 bytes a point), resets the peak-RSS counter and
//     assigns with max_distance = SPACINGS x spacing; prints one Markdown row:
//     wall and CPU seconds of the assignment, RSS before, peak RSS during it
//     and the cloud's size, and the counts of the report.

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include <tbb/parallel_for.h>

#include "stages/geometry/mesh/decimate.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/bake/point_assign.h"
#include "stages/geometry/points/spacing.h"
#include "bench/bench_clock.h"
#include "stages/geometry/synth/scanner.h"
#include "stages/geometry/synth/scene.h"
#include "stages/geometry/uv/atlas.h"

namespace {

using pb::bench::Clock;
using pb::bench::CpuSeconds;
using pb::bench::Seconds;

using pb::bench::StatusBytes;

int Fail(const pb::Status& status) {
  std::fprintf(stderr, "error: %s\n", status.message().c_str());
  return 1;
}

int Prepare(const std::string& dir, uint64_t points, size_t faces) {
  auto start = Clock::now();
  auto scene = pb::MakeSynthScene("room", 1);
  if (!scene.ok()) return Fail(scene.status());
  pb::SynthScanOptions scan_options;
  scan_options.target_points = points;
  auto scan = pb::SimulateScan(*scene, scan_options);
  if (!scan.ok()) return Fail(scan.status());
  pb::PointCloud& cloud = scan->cloud;
  std::fprintf(stderr, "scan: %zu points, %.1f s\n", cloud.size(), Seconds(start));
  start = Clock::now();
  cloud.normals.resize(cloud.positions.size());
  tbb::parallel_for(size_t(0), cloud.size(), [&](size_t i) {
    const pb::Vec3 p = {cloud.origin[0] + cloud.positions[3 * i], cloud.origin[1] + cloud.positions[3 * i + 1],
                        cloud.origin[2] + cloud.positions[3 * i + 2]};
    const pb::SurfaceSample sample = pb::SampleSurface(*scene, p);
    for (int k = 0; k < 3; ++k) cloud.normals[3 * i + k] = float(sample.normal[k]);
  });
  std::fprintf(stderr, "true normals: %.1f s\n", Seconds(start));
  start = Clock::now();
  auto spacing = pb::MedianSpacing(cloud);
  if (!spacing.ok()) return Fail(spacing.status());
  std::fprintf(stderr, "spacing %.5f m (scanner estimate %.5f m): %.1f s\n", *spacing, scan->median_spacing_m,
               Seconds(start));
  if (auto s = pb::WritePlyPoints(dir + "/cloud.ply", cloud); !s.ok()) return Fail(s);

  start = Clock::now();
  const pb::Mesh truth = pb::SynthTruthMesh(*scene, 0.02);
  pb::DecimateOptions decimate;
  decimate.target_faces = faces;
  pb::DecimateReport decimate_report;
  auto low = pb::DecimateMesh(truth, decimate, &decimate_report);
  if (!low.ok()) return Fail(low.status());
  pb::UnwrapOptions unwrap;
  pb::AtlasReport atlas;
  auto unwrapped = pb::UnwrapMesh(*low, unwrap, &atlas);
  if (!unwrapped.ok()) return Fail(unwrapped.status());
  std::fprintf(stderr, "low mesh: truth %zu faces -> %zu, unwrapped: %.1f s\n", truth.face_count(),
               unwrapped->face_count(), Seconds(start));
  if (auto s = pb::WritePlyMesh(dir + "/low.ply", *unwrapped); !s.ok()) return Fail(s);
  std::ofstream(dir + "/info.txt") << *spacing << "\n" << scan->median_spacing_m << "\n";
  return 0;
}

int Run(const std::string& dir, double spacings, double angle_deg, int threads, int size) {
  double spacing = 0;
  std::ifstream(dir + "/info.txt") >> spacing;
  if (!(spacing > 0)) return Fail(pb::Status::Invalid(dir + "/info.txt: no spacing (run prepare first)"));
  auto low = pb::ReadPlyMesh(dir + "/low.ply");
  if (!low.ok()) return Fail(low.status());
  auto read = pb::ReadPlyPoints(dir + "/cloud.ply");
  if (!read.ok()) return Fail(read.status());
  pb::PointCloud cloud = std::move(read->points);
  cloud.station_ids = {};
  cloud.stations.clear();
  const double cloud_bytes = double(cloud.positions.size() * 4 + cloud.normals.size() * 4 + cloud.colors.size());
  const size_t faces = low->mesh.face_count();
  const double rss_before = StatusBytes("VmRSS:");
  pb::bench::ResetPeakRss();

  pb::AssignOptions options;
  options.max_distance_m = spacings * spacing;
  options.max_angle_deg = angle_deg;
  options.threads = threads;
  options.size = size;
  pb::AssignReport report;
  const double cpu0 = CpuSeconds();
  const auto start = Clock::now();
  auto mapped = pb::AssignPointsToFaces(low->mesh, std::move(cloud), options, &report);
  const double wall = Seconds(start), cpu = CpuSeconds() - cpu0;
  if (!mapped.ok()) return Fail(mapped.status());
  const double peak = StatusBytes("VmHWM:"), rss_after = StatusBytes("VmRSS:");
  const double n = double(report.points);
  std::printf("| %zu | %zu | %.1f (%.2f mm) | %.0f | %d | %.2f | %.2f | %.0f | %.0f | %.0f | %.0f | %.1f%% | %.1f%% | %.1f%% | %.2f |\n",
              report.points, faces, spacings, 1e3 * options.max_distance_m, angle_deg, threads, wall, cpu,
              cloud_bytes / 1e6, rss_before / 1e6, peak / 1e6, rss_after / 1e6, 100 * report.assigned / n,
              100 * report.too_far / n, 100 * report.wrong_angle / n, 1e3 * report.mean_distance_m);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "prepare" && argc >= 4)
    return Prepare(argv[2], std::strtoull(argv[3], nullptr, 10), argc > 4 ? std::strtoull(argv[4], nullptr, 10) : 250000);
  if (mode == "run" && argc >= 5)
    return Run(argv[2], std::atof(argv[3]), std::atof(argv[4]), argc > 5 ? std::atoi(argv[5]) : 0,
               argc > 6 ? std::atoi(argv[6]) : 4096);
  if (mode == "header") {
    std::printf("| points | faces | max distance, spacings (mm) | max angle | threads | wall s | CPU s | cloud MB | RSS before MB | peak RSS MB | RSS after MB | assigned | too far | wrong angle | mean dist mm |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    return 0;
  }
  std::fprintf(stderr,
               "usage: point_assign_bench prepare DIR POINTS [FACES]\n"
               "       point_assign_bench run DIR SPACINGS ANGLE_DEG [THREADS] [SIZE]\n"
               "       point_assign_bench header\n");
  return 2;
}
