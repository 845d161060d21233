// fit_bench: mesh.fit's FitMeshToPoints on a mesh and its scan written by a
// workflow (docs/bench-fit.md, bench/fit.sh).
//
//   fit_bench [--normals] MESH.ply POINTS.ply [THREADS=2] [EXPECTED.ply]
//
// Reads both (pointbake PLY, e.g. a workflow's `outputs:` of a decimated
// mesh and the points it is fitted to), fits with the stage's defaults
// (with --normals: along the vertex normals only, version 3's fit) on
// THREADS threads and prints one line: wall and CPU seconds of the fit alone
// (reading excluded), peak RSS, the point and face counts, the report's mean
// |distance| before and after, and an XXH3-128 digest of the output positions'
// bytes. With EXPECTED (the same fit's output from another build), also
// whether every output coordinate is bit-identical to it: a speed-up of the
// fit that changes no output says so here.
//
// Then the nearest-face search alone, TriangleBvh's two engines in the same
// run (the ratio is the figure; docs/bench-fit.md): every point's nearest
// face of the fitted mesh without a hint, then with the input mesh's
// nearest face as the hint (as the fit's rounds do), each on THREADS
// threads; and whether both engines give the same faces and distances.
#include <tbb/task_arena.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>

#include "base/hash.h"
#include "bench/bench_clock.h"
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <vector>

#include "stages/geometry/io/ply.h"
#include "stages/geometry/mesh/distance.h"
#include "stages/geometry/mesh/fit.h"

namespace {

int Fail(const std::string& what, const pb::Status& status) {
  std::fprintf(stderr, "fit_bench: %s: %s\n", what.c_str(), status.message().c_str());
  return 1;
}

// Seconds to find every point's nearest face of `bvh` (hints may be empty).
double TimeNearest(const pb::TriangleBvh& bvh, const std::vector<pb::Vec3>& points,
                   const std::vector<uint32_t>& hints, std::vector<pb::TriangleBvh::Hit>& hits) {
  hits.assign(points.size(), {});
  const auto start = pb::bench::Clock::now();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 1024),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t i = r.begin(); i < r.end(); ++i) {
                        hits[i] = bvh.Nearest(points[i], hints.empty() ? UINT32_MAX : hints[i]);
                      }
                    });
  return pb::bench::Seconds(start);
}

// The engines' comparison (see the top): prints one line per kind of query.
bool CompareEngines(const pb::Mesh& input, const pb::Mesh& fitted, const pb::PointCloud& cloud) {
  using pb::TriangleBvh;
  std::vector<pb::Vec3> points(cloud.size());
  for (size_t i = 0; i < points.size(); ++i) {
    for (int a = 0; a < 3; ++a) points[i][a] = cloud.positions[3 * i + a] + cloud.origin[a];
  }
  std::vector<TriangleBvh::Hit> hits;
  std::vector<uint32_t> hints(points.size());
  {
    const TriangleBvh before(input);
    TimeNearest(before, points, {}, hits);
    for (size_t i = 0; i < hits.size(); ++i) hints[i] = hits[i].face;
  }
  const TriangleBvh embree(fitted, TriangleBvh::Engine::kEmbree);
  const TriangleBvh builtin(fitted, TriangleBvh::Engine::kBuiltin);
  if (embree.engine() != TriangleBvh::Engine::kEmbree) {
    std::printf("nearest: Embree could not be set up\n");
    return false;
  }
  bool same = true;
  for (const bool hinted : {false, true}) {
    std::vector<TriangleBvh::Hit> a, b;
    const std::vector<uint32_t> none;
    const double te = TimeNearest(embree, points, hinted ? hints : none, a);
    const double tb = TimeNearest(builtin, points, hinted ? hints : none, b);
    size_t differ = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      differ += a[i].face != b[i].face || a[i].squared_distance_m2 != b[i].squared_distance_m2 ||
                a[i].closest != b[i].closest;
    }
    same = same && differ == 0;
    std::printf("nearest %s: built-in %.2f s, Embree %.2f s (%.2fx); %zu of %zu answers differ\n",
                hinted ? "with the input's face as hint" : "without hint", tb, te, tb / te, differ,
                a.size());
  }
  return same;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pb;
  const bool along_normals = argc > 1 && std::string_view(argv[1]) == "--normals";
  if (along_normals) {
    argv[1] = argv[0];
    ++argv;
    --argc;
  }
  if (argc < 3 || argc > 5) {
    std::fprintf(stderr,
                 "usage: fit_bench [--normals] MESH.ply POINTS.ply [THREADS=2] [EXPECTED.ply]\n");
    return 2;
  }
  const int threads = argc > 3 ? std::atoi(argv[3]) : 2;
  if (threads < 1) {
    std::fprintf(stderr, "fit_bench: THREADS must be >= 1, got '%s'\n", argv[3]);
    return 2;
  }
  auto mesh = ReadPlyMesh(argv[1]);
  if (!mesh.ok()) return Fail(argv[1], mesh.status());
  auto points = ReadPlyPoints(argv[2]);
  if (!points.ok()) return Fail(argv[2], points.status());

  FitOptions options;
  options.threads = threads;
  options.free_directions = !along_normals;
  FitReport report;
  bench::ResetPeakRss();
  const double cpu0 = bench::CpuSeconds();
  const auto start = bench::Clock::now();
  auto fitted = FitMeshToPoints(mesh->mesh, points->points, options, &report);
  const double wall = bench::Seconds(start);
  const double cpu = bench::CpuSeconds() - cpu0;
  if (!fitted.ok()) return Fail("fit", fitted.status());
  const std::vector<float>& out = fitted->positions;
  bool ok = true;
  std::printf("fit: %.2f s wall, %.2f s CPU, peak RSS %.0f MB; %llu points, %zu faces; "
              "mean |d| %.6f -> %.6f m; positions xxh3 %s",
              wall, cpu, bench::StatusBytes("VmHWM:") / 1e6,
              static_cast<unsigned long long>(report.points), mesh->mesh.face_count(),
              report.mean_abs_distance_before_m, report.mean_abs_distance_after_m,
              HashBytes(std::string_view(reinterpret_cast<const char*>(out.data()),
                                     out.size() * sizeof(float)))
                  .Hex()
                  .c_str());
  if (argc > 4) {
    auto expected = ReadPlyMesh(argv[4]);
    if (!expected.ok()) return Fail(argv[4], expected.status());
    const std::vector<float>& want = expected->mesh.positions;
    size_t differ = want.size() == out.size() ? 0 : out.size();
    if (want.size() == out.size()) {
      for (size_t i = 0; i < out.size(); ++i) {
        if (std::memcmp(&out[i], &want[i], sizeof(float)) != 0) ++differ;
      }
    }
    std::printf("; %s (%zu of %zu coordinates differ from %s)",
                differ == 0 ? "bit-identical" : "DIFFERENT", differ, out.size(), argv[4]);
    if (differ != 0) ok = false;
  }
  std::printf("\n");
  std::fflush(stdout);
  tbb::task_arena arena(threads);
  bool same = true;
  arena.execute([&] { same = CompareEngines(mesh->mesh, *fitted, points->points); });
  return ok && same ? 0 : 1;
}
