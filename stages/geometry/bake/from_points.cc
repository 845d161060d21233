#include "stages/geometry/bake/from_points.h"

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "stages/geometry/bake/raster.h"
#include "stages/geometry/core/mesh.h"
#include "stages/geometry/core/vec3.h"

namespace pb {
namespace {

using vec3::Cross;
using vec3::Dot;
using vec3::Norm;
using vec3::Scale;
using vec3::Sub;
using vec3::V3;

struct FaceScratch {
  FaceInterpolator interpolator;
  std::vector<TexelSample> points;
  std::vector<std::array<float, 3>> colors;
  std::vector<std::array<float, 3>> normals;
};

// Texels per meter on `face`: sqrt(UV area in texels^2 / 3-D area in m^2).
double TexelsPerMeter(const Mesh& mesh, uint32_t face, int size) {
  const uint32_t* v = &mesh.indices[3 * size_t(face)];
  auto p = [&](int k, int c) { return double(mesh.positions[3 * size_t(v[k]) + c]); };
  auto uv = [&](int k, int c) { return double(mesh.uvs[2 * size_t(v[k]) + c]) * size; };
  double e1[3], e2[3];
  for (int c = 0; c < 3; ++c) {
    e1[c] = p(1, c) - p(0, c);
    e2[c] = p(2, c) - p(0, c);
  }
  const double cx = e1[1] * e2[2] - e1[2] * e2[1];
  const double cy = e1[2] * e2[0] - e1[0] * e2[2];
  const double cz = e1[0] * e2[1] - e1[1] * e2[0];
  const double area_m2 = 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
  const double area_texels = 0.5 * std::abs((uv(1, 0) - uv(0, 0)) * (uv(2, 1) - uv(0, 1)) -
                                            (uv(1, 1) - uv(0, 1)) * (uv(2, 0) - uv(0, 0)));
  if (!(area_m2 > 0)) return 0;
  return std::sqrt(area_texels / area_m2);
}

// Appends to `out` the points of the faces across `face`'s edges that lie
// within a band of about two point spacings of the shared edge, placed in
// `face`'s texel space: the neighbour is unfolded about the edge into the
// face's plane (an isometry), and the face's affine map from its plane to
// its UV triangle takes it from there. Returns how many were appended.
size_t BorrowAcrossEdges(const Mesh& mesh, std::span<const uint32_t> welded,
                         std::span<const uint32_t> partners, const MappedPoints& mapped,
                         uint32_t face, int size, bool point_normals, std::vector<TexelSample>& out) {
  size_t borrowed = 0;
  for (int k = 0; k < 3; ++k) {
    const uint32_t partner = partners[3 * size_t(face) + k];
    if (partner == kBorderEdge || partner == kNoPartner) continue;
    const uint32_t other = partner / 3;
    const uint64_t begin = mapped.face_begin[other], end = mapped.face_begin[other + 1];
    if (begin == end) continue;
    const size_t fa = mesh.indices[3 * size_t(face) + k];
    const size_t fb = mesh.indices[3 * size_t(face) + (k + 1) % 3];
    const size_t fc = mesh.indices[3 * size_t(face) + (k + 2) % 3];
    const size_t g0 = mesh.indices[partner];
    const size_t g1 = mesh.indices[3 * size_t(other) + (partner % 3 + 1) % 3];
    const size_t gd = mesh.indices[3 * size_t(other) + (partner % 3 + 2) % 3];
    const V3 a = VertexPosition(mesh, fa), b = VertexPosition(mesh, fb), c = VertexPosition(mesh, fc);
    const V3 d = VertexPosition(mesh, gd);
    // The face in a 2-D frame: a at the origin, b on +x, c above.
    const V3 ab = Sub(b, a), ac = Sub(c, a), ad = Sub(d, a);
    const double length = Norm(ab);
    if (!(length > 0)) continue;
    const V3 x_axis = Scale(ab, 1 / length);
    const double cx = Dot(ac, x_axis), cy = Norm(Sub(ac, Scale(x_axis, cx)));
    if (!(cy > 1e-9 * length)) continue;
    // d unfolded below the edge, and its barycentric coordinates there.
    const double dx = Dot(ad, x_axis), dy = -Norm(Sub(ad, Scale(x_axis, dx)));
    const double gamma = dy / cy, beta = (dx - gamma * cx) / length, alpha = 1 - beta - gamma;
    const auto ta = TexelPosition(mesh, fa, size), tb = TexelPosition(mesh, fb, size),
               tc = TexelPosition(mesh, fc, size);
    const std::array<double, 2> td{alpha * ta[0] + beta * tb[0] + gamma * tc[0],
                                   alpha * ta[1] + beta * tb[1] + gamma * tc[1]};
    // The neighbour's own texel triangle, and where its corners go.
    const auto s0 = TexelPosition(mesh, g0, size), s1 = TexelPosition(mesh, g1, size),
               s2 = TexelPosition(mesh, gd, size);
    const bool same_way = welded[g0] == welded[fa];
    const auto& t0 = same_way ? ta : tb;
    const auto& t1 = same_way ? tb : ta;
    const double det = (s1[0] - s0[0]) * (s2[1] - s0[1]) - (s2[0] - s0[0]) * (s1[1] - s0[1]);
    const double area_m2 = 0.5 * Norm(Cross(ab, ad));
    if (!(std::abs(det) > 1e-12) || !(area_m2 > 0)) continue;
    // The points within two spacings of the edge, a spacing being the side
    // of the square each point has, sqrt(area / n): 2 sqrt(area / n) in
    // units of the neighbour's height over the edge, 2 area / length. (1.4
    // and 2.8 spacings measured the same on the real scans; 4.2, no better,
    // took 1.8x the paper's CPU time, 2 takes 1.3x: docs/bake-interpolation.md.)
    const double band =
        std::min(1.0, std::sqrt(length * length / (area_m2 * double(end - begin))));
    for (uint64_t i = begin; i < end; ++i) {
      const double ps = mapped.st[2 * i] - s0[0], pt = mapped.st[2 * i + 1] - s0[1];
      const double l1 = (ps * (s2[1] - s0[1]) - (s2[0] - s0[0]) * pt) / det;
      const double l2 = ((s1[0] - s0[0]) * pt - ps * (s1[1] - s0[1])) / det;
      if (!(l2 <= band)) continue;
      const double l0 = 1 - l1 - l2;
      TexelSample sample;
      sample.s = float(l0 * t0[0] + l1 * t1[0] + l2 * td[0]);
      sample.t = float(l0 * t0[1] + l1 * t1[1] + l2 * td[1]);
      for (int ch = 0; ch < 3; ++ch) sample.color[ch] = mapped.colors[3 * i + ch];
      sample.normal = point_normals ? std::array<float, 3>{mapped.normals[3 * i], mapped.normals[3 * i + 1],
                                                           mapped.normals[3 * i + 2]}
                                    : std::array<float, 3>{0, 0, 1};
      out.push_back(sample);
      ++borrowed;
    }
  }
  return borrowed;
}

}  // namespace

Expected<BakeResult> BakeFromPoints(Mesh low, PointCloud&& cloud, const BakeOptions& options,
                                    const FromPointsOptions& from_points,
                                    FromPointsReport* report) {
  if (!cloud.has_colors()) {
    return Status::Invalid("bake.from_points: the point cloud has no colors");
  }
  if (!(from_points.splat_sigma_m > 0)) {
    return Status::Invalid("bake.from_points: splat sigma must be > 0 meters");
  }
  BakeResult result;
  PB_ASSIGN_OR_RETURN(result.mesh, PrepareBakeMesh(std::move(low)));
  const Mesh& mesh = result.mesh;
  PB_ASSIGN_OR_RETURN(const BakeRaster raster, BakeRaster::Build(mesh, options.size, options.threads));

  AssignOptions assign;
  assign.max_distance_m = from_points.max_distance_m;
  assign.max_angle_deg = from_points.max_angle_deg;
  assign.size = options.size;
  assign.threads = options.threads;
  if (options.progress) assign.progress = [&](double f) { options.progress(0.5 * f); };
  AssignReport assign_report;
  PB_ASSIGN_OR_RETURN(const MappedPoints mapped,
                      AssignPointsToFaces(mesh, std::move(cloud), assign, &assign_report));
  cloud = PointCloud();  // whatever the assignment left is not needed

  result.maps = BakeMaps::Make(options.size, options.float_normals);
  BakeMaps& maps = result.maps;
  const bool point_normals = !mapped.normals.empty();
  std::vector<uint32_t> welded, partners;
  if (from_points.neighbors) {
    welded = WeldedVertices(mesh);
    partners = EdgePartners(mesh, welded);
  }
  std::atomic<size_t> faces_with_points{0}, faces_from_corners{0}, points_borrowed{0};
  tbb::enumerable_thread_specific<FaceScratch> scratch;
  ForEachBakeFace(mesh, raster, options.threads, [&](uint32_t face, std::span<const BakeTexel> texels) {
    FaceScratch& local = scratch.local();
    const uint64_t begin = mapped.face_begin[face], end = mapped.face_begin[face + 1];
    local.points.resize(end - begin);
    std::array<double, 3> mean_color{};
    for (uint64_t i = begin; i < end; ++i) {
      TexelSample& sample = local.points[i - begin];
      sample.s = mapped.st[2 * i];
      sample.t = mapped.st[2 * i + 1];
      for (int c = 0; c < 3; ++c) {
        sample.color[c] = mapped.colors[3 * i + c];
        mean_color[c] += sample.color[c];
      }
      // Without point normals the normal map stays flat (not written below).
      sample.normal = point_normals ? std::array<float, 3>{mapped.normals[3 * i], mapped.normals[3 * i + 1],
                                                           mapped.normals[3 * i + 2]}
                                    : std::array<float, 3>{0, 0, 1};
    }
    // A face with no point of its own keeps its corners' blend: its points
    // are not where the scan is (a bevel Poisson rounded in front of a
    // room's corner), and the neighbours' edge bands alone would span its
    // inside with large flat triangles.
    const bool borrow = from_points.neighbors && end > begin;
    if (borrow) {
      const size_t borrowed =
          BorrowAcrossEdges(mesh, welded, partners, mapped, face, options.size, point_normals, local.points);
      points_borrowed.fetch_add(borrowed, std::memory_order_relaxed);
    }
    std::array<TexelSample, 3> corners;
    for (int k = 0; k < 3; ++k) {
      const size_t v = mesh.indices[3 * size_t(face) + k];
      const std::array<double, 2> texel = TexelPosition(mesh, v, options.size);
      corners[k].s = float(texel[0]);
      corners[k].t = float(texel[1]);
      for (int c = 0; c < 3; ++c) {
        // Without vertex colors the corners take the face's mean point color
        // (mid gray on a face with no points).
        corners[k].color[c] = mesh.has_colors() ? float(mesh.colors[3 * v + c])
                              : end > begin     ? float(mean_color[c] / double(end - begin))
                                                : 128.0f;
        corners[k].normal[c] = mesh.normals[3 * v + c];
      }
    }
    if (end > begin) {
      faces_with_points.fetch_add(1, std::memory_order_relaxed);
    } else {
      faces_from_corners.fetch_add(1, std::memory_order_relaxed);
    }
    TexelInterpolationOptions interpolation = from_points.interpolation;
    // The corners stay samples of a face with fewer than three points of
    // its own: with the neighbours' bands they anchor its inside.
    if (borrow && end - begin >= 3) interpolation.corner_samples = false;
    interpolation.splat_sigma_texels =
        std::max(0.5f, float(from_points.splat_sigma_m * TexelsPerMeter(mesh, face, options.size)));
    local.interpolator.Interpolate(corners, local.points, texels, interpolation, local.colors,
                                   local.normals);
    for (size_t i = 0; i < texels.size(); ++i) {
      const BakeTexel& texel = texels[i];
      maps.SetColor(texel.x, texel.y, local.colors[i]);
      if (point_normals) {
        const TexelFrame frame = FrameAt(mesh, face, texel.bary);
        maps.SetNormal(texel.x, texel.y, ToTangentSpace(frame, local.normals[i]));
      }
    }
  }, options.progress ? std::function<void(double)>([&](double f) { options.progress(0.5 + 0.45 * f); })
                      : std::function<void(double)>());

  result.covered_texels = raster.covered_texels();
  result.edge_texels = raster.edge_texels();
  result.gutter_texels = DilateBakeMaps(maps, raster, options.gutter, options.threads);
  if (report) {
    report->assign = assign_report;
    report->faces_with_points = faces_with_points.load();
    report->faces_from_corners = faces_from_corners.load();
    report->points_borrowed = points_borrowed.load();
  }
  return result;
}

}  // namespace pb
