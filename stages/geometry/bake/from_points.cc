#include "stages/geometry/bake/from_points.h"

#include <tbb/enumerable_thread_specific.h>

#include <atomic>
#include <cmath>
#include <string>
#include <utility>

namespace pb {
namespace {

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
  std::atomic<size_t> faces_with_points{0}, faces_from_corners{0};
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
    std::array<TexelSample, 3> corners;
    for (int k = 0; k < 3; ++k) {
      const size_t v = mesh.indices[3 * size_t(face) + k];
      corners[k].s = mesh.uvs[2 * v] * float(options.size);
      corners[k].t = (1.0f - mesh.uvs[2 * v + 1]) * float(options.size);
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
  }
  return result;
}

}  // namespace pb
