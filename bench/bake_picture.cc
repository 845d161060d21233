// The same synthetic wall baked five ways, for docs/bake.md: one low mesh
// (Poisson depth 7, decimated, unwrapped) baked from its vertex colors (LPM),
// from a Poisson depth 9 mesh (Remeshing's bake.from_mesh) and from the
// points (bake.from_points: delaunay as the paper, delaunay with the
// neighbours' points, splat), next to the ground truth. Writes a PNG of six
// panels (truth, vertex colors, from mesh, the three from points): an
// orthographic view of a piece of the room's south wall, each panel drawn
// by sampling its color map bilinearly through the low mesh's uvs (the
// truth panel samples the scene's albedo).
// Prints a Markdown table of each bake's mean |baked - true albedo| over all
// texels on the true surface, and its time.
//
// Usage: bake_picture OUT.png [POINTS] [SIZE]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/bench_clock.h"
#include "stages/geometry/bake/bake.h"
#include "stages/geometry/bake/from_mesh.h"
#include "stages/geometry/bake/from_points.h"
#include "stages/geometry/bake/truth.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/mesh/clean.h"
#include "stages/geometry/mesh/decimate.h"
#include "stages/geometry/points/normals.h"
#include "stages/geometry/mesh/poisson.h"
#include "stages/geometry/synth/scanner.h"
#include "stages/geometry/synth/scene.h"
#include "stages/geometry/uv/atlas.h"

namespace pb {
namespace {

void Check(const Status& status, const char* what) {
  if (!status.ok()) {
    std::fprintf(stderr, "bake_picture: %s: %s\n", what, status.message().c_str());
    std::exit(1);
  }
}

template <typename T>
T Take(Expected<T> value, const char* what) {
  Check(value.status(), what);
  return std::move(*value);
}

Mesh PoissonMesh(const PointCloud& cloud, int depth) {
  PoissonOptions options;
  options.depth = depth;
  PoissonOutput out = Take(ReconstructPoisson(cloud, options), "poisson");
  Mesh trimmed = TrimByDensity(std::move(out.mesh), out.densities, 0.01, nullptr);
  CleanReport report;
  return Take(CleanMesh(trimmed, CleanOptions{}, &report), "clean");
}

// The picture window: x in [x0, x0 + width_m], z in [z0, z0 + height_m] on
// the wall whose inner face is near y = wall_y, looked at from +y.
struct Window {
  double x0, z0, width_m, height_m, wall_y;
  int pixels_per_m;
  int width() const { return int(width_m * pixels_per_m); }
  int height() const { return int(height_m * pixels_per_m); }
};

std::array<float, 3> SampleBilinear(const Image& image, float u, float v) {
  const float x = u * image.width - 0.5f, y = (1 - v) * image.height - 0.5f;
  const int x0 = std::clamp(int(std::floor(x)), 0, image.width - 1);
  const int y0 = std::clamp(int(std::floor(y)), 0, image.height - 1);
  const int x1 = std::min(x0 + 1, image.width - 1), y1 = std::min(y0 + 1, image.height - 1);
  const float fx = std::clamp(x - x0, 0.0f, 1.0f), fy = std::clamp(y - y0, 0.0f, 1.0f);
  std::array<float, 3> out{};
  for (int c = 0; c < 3; ++c) {
    out[c] = (1 - fy) * ((1 - fx) * image.at_u8(x0, y0, c) + fx * image.at_u8(x1, y0, c)) +
             fy * ((1 - fx) * image.at_u8(x0, y1, c) + fx * image.at_u8(x1, y1, c));
  }
  return out;
}

// Orthographic view of the wall faces of `mesh` (normal towards +y, near
// wall_y), textured with `color` through the mesh's uvs.
void DrawPanel(const Mesh& mesh, const Image& color, const Window& w, Image& out, int x_offset) {
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    double p[3][3];
    for (int k = 0; k < 3; ++k) {
      for (int c = 0; c < 3; ++c) p[k][c] = mesh.origin[c] + mesh.positions[3 * size_t(mesh.indices[3 * f + k]) + c];
    }
    const double centroid_y = (p[0][1] + p[1][1] + p[2][1]) / 3;
    const double ny = (p[1][2] - p[0][2]) * (p[2][0] - p[0][0]) - (p[1][0] - p[0][0]) * (p[2][2] - p[0][2]);
    if (std::abs(centroid_y - w.wall_y) > 0.05 || !(ny > 0)) continue;
    // Pixel coordinates: px right along x, py down along -z.
    double q[3][2];
    for (int k = 0; k < 3; ++k) {
      q[k][0] = (p[k][0] - w.x0) * w.pixels_per_m;
      q[k][1] = (w.z0 + w.height_m - p[k][2]) * w.pixels_per_m;
    }
    const double area = (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[1][1] - q[0][1]) * (q[2][0] - q[0][0]);
    if (std::abs(area) < 1e-12) continue;
    const int xmin = std::max(0, int(std::floor(std::min({q[0][0], q[1][0], q[2][0]}))));
    const int xmax = std::min(w.width() - 1, int(std::ceil(std::max({q[0][0], q[1][0], q[2][0]}))));
    const int ymin = std::max(0, int(std::floor(std::min({q[0][1], q[1][1], q[2][1]}))));
    const int ymax = std::min(w.height() - 1, int(std::ceil(std::max({q[0][1], q[1][1], q[2][1]}))));
    for (int y = ymin; y <= ymax; ++y) {
      for (int x = xmin; x <= xmax; ++x) {
        const double sx = x + 0.5, sy = y + 0.5;
        double b[3];
        for (int k = 0; k < 3; ++k) {
          const double* a = q[(k + 1) % 3];
          const double* c = q[(k + 2) % 3];
          b[k] = ((c[0] - a[0]) * (sy - a[1]) - (c[1] - a[1]) * (sx - a[0])) / area;
        }
        if (b[0] < 0 || b[1] < 0 || b[2] < 0) continue;
        float u = 0, v = 0;
        for (int k = 0; k < 3; ++k) {
          const uint32_t vertex = mesh.indices[3 * f + k];
          u += float(b[k]) * mesh.uvs[2 * vertex];
          v += float(b[k]) * mesh.uvs[2 * vertex + 1];
        }
        const auto rgb = SampleBilinear(color, u, v);
        for (int c = 0; c < 3; ++c) out.at_u8(x_offset + x, y, c) = uint8_t(std::lround(rgb[c]));
      }
    }
  }
}

using pb::bench::Seconds;

int Main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bake_picture OUT.png [POINTS] [SIZE]\n");
    return 2;
  }
  const std::string out_path = argv[1];
  const uint64_t points = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 3000000;
  const int size = argc > 3 ? std::atoi(argv[3]) : 2048;
  const SynthScene scene = Take(MakeSynthScene("room", 3, Vec3{3.0, 2.4, 2.4}), "scene");
  SynthScanOptions scan_options;
  scan_options.target_points = points;
  scan_options.stations = 2;
  SynthScanResult scan = Take(SimulateScan(scene, scan_options), "scan");
  Check(EstimateNormals(scan.cloud, NormalOptions{}), "normals");
  const double spacing_m = scan.median_spacing_m;

  const Mesh high = PoissonMesh(scan.cloud, 9);
  DecimateOptions decimate;
  decimate.target_faces = 20000;
  const Mesh decimated = Take(DecimateMesh(PoissonMesh(scan.cloud, 7), decimate, nullptr), "decimate");
  UnwrapOptions unwrap;
  unwrap.size_texels = size;
  const Mesh low = Take(UnwrapMesh(decimated, unwrap, nullptr), "unwrap");
  std::fprintf(stderr, "%zu points, spacing %.2f mm; high %zu faces, low %zu faces, %d² maps\n",
               scan.cloud.size(), spacing_m * 1e3, high.face_count(), low.face_count(), size);

  BakeOptions options;
  options.size = size;
  struct Baked {
    const char* name;
    BakeResult result;
    double seconds;
  };
  std::vector<Baked> baked;
  auto start = std::chrono::steady_clock::now();
  baked.push_back({"bake.vertex_colors (LPM)", Take(BakeVertexColors(low, options), "vertex colors"), Seconds(start)});
  start = std::chrono::steady_clock::now();
  FromMeshOptions cage;
  cage.cage_m = 0.03;
  baked.push_back({"bake.from_mesh (Remeshing's bake, from the depth-9 mesh)",
                   Take(BakeFromMesh(low, high, options, cage), "from mesh"), Seconds(start)});
  struct Variant {
    const char* name;
    TexelInterpolation mode;
    bool neighbors;
  };
  for (const Variant& variant :
       {Variant{"bake.from_points, delaunay (the paper)", TexelInterpolation::kDelaunay, false},
        Variant{"bake.from_points, delaunay with the neighbours' points (default)",
                TexelInterpolation::kDelaunay, true},
        Variant{"bake.from_points, splat", TexelInterpolation::kSplat, false}}) {
    FromPointsOptions transfer;
    transfer.max_distance_m = 4 * spacing_m;
    transfer.max_angle_deg = 90;
    transfer.splat_sigma_m = spacing_m;
    transfer.interpolation.mode = variant.mode;
    transfer.neighbors = variant.neighbors;
    PointCloud copy = scan.cloud;
    start = std::chrono::steady_clock::now();
    BakeResult result = Take(BakeFromPoints(low, std::move(copy), options, transfer), "from points");
    baked.push_back({variant.name, std::move(result), Seconds(start)});
  }

  std::printf("| bake | mean abs. color error vs truth (0-255) | time |\n|---|---:|---:|\n");
  for (const Baked& b : baked) {
    std::printf("| %s | %.2f | %.1f s |\n", b.name,
                Take(ColorErrorAgainstTruth(scene, b.result), "error").mean_abs, b.seconds);
  }

  Vec3 min_m, max_m;
  SceneBounds(scene, &min_m, &max_m);
  // The inner face of the wall at the smallest y: the nearest true surface
  // sample from just inside.
  const double x_mid = 0.5 * (min_m[0] + max_m[0]);
  const SurfaceSample inner = SampleSurface(scene, {x_mid, min_m[1] + 0.3, 1.0});
  const double wall_y = min_m[1] + 0.3 - inner.distance_m;
  const Window window{x_mid - 0.45, 0.75, 0.6, 0.45, wall_y, 1000};
  const int panels = 6, gap = 6;
  Image picture = Image::Make(panels * window.width() + (panels - 1) * gap, window.height(), 3,
                              Image::PixelType::kU8);
  std::fill(picture.data.begin(), picture.data.end(), uint8_t(255));
  for (int y = 0; y < window.height(); ++y) {
    for (int x = 0; x < window.width(); ++x) {
      const double px = window.x0 + (x + 0.5) / window.pixels_per_m;
      const double pz = window.z0 + window.height_m - (y + 0.5) / window.pixels_per_m;
      const SurfaceSample truth = SampleSurface(scene, {px, wall_y + 0.01, pz});
      for (int c = 0; c < 3; ++c) picture.at_u8(x, y, c) = uint8_t(std::lround(255 * truth.albedo[c]));
    }
  }
  for (int i = 0; i < 5; ++i) {
    DrawPanel(baked[i].result.mesh, baked[i].result.maps.color, window, picture,
              (i + 1) * (window.width() + gap));
  }
  Check(WritePng(out_path, picture), "write");
  std::fprintf(stderr, "wrote %s: truth | vertex colors | from mesh | from points delaunay | with neighbours | splat\n",
               out_path.c_str());
  return 0;
}

}  // namespace
}  // namespace pb

int main(int argc, char** argv) { return pb::Main(argc, argv); }
