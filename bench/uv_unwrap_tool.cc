// uv_unwrap_tool: uv.unwrap's `charts` (or `per_triangle`) unwrapper on one
// mesh, as bench/uv_unwrap.sh runs it beside Blender: prints the time
// (unwrap + measuring; PLY reading excluded) and the atlas report.
//
//   PB_UV_MESH=path.ply | PB_UV_SYNTH_CELL=0.05 (SynthTruthMesh(room, cell))
//   [PB_UV_SIZE=4096] [PB_UV_METHOD=per_triangle] [PB_UV_THREADS=0]
//   [PB_UV_MAX_STRETCH=1.25] [PB_UV_MEASURE_ONLY=1: measure the file's own
//   uvs (e.g. Blender's)] [PB_UV_CHECK=1: overlaps and gaps]
//   [PB_UV_PNG=atlas.png: the charts, 1024^2] [PB_UV_OUT=unwrapped.ply]
//   uv_unwrap_tool
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "bench/bench_clock.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/synth/scene.h"
#include "stages/geometry/uv/atlas.h"

namespace pb {
namespace {

int Fail(const Status& status) {
  std::fprintf(stderr, "error: %s\n", status.message().c_str());
  return 1;
}

// Each chart a flat color on white, `pixels` square.
Image RenderAtlas(const Mesh& mesh, int pixels) {
  Image image = Image::Make(pixels, pixels, 3, Image::PixelType::kU8);
  std::fill(image.data.begin(), image.data.end(), uint8_t(255));
  uint32_t charts = 0;
  const std::vector<uint32_t> chart = ChartOfFaces(mesh, &charts);
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    uint32_t h = chart[f] * 2654435761u;
    h ^= h >> 15;
    const uint8_t color[3] = {uint8_t(40 + (h & 0x9f)), uint8_t(40 + ((h >> 8) & 0x9f)),
                              uint8_t(40 + ((h >> 16) & 0x9f))};
    double x[3], y[3];
    for (int k = 0; k < 3; ++k) {
      x[k] = mesh.uvs[2 * size_t(mesh.indices[3 * f + k])] * pixels;
      y[k] = (1.0 - mesh.uvs[2 * size_t(mesh.indices[3 * f + k]) + 1]) * pixels;  // v up
    }
    const int x0 = std::max(0, int(std::floor(std::min({x[0], x[1], x[2]}))));
    const int x1 = std::min(pixels - 1, int(std::ceil(std::max({x[0], x[1], x[2]}))));
    const int y0 = std::max(0, int(std::floor(std::min({y[0], y[1], y[2]}))));
    const int y1 = std::min(pixels - 1, int(std::ceil(std::max({y[0], y[1], y[2]}))));
    for (int py = y0; py <= y1; ++py) {
      for (int px = x0; px <= x1; ++px) {
        // Conservative: any pixel the triangle touches (tiny faces stay visible).
        bool inside = false;
        for (double oy : {0.0, 0.5, 1.0}) {
          for (double ox : {0.0, 0.5, 1.0}) {
            const double cx = px + ox, cy = py + oy;
            const double d0 = (x[1] - x[0]) * (cy - y[0]) - (y[1] - y[0]) * (cx - x[0]);
            const double d1 = (x[2] - x[1]) * (cy - y[1]) - (y[2] - y[1]) * (cx - x[1]);
            const double d2 = (x[0] - x[2]) * (cy - y[2]) - (y[0] - y[2]) * (cx - x[2]);
            inside |= (d0 <= 0 && d1 <= 0 && d2 <= 0) || (d0 >= 0 && d1 >= 0 && d2 >= 0);
          }
        }
        if (!inside) continue;
        for (int c = 0; c < 3; ++c) image.at_u8(px, py, c) = color[c];
      }
    }
  }
  return image;
}

}  // namespace
}  // namespace pb

int main() {
  using namespace pb;
  const char* path = std::getenv("PB_UV_MESH");
  const char* cell = std::getenv("PB_UV_SYNTH_CELL");
  if (path == nullptr && cell == nullptr) {
    std::fprintf(stderr, "set PB_UV_MESH or PB_UV_SYNTH_CELL\n");
    return 2;
  }
  Expected<PlyMesh> ply = PlyMesh{};
  if (cell != nullptr) {
    ply->mesh = SynthTruthMesh(*MakeSynthScene("room", 1), std::atof(cell));
  } else {
    ply = ReadPlyMesh(path, {});
  }
  if (!ply.ok()) return Fail(ply.status());
  UnwrapOptions options;
  if (const char* size = std::getenv("PB_UV_SIZE")) options.size_texels = std::atoi(size);
  if (const char* method = std::getenv("PB_UV_METHOD")) {
    if (std::string(method) == "per_triangle") options.method = UnwrapMethod::kPerTriangle;
    if (std::string(method) == "conformal") options.method = UnwrapMethod::kConformal;
    if (std::string(method) == "charts") options.method = UnwrapMethod::kCharts;
  }
  if (const char* threads = std::getenv("PB_UV_THREADS")) options.threads = std::atoi(threads);
  if (const char* cone = std::getenv("PB_UV_CONE")) options.cone_deg = std::atof(cone);
  if (const char* bound = std::getenv("PB_UV_MAX_CHART_STRETCH"))
    options.max_chart_stretch = std::atof(bound);
  if (const char* stretch = std::getenv("PB_UV_MAX_STRETCH"))
    options.max_stretch = std::atof(stretch);
  AtlasReport report;
  const auto start = bench::Clock::now();
  // PB_UV_MEASURE_ONLY=1: measure the file's own UVs (e.g. Blender's).
  auto out = std::getenv("PB_UV_MEASURE_ONLY") != nullptr ? Expected<Mesh>(ply->mesh)
                                                          : UnwrapMesh(ply->mesh, options, &report);
  if (std::getenv("PB_UV_MEASURE_ONLY") != nullptr) {
    report = MeasureAtlas(*out, options.size_texels);
  }
  const double seconds = bench::Seconds(start);
  if (!out.ok()) return Fail(out.status());
  std::printf(
      "faces %zu vertices %zu->%zu: %.3f s (incl. measuring), charts %llu, coverage %.4f, "
      "stretch L2 %.4f Linf %.3f, seams %.1f m, outside %llu, not ccw %llu, isolated %llu, "
      "rounds %d\n",
      ply->mesh.face_count(), ply->mesh.vertex_count(), out->vertex_count(), seconds,
      (unsigned long long)report.charts, report.coverage, report.stretch_l2, report.stretch_linf,
      report.seam_length_m, (unsigned long long)report.faces_outside,
      (unsigned long long)report.faces_not_ccw, (unsigned long long)report.isolated_faces,
      report.rounds);
  if (std::getenv("PB_UV_CHECK") != nullptr) {
    MeasureOptions measure;
    measure.check_overlaps = true;
    const AtlasReport r = MeasureAtlas(*out, options.size_texels, measure);
    std::printf("overlapping faces %llu, chart pairs %llu, min gap %.3f texels, border %.3f\n",
                (unsigned long long)r.overlapping_faces,
                (unsigned long long)r.overlapping_chart_pairs, r.min_chart_gap_texels,
                r.min_border_gap_texels);
  }
  if (const char* png = std::getenv("PB_UV_PNG")) {
    if (Status st = WritePng(png, RenderAtlas(*out, 1024)); !st.ok()) return Fail(st);
  }
  if (const char* ply_out = std::getenv("PB_UV_OUT")) {
    if (Status st = WritePlyMesh(ply_out, *out); !st.ok()) return Fail(st);
  }
  return 0;
}
