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
    if (Status st = WritePng(png, DrawAtlas(*out, 1024)); !st.ok()) return Fail(st);
  }
  if (const char* ply_out = std::getenv("PB_UV_OUT")) {
    if (Status st = WritePlyMesh(ply_out, *out); !st.ok()) return Fail(st);
  }
  return 0;
}
