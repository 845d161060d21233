// texel_interp_bench: bake.from_points' per-face interpolation
// (FaceInterpolator, stages/geometry/bake/texel_interp.h) in each mode, on
// 2.5·10^4 faces of ~50 texels and 120 points (the averages of the paper-size
// bake: 3·10^7 points onto 2.5·10^5 faces at 4096^2), one thread. Faces are
// 1000 random triangles rasterized by BakeRaster as in a real bake, each used
// 25 times. Prints microseconds per face (thread CPU time, so that other load
// on the machine counts less; wall time beside it) and the time that gives
// for 2.5·10^5 faces (docs/bake-interpolation.md).
//
//   texel_interp_bench [MODES=delaunay,nearest,idw,splat]
#include <time.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "bench/bench_clock.h"
#include "stages/geometry/bake/raster.h"
#include "stages/geometry/bake/texel_interp.h"

namespace {

using pb::BakeTexel;
using pb::TexelSample;

constexpr int kDistinct = 1000, kFaces = 25000, kPointsPerFace = 120;
constexpr int kCell = 16, kCellsPerRow = 32, kAtlas = kCell * kCellsPerRow;

struct Face {
  std::array<TexelSample, 3> corners;
  std::vector<TexelSample> points;
  std::vector<BakeTexel> texels;
};

double ThreadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// kDistinct triangles, one per 16 x 16 cell of a 512^2 atlas, with
// kPointsPerFace random points (color, unit normal) inside each. Alone in
// their cells, the faces own all their edge texels (in a mesh, neighbours
// share them), so areas of 26..44 texels^2 give the ~50 texels a face owns
// in the paper-size bake.
std::vector<Face> MakeFaces() {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 1), signed_unit(-1, 1);
  pb::Mesh mesh;
  std::vector<Face> faces;
  while (faces.size() < kDistinct) {
    const float x0 = float(faces.size() % kCellsPerRow * kCell) + 1;
    const float y0 = float(faces.size() / kCellsPerRow * kCell) + 1;
    Face face;
    for (TexelSample& c : face.corners) {
      c.s = x0 + 13 * u(rng), c.t = y0 + 13 * u(rng);
      c.color = {255 * u(rng), 255 * u(rng), 255 * u(rng)};
      c.normal = {0, 0, 1};
    }
    const auto& c = face.corners;
    const double area = 0.5 * std::abs((c[1].s - c[0].s) * (c[2].t - c[0].t) -
                                       (c[2].s - c[0].s) * (c[1].t - c[0].t));
    if (area < 26 || area > 44) continue;
    const uint32_t first = uint32_t(mesh.vertex_count());
    for (const TexelSample& corner : c) {
      mesh.positions.insert(mesh.positions.end(), {corner.s, corner.t, 0});
      mesh.uvs.insert(mesh.uvs.end(), {corner.s / kAtlas, 1 - corner.t / kAtlas});
    }
    // Counter-clockwise in uv (v up) whichever way the corners came.
    const bool ccw = (c[1].s - c[0].s) * (c[2].t - c[0].t) - (c[2].s - c[0].s) * (c[1].t - c[0].t) < 0;
    mesh.indices.insert(mesh.indices.end(), {first, ccw ? first + 1 : first + 2, ccw ? first + 2 : first + 1});
    while (face.points.size() < kPointsPerFace) {
      const float a = u(rng), b = u(rng);
      if (a + b > 1) continue;
      std::array<float, 3> n = {signed_unit(rng), signed_unit(rng), signed_unit(rng)};
      const float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      if (length < 0.1f) continue;
      TexelSample p;
      p.s = c[0].s + a * (c[1].s - c[0].s) + b * (c[2].s - c[0].s);
      p.t = c[0].t + a * (c[1].t - c[0].t) + b * (c[2].t - c[0].t);
      p.color = {255 * u(rng), 255 * u(rng), 255 * u(rng)};
      p.normal = {n[0] / length, n[1] / length, n[2] / length};
      face.points.push_back(p);
    }
    faces.push_back(std::move(face));
  }
  auto raster = pb::BakeRaster::Build(mesh, kAtlas, 1);
  if (!raster.ok()) {
    std::fprintf(stderr, "%s\n", raster.status().message().c_str());
    std::exit(1);
  }
  for (size_t f = 0; f < faces.size(); ++f) raster->TexelsOf(mesh, uint32_t(f), faces[f].texels);
  return faces;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string only = argc > 1 ? argv[1] : "";
  const std::vector<Face> faces = MakeFaces();
  size_t texels = 0;
  for (const Face& face : faces) texels += face.texels.size();
  std::printf("faces: %d (%d distinct), %.1f texels and %d points per face\n", kFaces, kDistinct,
              double(texels) / kDistinct, kPointsPerFace);
  const std::pair<pb::TexelInterpolation, const char*> modes[] = {
      {pb::TexelInterpolation::kDelaunay, "delaunay"},
      {pb::TexelInterpolation::kNearest, "nearest"},
      {pb::TexelInterpolation::kIdw, "idw"},
      {pb::TexelInterpolation::kSplat, "splat"}};
  for (const auto& [mode, name] : modes) {
    if (!only.empty() && only.find(name) == std::string::npos) continue;
    pb::FaceInterpolator interpolator;
    pb::TexelInterpolationOptions options;
    options.mode = mode;
    std::vector<std::array<float, 3>> colors, normals;
    double checksum = 0;
    const double cpu_start = ThreadCpuSeconds();
    const auto start = pb::bench::Clock::now();
    for (int f = 0; f < kFaces; ++f) {
      const Face& face = faces[f % kDistinct];
      interpolator.Interpolate(face.corners, face.points, face.texels, options, colors, normals);
      if (!colors.empty()) checksum += colors[0][0];
    }
    const double wall = pb::bench::Seconds(start);
    const double us = 1e6 * (ThreadCpuSeconds() - cpu_start) / kFaces;
    std::printf("%-9s %7.2f us/face CPU (%.2f wall) -> %5.2f s for 2.5e5 faces on 1 thread "
                "(checksum %.1f)\n",
                name, us, 1e6 * wall / kFaces, us * 2.5e5 * 1e-6, checksum);
  }
  return 0;
}
