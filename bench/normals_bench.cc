// normals_bench: points.normals, points.outliers and points.spacing on ~10^7
// points of a noisy curved surface 2 mm apart, in shuffled order: the k-d
// tree build, normals with no orientation, station orientation and
// propagation, statistical outlier removal (k = 16) and the median spacing;
// the normals also with the k nearest everywhere (widen_dense false), for
// the cost of widening.
// Wall and CPU seconds (all threads): on a shared machine CPU time / cores
// estimates the unloaded wall time. The normals' fingerprint (FNV-1a of the
// float bits) compares builds.
//
//   normals_bench [SIDE=3163]      (SIDE^2 points)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <vector>

#include "bench/bench_clock.h"
#include "stages/geometry/points/knn.h"
#include "stages/geometry/points/normals.h"
#include "stages/geometry/points/outliers.h"
#include "stages/geometry/points/spacing.h"

namespace {

struct Start {
  pb::bench::Clock::time_point wall = pb::bench::Clock::now();
  double cpu = pb::bench::CpuSeconds();
};

void Print(const char* what, const Start& start) {
  std::printf("%s: %.2f s wall, %.2f s CPU\n", what, pb::bench::Seconds(start.wall),
              pb::bench::CpuSeconds() - start.cpu);
  std::fflush(stdout);
}

bool Check(const pb::Status& status) {
  if (!status.ok()) std::fprintf(stderr, "%s\n", status.message().c_str());
  return status.ok();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pb;
  const int side = argc > 1 ? std::atoi(argv[1]) : 3163;
  std::mt19937 rng(1);
  std::normal_distribution<float> noise(0.0f, 0.0003f);
  std::vector<uint32_t> order(static_cast<size_t>(side) * side);
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<uint32_t>(i);
  std::shuffle(order.begin(), order.end(), rng);
  PointCloud cloud;
  cloud.positions.resize(3 * order.size());
  for (size_t i = 0; i < order.size(); ++i) {
    const float x = 0.002f * (order[i] % side), y = 0.002f * (order[i] / side);
    cloud.positions[3 * i] = x + noise(rng);
    cloud.positions[3 * i + 1] = y + noise(rng);
    cloud.positions[3 * i + 2] = 0.2f * std::sin(2 * x) * std::cos(3 * y) + noise(rng);
  }
  std::printf("points %zu\n", cloud.size());
  Start start;
  if (!Check(KnnIndex::Build(cloud.positions).status())) return 1;
  Print("index build", start);
  start = Start();
  if (!Check(EstimateNormals(cloud, {.orientation = NormalOrientation::kNone}))) return 1;
  Print("normals k=16, no orientation (build included)", start);
  uint64_t hash = 1469598103934665603ull;
  for (float f : cloud.normals) {
    uint32_t bits;
    std::memcpy(&bits, &f, sizeof(bits));
    hash = (hash ^ bits) * 1099511628211ull;
  }
  std::printf("normals fingerprint %016llx\n", static_cast<unsigned long long>(hash));
  {
    PointCloud narrow = cloud;
    start = Start();
    if (!Check(EstimateNormals(narrow, {.widen_dense = false, .orientation = NormalOrientation::kNone}))) return 1;
    Print("normals k=16, no orientation, the k nearest everywhere (widen_dense false; build included)", start);
  }
  cloud.station_ids.assign(cloud.size(), 0);
  cloud.stations = {{3.0, 3.0, 2.0}};
  start = Start();
  if (!Check(EstimateNormals(cloud, {.orientation = NormalOrientation::kStations}))) return 1;
  Print("normals k=16, station orientation (build included)", start);
  start = Start();
  if (!Check(EstimateNormals(cloud, {.orientation = NormalOrientation::kPropagate}))) return 1;
  Print("normals k=16, propagation (build included)", start);
  start = Start();
  OutlierReport outliers;
  if (!Check(RemoveStatisticalOutliers(cloud, {}, &outliers).status())) return 1;
  Print("outliers k=16 (build included)", start);
  std::printf("outliers removed %zu\n", outliers.removed);
  start = Start();
  auto spacing = MedianSpacing(cloud, {});
  if (!Check(spacing.status())) return 1;
  Print("spacing (build included)", start);
  std::printf("median spacing %.6f m\n", *spacing);
  return 0;
}
