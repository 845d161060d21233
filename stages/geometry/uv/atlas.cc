// UV atlas construction and measurement; see uv_atlas.h for the algorithm
// and its sources (Blender Smart UV Project for the chart criterion, Sander
// et al. 2001 for stretch, Jylänki 2010 for the skyline packer, MeshLab's
// trivial per-triangle parametrization for the baseline).
#include "stages/geometry/uv/atlas.h"

#include "stages/geometry/core/image.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iterator>
#include <limits>
#include <numeric>
#include <set>
#include <string>
#include <utility>

#include "stages/geometry/uv/charts.h"
#include "stages/geometry/uv/pack.h"
#include "stages/geometry/uv/raster_pack.h"
#include "stages/geometry/uv/surface_charts.h"

namespace pb {
namespace {

Status CheckOptions(const Mesh& mesh, const UnwrapOptions& options) {
  PB_RETURN_IF_ERROR(Validate(mesh));
  if (options.size_texels < 8 || options.size_texels > 65536) {
    return Status::Invalid("uv unwrap: size must be in [8, 65536] texels, got " +
                           std::to_string(options.size_texels));
  }
  if (options.gutter_texels < 0 || 4 * options.gutter_texels >= options.size_texels) {
    return Status::Invalid("uv unwrap: gutter must be in [0, size/4) texels, got " +
                           std::to_string(options.gutter_texels));
  }
  if (!(options.max_angle_deg > 0 && options.max_angle_deg < 90)) {
    return Status::Invalid("uv unwrap: max_angle_deg must be in (0, 90), got " +
                           std::to_string(options.max_angle_deg));
  }
  if (!(options.cone_deg > 0 && options.cone_deg < 90)) {
    return Status::Invalid("uv unwrap: cone_deg must be in (0, 90), got " +
                           std::to_string(options.cone_deg));
  }
  if (!(options.max_chart_stretch > 1)) {
    return Status::Invalid("uv unwrap: max_chart_stretch must be > 1, got " +
                           std::to_string(options.max_chart_stretch));
  }
  if (!(options.max_stretch >= 1)) {
    return Status::Invalid("uv unwrap: max_stretch must be >= 1, got " +
                           std::to_string(options.max_stretch));
  }
  if (mesh.face_count() >= std::numeric_limits<uint32_t>::max() / 3) {
    return Status::Invalid("uv unwrap: too many faces");
  }
  return Status::Ok();
}

// Copies every attribute of vertex `from` of `in` to the end of `out`.
void AppendVertex(const Mesh& in, uint32_t from, Mesh* out) {
  const size_t v = from;
  out->positions.insert(out->positions.end(), in.positions.begin() + 3 * v,
                        in.positions.begin() + 3 * v + 3);
  if (in.has_normals()) {
    out->normals.insert(out->normals.end(), in.normals.begin() + 3 * v,
                        in.normals.begin() + 3 * v + 3);
  }
  if (in.has_colors()) {
    out->colors.insert(out->colors.end(), in.colors.begin() + 3 * v, in.colors.begin() + 3 * v + 3);
  }
  if (in.has_tangents()) {
    out->tangents.insert(out->tangents.end(), in.tangents.begin() + 4 * v,
                         in.tangents.begin() + 4 * v + 4);
  }
}

Mesh EmptyLike(const Mesh& mesh) {
  Mesh out;
  out.origin = mesh.origin;
  out.indices.resize(mesh.indices.size());
  return out;
}

// Slivers that float UVs cannot hold: faces whose smallest altitude would
// be under 0.02 texel at the density of an atlas half covered (the packed
// density is usually higher, which only makes them thicker).
std::vector<uint32_t> TinyFaces(const Mesh& mesh, int size_texels) {
  const size_t faces = mesh.face_count();
  std::vector<double> area(faces), longest(faces);
  double total = 0;
  for (size_t f = 0; f < faces; ++f) {
    double q[3][3];
    for (int k = 0; k < 3; ++k) {
      for (int d = 0; d < 3; ++d) q[k][d] = mesh.positions[3 * size_t(mesh.indices[3 * f + k]) + d];
    }
    const double e1[3] = {q[1][0] - q[0][0], q[1][1] - q[0][1], q[1][2] - q[0][2]};
    const double e2[3] = {q[2][0] - q[0][0], q[2][1] - q[0][1], q[2][2] - q[0][2]};
    const double e3[3] = {q[2][0] - q[1][0], q[2][1] - q[1][1], q[2][2] - q[1][2]};
    const double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2],
                 cz = e1[0] * e2[1] - e1[1] * e2[0];
    area[f] = 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
    longest[f] = std::sqrt(std::max({e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2],
                                     e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2],
                                     e3[0] * e3[0] + e3[1] * e3[1] + e3[2] * e3[2]}));
    total += area[f];
  }
  std::vector<uint32_t> tiny;
  if (!(total > 0)) return tiny;
  const double texels_per_m = double(size_texels) * std::sqrt(0.5 / total);
  for (size_t f = 0; f < faces; ++f) {
    const double altitude_m = longest[f] > 0 ? 2 * area[f] / longest[f] : 0;
    if (altitude_m * texels_per_m < 0.02) tiny.push_back(uint32_t(f));
  }
  return tiny;
}

// The unwrapped mesh: chart by chart, vertices copied, UVs placed.
Mesh Layout(const Mesh& mesh, const std::vector<FlatChart>& charts, const PackResult& packed,
            int size_texels) {
  Mesh out = EmptyLike(mesh);
  size_t total_vertices = 0;
  for (const FlatChart& c : charts) total_vertices += c.vertices.size();
  out.positions.reserve(3 * total_vertices);
  out.uvs.reserve(2 * total_vertices);
  const double s = packed.texels_per_meter, inv_size = 1.0 / size_texels;
  for (size_t c = 0; c < charts.size(); ++c) {
    const FlatChart& chart = charts[c];
    const uint32_t base = uint32_t(out.vertex_count());
    const double x = double(packed.x_texels[c]), y = double(packed.y_texels[c]);
    const bool turned = packed.turned[c] != 0;
    for (size_t i = 0; i < chart.vertices.size(); ++i) {
      AppendVertex(mesh, chart.vertices[i], &out);
      // A quarter turn (u, v) -> (height - v, u) is a rotation: no mirroring.
      const double u = turned ? chart.height_m - chart.uv_m[2 * i + 1] : chart.uv_m[2 * i];
      const double v = turned ? chart.uv_m[2 * i] : chart.uv_m[2 * i + 1];
      out.uvs.push_back(float((x + u * s) * inv_size));
      out.uvs.push_back(float((y + v * s) * inv_size));
    }
    for (size_t i = 0; i < chart.faces.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        out.indices[3 * size_t(chart.faces[i]) + k] = base + chart.corners[3 * i + k];
      }
    }
    if (chart.isolated) {  // the fixed right triangle, one texel on a side
      constexpr double kCorner[3][2] = {{0, 0}, {1, 0}, {0, 1}};
      for (int k = 0; k < 3; ++k) {
        const size_t v = base + chart.corners[k];
        out.uvs[2 * v] = float((x + kCorner[k][0]) * inv_size);
        out.uvs[2 * v + 1] = float((y + kCorner[k][1]) * inv_size);
      }
    }
  }
  return out;
}

// The unwrapped mesh from raster placements (raster_pack.h).
Mesh RasterLayout(const Mesh& mesh, const std::vector<FlatChart>& charts,
                  const RasterPackResult& packed, int size_texels) {
  Mesh out = EmptyLike(mesh);
  size_t total_vertices = 0;
  for (const FlatChart& c : charts) total_vertices += c.vertices.size();
  out.positions.reserve(3 * total_vertices);
  out.uvs.reserve(2 * total_vertices);
  const double s = packed.texels_per_meter, inv_size = 1.0 / size_texels;
  for (size_t c = 0; c < charts.size(); ++c) {
    const FlatChart& chart = charts[c];
    const RasterPlacement& p = packed.placements[c];
    const uint32_t base = uint32_t(out.vertex_count());
    for (size_t i = 0; i < chart.vertices.size(); ++i) {
      AppendVertex(mesh, chart.vertices[i], &out);
      const auto t = PlacedTexel(p, s, chart.uv_m[2 * i], chart.uv_m[2 * i + 1]);
      out.uvs.push_back(float(t[0] * inv_size));
      out.uvs.push_back(float(t[1] * inv_size));
    }
    for (size_t i = 0; i < chart.faces.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        out.indices[3 * size_t(chart.faces[i]) + k] = base + chart.corners[3 * i + k];
      }
    }
    if (chart.isolated) {  // the fixed right triangle, one texel on a side
      constexpr double kCorner[3][2] = {{0, 0}, {1, 0}, {0, 1}};
      for (int k = 0; k < 3; ++k) {
        const size_t v = base + chart.corners[k];
        out.uvs[2 * v] = float((double(p.x) + kCorner[k][0]) * inv_size);
        out.uvs[2 * v + 1] = float((double(p.y) + kCorner[k][1]) * inv_size);
      }
    }
  }
  return out;
}

// Faces whose UV triangle (as stored, float) has under 10^-6 texel^2 of
// signed area, increasing.
std::vector<uint32_t> FacesWithoutUvArea(const Mesh& out, int size_texels) {
  std::vector<uint32_t> faces;
  const double min_area = 1e-6 / (double(size_texels) * size_texels);
  for (size_t f = 0; f < out.face_count(); ++f) {
    const float* a = &out.uvs[2 * size_t(out.indices[3 * f])];
    const float* b = &out.uvs[2 * size_t(out.indices[3 * f + 1])];
    const float* c = &out.uvs[2 * size_t(out.indices[3 * f + 2])];
    const double area = 0.5 * ((double(b[0]) - a[0]) * (double(c[1]) - a[1]) -
                               (double(c[0]) - a[0]) * (double(b[1]) - a[1]));
    if (area < min_area) faces.push_back(uint32_t(f));
  }
  return faces;
}

template <typename F>
auto InArena(int threads, F&& body) {
  if (threads > 0) {
    tbb::task_arena arena(threads);
    return arena.execute(std::forward<F>(body));
  }
  return body();
}

}  // namespace

namespace {

// One atlas built with the given isolated faces (see TinyFaces): the
// unwrapped mesh and its packing scale. `first_round` reports progress.
using AtlasAttempt = std::function<Expected<Mesh>(const std::vector<uint32_t>& isolated_faces,
                                                  bool first_round, double* texels_per_meter)>;

// Builds atlases until every face has float UV area: faces whose float UVs
// come out with none at the packed scale are isolated and everything is
// redone; each round isolates more faces, so this ends (in practice after
// one or two rounds). Shared by the `charts` and `conformal` methods.
Expected<Mesh> UnwrapInRounds(const Mesh& mesh, const UnwrapOptions& options,
                              const AtlasAttempt& attempt, AtlasReport* report) {
  std::vector<uint32_t> isolated = TinyFaces(mesh, options.size_texels);
  for (int round = 0;; ++round) {
    double texels_per_meter = 0;
    // Progress is reported by the first round only (it must not go back).
    auto out = attempt(isolated, round == 0, &texels_per_meter);
    if (!out.ok()) return out.status();
    std::vector<uint32_t> flat_faces = FacesWithoutUvArea(*out, options.size_texels);
    std::vector<uint32_t> merged;
    std::set_union(isolated.begin(), isolated.end(), flat_faces.begin(), flat_faces.end(),
                   std::back_inserter(merged));
    if (merged.size() > isolated.size()) {
      isolated = std::move(merged);
      continue;
    }
    if (report != nullptr) {
      *report = MeasureAtlas(*out, options.size_texels);
      report->texels_per_meter = texels_per_meter;
      report->isolated_faces = isolated.size();
      report->rounds = round + 1;
    }
    if (options.progress) options.progress(1.0);
    return out;
  }
}

}  // namespace

Expected<Mesh> UnwrapCharts(const Mesh& mesh, const UnwrapOptions& options, AtlasReport* report) {
  PB_RETURN_IF_ERROR(CheckOptions(mesh, options));
  return InArena(options.threads, [&]() -> Expected<Mesh> {
    auto progress = [&](double f) {
      if (options.progress) options.progress(0.8 * f);
    };
    auto attempt = [&](const std::vector<uint32_t>& isolated, bool first_round,
                       double* texels_per_meter) -> Expected<Mesh> {
      ChartOptions chart_options;
      chart_options.max_angle_deg = options.max_angle_deg;
      chart_options.max_stretch = options.max_stretch;
      chart_options.isolated_faces = isolated;
      std::vector<FlatChart> charts = MakeFlatCharts(
          mesh, chart_options, nullptr,
          first_round ? std::function<void(double)>(progress) : std::function<void(double)>());
      std::vector<ChartExtent> extents(charts.size());
      for (size_t c = 0; c < charts.size(); ++c) {
        extents[c] = {charts[c].width_m, charts[c].height_m};
      }
      auto packed = PackCharts(extents, options.size_texels, options.gutter_texels);
      if (!packed.ok()) return packed.status();
      if (options.progress && first_round) options.progress(0.85);
      *texels_per_meter = packed->texels_per_meter;
      return Layout(mesh, charts, *packed, options.size_texels);
    };
    return UnwrapInRounds(mesh, options, attempt, report);
  });
}

Expected<Mesh> UnwrapConformal(const Mesh& mesh, const UnwrapOptions& options,
                               AtlasReport* report) {
  PB_RETURN_IF_ERROR(CheckOptions(mesh, options));
  return InArena(options.threads, [&]() -> Expected<Mesh> {
    auto progress = [&](double f) {
      if (options.progress) options.progress(0.7 * f);
    };
    auto attempt = [&](const std::vector<uint32_t>& isolated, bool first_round,
                       double* texels_per_meter) -> Expected<Mesh> {
      SurfaceChartOptions chart_options;
      chart_options.cone_deg = options.cone_deg;
      chart_options.max_chart_stretch = options.max_chart_stretch;
      chart_options.isolated_faces = isolated;
      std::vector<FlatChart> charts = MakeSurfaceCharts(
          mesh, chart_options,
          first_round ? std::function<void(double)>(progress) : std::function<void(double)>());
      auto packed = RasterPackCharts(charts, options.size_texels, options.gutter_texels);
      if (!packed.ok()) return packed.status();
      if (options.progress && first_round) options.progress(0.9);
      *texels_per_meter = packed->texels_per_meter;
      return RasterLayout(mesh, charts, *packed, options.size_texels);
    };
    return UnwrapInRounds(mesh, options, attempt, report);
  });
}

Expected<Mesh> UnwrapPerTriangle(const Mesh& mesh, const UnwrapOptions& options,
                                 AtlasReport* report) {
  PB_RETURN_IF_ERROR(CheckOptions(mesh, options));
  const size_t faces = mesh.face_count();
  const int64_t per_row = std::max<int64_t>(1, int64_t(std::ceil(std::sqrt(double(faces)))));
  const int64_t cell = (options.size_texels - options.gutter_texels) / per_row;
  const int64_t leg = cell - options.gutter_texels;
  if (leg < 2) {
    return Status::Invalid("uv unwrap per_triangle: " + std::to_string(faces) +
                           " faces need a grid of " + std::to_string(per_row) + "^2 cells of " +
                           std::to_string(options.gutter_texels + 2) +
                           "+ texels; raise `size` or lower `gutter`, or use method charts");
  }
  Mesh out = EmptyLike(mesh);
  out.positions.reserve(9 * faces);
  out.uvs.reserve(6 * faces);
  const double inv_size = 1.0 / options.size_texels;
  for (size_t f = 0; f < faces; ++f) {
    const double x0 = double(options.gutter_texels + int64_t(f) % per_row * cell);
    const double y0 = double(options.gutter_texels + int64_t(f) / per_row * cell);
    const double corner[3][2] = {{x0, y0}, {x0 + leg, y0}, {x0, y0 + leg}};
    for (int k = 0; k < 3; ++k) {
      out.indices[3 * f + k] = uint32_t(out.vertex_count());
      AppendVertex(mesh, mesh.indices[3 * f + k], &out);
      out.uvs.push_back(float(corner[k][0] * inv_size));
      out.uvs.push_back(float(corner[k][1] * inv_size));
    }
    if (options.progress && f % 65536 == 0) options.progress(0.8 * double(f) / double(faces));
  }
  if (report != nullptr) *report = MeasureAtlas(out, options.size_texels);
  if (options.progress) options.progress(1.0);
  return out;
}

Expected<Mesh> UnwrapMesh(const Mesh& mesh, const UnwrapOptions& options, AtlasReport* report) {
  switch (options.method) {
    case UnwrapMethod::kCharts: return UnwrapCharts(mesh, options, report);
    case UnwrapMethod::kConformal: return UnwrapConformal(mesh, options, report);
    case UnwrapMethod::kPerTriangle: break;
  }
  return UnwrapPerTriangle(mesh, options, report);
}

std::vector<uint32_t> ChartOfFaces(const Mesh& mesh, uint32_t* chart_count) {
  std::vector<uint32_t> parent(mesh.vertex_count());
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  const size_t faces = mesh.face_count();
  for (size_t f = 0; f < faces; ++f) {
    const uint32_t a = find(mesh.indices[3 * f]);
    for (int k = 1; k < 3; ++k) {
      const uint32_t b = find(mesh.indices[3 * f + k]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  constexpr uint32_t kUnset = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> number(mesh.vertex_count(), kUnset);
  std::vector<uint32_t> chart(faces);
  uint32_t count = 0;
  for (size_t f = 0; f < faces; ++f) {
    const uint32_t root = find(mesh.indices[3 * f]);
    if (number[root] == kUnset) number[root] = count++;
    chart[f] = number[root];
  }
  if (chart_count != nullptr) *chart_count = count;
  return chart;
}

namespace {

using Tri2 = std::array<double, 6>;

Tri2 UvTriangle(const Mesh& mesh, size_t f) {
  Tri2 t;
  for (int k = 0; k < 3; ++k) {
    const size_t v = mesh.indices[3 * f + k];
    t[2 * k] = mesh.uvs[2 * v];
    t[2 * k + 1] = mesh.uvs[2 * v + 1];
  }
  return t;
}

// Per-face sums over a fixed chunk of faces, added in chunk order so that
// the totals do not depend on the thread count.
struct FaceSums {
  double area3 = 0, area_uv = 0, l2_weighted = 0, linf = 0;
  uint64_t outside = 0, not_ccw = 0;
};

// Faces with an altitude under `min_altitude_m` are left out of linf
// (slivers the texture cannot show; the unwrapper isolates them).
FaceSums MeasureFaces(const Mesh& mesh, size_t begin, size_t end, double min_altitude_m) {
  FaceSums sums;
  for (size_t f = begin; f < end; ++f) {
    const Tri2 t = UvTriangle(mesh, f);
    double q[3][3];
    for (int k = 0; k < 3; ++k) {
      const size_t v = mesh.indices[3 * f + k];
      for (int d = 0; d < 3; ++d) q[k][d] = mesh.positions[3 * v + d];
      if (!(t[2 * k] >= 0 && t[2 * k] <= 1 && t[2 * k + 1] >= 0 && t[2 * k + 1] <= 1)) {
        ++sums.outside;
        break;
      }
    }
    for (int k = 0; k < 3; ++k) {
      const size_t v = mesh.indices[3 * f + k];
      for (int d = 0; d < 3; ++d) q[k][d] = mesh.positions[3 * v + d];
    }
    const double e1[3] = {q[1][0] - q[0][0], q[1][1] - q[0][1], q[1][2] - q[0][2]};
    const double e2[3] = {q[2][0] - q[0][0], q[2][1] - q[0][1], q[2][2] - q[0][2]};
    const double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2],
                 cz = e1[0] * e2[1] - e1[1] * e2[0];
    const double area3 = 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
    const double s1 = t[0], t1 = t[1], s2 = t[2], t2 = t[3], s3 = t[4], t3 = t[5];
    const double area_uv = 0.5 * ((s2 - s1) * (t3 - t1) - (s3 - s1) * (t2 - t1));
    if (!(area_uv > 0)) {
      ++sums.not_ccw;
      continue;
    }
    sums.area3 += area3;
    sums.area_uv += area_uv;
    double ss[3], st[3];
    for (int d = 0; d < 3; ++d) {
      ss[d] = (q[0][d] * (t2 - t3) + q[1][d] * (t3 - t1) + q[2][d] * (t1 - t2)) / (2 * area_uv);
      st[d] = (q[0][d] * (s3 - s2) + q[1][d] * (s1 - s3) + q[2][d] * (s2 - s1)) / (2 * area_uv);
    }
    const double a = ss[0] * ss[0] + ss[1] * ss[1] + ss[2] * ss[2];
    const double b = ss[0] * st[0] + ss[1] * st[1] + ss[2] * st[2];
    const double c = st[0] * st[0] + st[1] * st[1] + st[2] * st[2];
    sums.l2_weighted += area3 * 0.5 * (a + c);
    double longest2 = 0;
    for (int k = 0; k < 3; ++k) {
      const int m = (k + 1) % 3;
      longest2 = std::max(longest2, (q[m][0] - q[k][0]) * (q[m][0] - q[k][0]) +
                                        (q[m][1] - q[k][1]) * (q[m][1] - q[k][1]) +
                                        (q[m][2] - q[k][2]) * (q[m][2] - q[k][2]));
    }
    if (area3 > 0 && 2 * area3 >= min_altitude_m * std::sqrt(longest2)) {
      sums.linf =
          std::max(sums.linf, std::sqrt(0.5 * (a + c + std::sqrt((a - c) * (a - c) + 4 * b * b))));
    }
  }
  return sums;
}

// 3-D length of seams: edges that are open in the unwrapped mesh but whose
// two end positions are shared by another open edge (the other side of the
// cut). Vertices are welded by exact position, only on open edges.
double SeamLength(const Mesh& mesh) {
  const size_t faces = mesh.face_count();
  std::vector<uint32_t> offsets(mesh.vertex_count() + 1, 0);
  for (uint32_t v : mesh.indices) ++offsets[v + 1];
  for (size_t v = 0; v + 1 < offsets.size(); ++v) offsets[v + 1] += offsets[v];
  std::vector<uint32_t> incident(mesh.indices.size());
  {
    std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (size_t i = 0; i < mesh.indices.size(); ++i)
      incident[fill[mesh.indices[i]]++] = uint32_t(i / 3);
  }
  struct Open {
    std::array<float, 6> key;  // end positions, lower one first
    uint32_t a, b;             // output vertices, lower one first
  };
  std::vector<Open> open;
  auto pos = [&](uint32_t v) {
    return std::array<float, 3>{mesh.positions[3 * size_t(v)], mesh.positions[3 * size_t(v) + 1],
                                mesh.positions[3 * size_t(v) + 2]};
  };
  for (size_t f = 0; f < faces; ++f) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = mesh.indices[3 * f + k], b = mesh.indices[3 * f + (k + 1) % 3];
      bool twin = false;
      for (uint32_t i = offsets[b]; i < offsets[b + 1] && !twin; ++i) {
        const size_t g = incident[i];
        for (int m = 0; m < 3; ++m) {
          if (mesh.indices[3 * g + m] == b && mesh.indices[3 * g + (m + 1) % 3] == a) twin = true;
        }
      }
      if (twin) continue;
      auto pa = pos(a), pb = pos(b);
      if (pb < pa) std::swap(pa, pb);
      open.push_back({{pa[0], pa[1], pa[2], pb[0], pb[1], pb[2]}, std::min(a, b), std::max(a, b)});
    }
  }
  std::sort(open.begin(), open.end(), [](const Open& x, const Open& y) {
    return std::tie(x.key, x.a, x.b) < std::tie(y.key, y.a, y.b);
  });
  double seam = 0;
  for (size_t i = 0; i < open.size();) {
    size_t j = i + 1;
    bool differ = false;
    while (j < open.size() && open[j].key == open[i].key) {
      differ |= open[j].a != open[i].a || open[j].b != open[i].b;
      ++j;
    }
    if (differ) {
      const auto& k = open[i].key;
      seam += std::sqrt(double(k[3] - k[0]) * (k[3] - k[0]) + double(k[4] - k[1]) * (k[4] - k[1]) +
                        double(k[5] - k[2]) * (k[5] - k[2]));
    }
    i = j;
  }
  return seam;
}

}  // namespace

AtlasReport MeasureAtlas(const Mesh& mesh, int size_texels, const MeasureOptions& options) {
  AtlasReport report;
  const size_t faces = mesh.face_count();
  report.faces = faces;
  report.vertices = mesh.vertex_count();
  if (!mesh.has_uvs() || mesh.uvs.size() != 2 * mesh.vertex_count()) {
    report.faces_outside = faces;
    return report;
  }
  uint32_t chart_count = 0;
  const std::vector<uint32_t> chart = ChartOfFaces(mesh, &chart_count);
  report.charts = chart_count;

  constexpr size_t kChunk = 65536;
  const size_t chunks = (faces + kChunk - 1) / kChunk;
  std::vector<FaceSums> partial(chunks);
  // Pass 1 finds the scale (texels per meter), pass 2 the stretch without
  // sub-texel slivers.
  double min_altitude_m = std::numeric_limits<double>::infinity();
  FaceSums total;
  for (int pass = 0; pass < 2; ++pass) {
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
      partial[c] =
          MeasureFaces(mesh, c * kChunk, std::min(faces, (c + 1) * kChunk), min_altitude_m);
    });
    if (pass == 1) break;
    double area3 = 0, area_uv = 0;
    for (const FaceSums& p : partial) {
      area3 += p.area3;
      area_uv += p.area_uv;
    }
    if (!(area3 > 0 && area_uv > 0)) break;
    min_altitude_m = 0.05 / (std::sqrt(area_uv / area3) * size_texels);
  }
  for (const FaceSums& p : partial) {
    total.area3 += p.area3;
    total.area_uv += p.area_uv;
    total.l2_weighted += p.l2_weighted;
    total.linf = std::max(total.linf, p.linf);
    total.outside += p.outside;
    total.not_ccw += p.not_ccw;
  }
  report.faces_outside = total.outside;
  report.faces_not_ccw = total.not_ccw;
  report.coverage = total.area_uv;
  if (total.area3 > 0 && total.area_uv > 0) {
    const double normalize = std::sqrt(total.area_uv / total.area3);
    report.stretch_l2 = std::sqrt(total.l2_weighted / total.area3) * normalize;
    report.stretch_linf = total.linf * normalize;
  }
  report.seam_length_m = SeamLength(mesh);

  double border = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < mesh.uvs.size(); ++i) {
    border = std::min({border, double(mesh.uvs[i]), 1.0 - double(mesh.uvs[i])});
  }
  report.min_border_gap_texels = faces > 0 ? border * size_texels : 0;
  if (!options.check_overlaps) return report;

  // Face pairs whose UV boxes come within the probe distance.
  const double probe = options.gap_probe_texels / size_texels;
  std::vector<Box2> boxes(faces);
  for (size_t f = 0; f < faces; ++f) {
    const Tri2 t = UvTriangle(mesh, f);
    boxes[f] = {
        std::min({t[0], t[2], t[4]}) - 0.5 * probe, std::min({t[1], t[3], t[5]}) - 0.5 * probe,
        std::max({t[0], t[2], t[4]}) + 0.5 * probe, std::max({t[1], t[3], t[5]}) + 0.5 * probe};
  }
  std::set<std::pair<uint32_t, uint32_t>> chart_pairs;
  double gap = probe;
  // UV units: float32 rounding of UVs near 1 is 6e-8; this is 1/1600 texel
  // at 4096 texels, far below any real overlap.
  constexpr double kTolerance = 1.5e-7;
  ForEachIntersectingBoxPair(boxes, [&](uint32_t i, uint32_t j) {
    const Tri2 a = UvTriangle(mesh, i), b = UvTriangle(mesh, j);
    if (TrianglesOverlap(a, b, kTolerance)) {
      ++report.overlapping_faces;
      if (chart[i] != chart[j]) chart_pairs.insert(std::minmax(chart[i], chart[j]));
      gap = chart[i] != chart[j] ? 0 : gap;
    } else if (chart[i] != chart[j]) {
      gap = std::min(gap, TriangleDistance(a, b));
    }
    return true;
  });
  report.overlapping_chart_pairs = chart_pairs.size();
  report.min_chart_gap_texels = gap * size_texels;
  return report;
}

Image DrawAtlas(const Mesh& mesh, int pixels) {
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

}  // namespace pb
