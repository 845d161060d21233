// Splat rendering (splat.h): screen-aligned disks, a per-tile depth pass and a
// per-tile blending pass, tiles processed independently so the result does
// not depend on scheduling. Sources: surface splatting in its simplest form
// (Zwicker, Pfister, van Baar, Gross 2001, "Surface Splatting", SIGGRAPH:
// visibility with a depth tolerance, then a normalized weighted sum of the
// splats of the front surface). Departs from it: disks face the camera
// instead of lying in the tangent plane (scans without normals are drawn the
// same way; at 512-1024 px a disk is a few pixels), and the weight is a
// truncated parabola, not an EWA-filtered Gaussian (no texture prefiltering
// is needed: a splat is one color). Built with -ffp-contract=off
// -fno-fast-math like render.cc.
#include "stages/geometry/render/splat.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "stages/geometry/core/vec3.h"

namespace pb {
namespace {

using vec3::V3;
using vec3::Sub;
using vec3::Dot;
using vec3::Cross;

V3 Normalize(const V3& a) {
  const double length = std::sqrt(Dot(a, a));
  return length > 0 ? V3{a[0] / length, a[1] / length, a[2] / length} : a;
}
bool Finite(const V3& a) { return std::isfinite(a[0]) && std::isfinite(a[1]) && std::isfinite(a[2]); }

constexpr int kTile = 64;  // tile side, samples
constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

// The camera of render.h: the same frame, focal length and sample grid.
struct SplatCamera {
  V3 eye{}, right{}, up{}, forward{};
  int samples = 0;
  double half = 0, focal = 0;
  // The view depth of `rel` (a position relative to the eye) and its sample
  // coordinates (meaningless when the depth is below the near plane).
  double Project(const V3& rel, double& x, double& y) const {
    const double z = Dot(rel, forward);
    x = half + focal * Dot(rel, right) / z;
    y = half - focal * Dot(rel, up) / z;
    return z;
  }
};

Expected<SplatCamera> MakeCamera(const RenderCamera& camera, const std::array<double, 3>& origin,
                                 const SplatOptions& options) {
  if (!(camera.size >= 1 && camera.size <= 16384))
    return Status::Invalid("splats: size must be in [1, 16384], got " + std::to_string(camera.size));
  if (!(options.supersample >= 1 && options.supersample <= 16))
    return Status::Invalid("splats: supersample must be in [1, 16], got " + std::to_string(options.supersample));
  if (camera.size * options.supersample > 16384)
    return Status::Invalid("splats: size * supersample must be <= 16384 samples per axis");
  if (!(camera.fov_deg > 0 && camera.fov_deg < 180))
    return Status::Invalid("splats: fov_deg must be in (0, 180), got " + std::to_string(camera.fov_deg));
  if (!Finite(camera.eye) || !Finite(camera.target) || !Finite(camera.up))
    return Status::Invalid("splats: eye, target and up must be finite");
  if (!(options.depth_tolerance >= 0) || !std::isfinite(options.depth_tolerance))
    return Status::Invalid("splats: depth_tolerance must be finite and >= 0");
  if (!(options.max_radius_px > 0) || !std::isfinite(options.max_radius_px))
    return Status::Invalid("splats: max_radius_px must be finite and > 0");
  SplatCamera cam;
  cam.eye = Sub(camera.eye, origin);
  const V3 view = Sub(camera.target, camera.eye);
  if (Dot(view, view) == 0) return Status::Invalid("splats: eye and target are the same point");
  cam.forward = Normalize(view);
  const V3 side = Cross(cam.forward, camera.up);
  if (std::sqrt(Dot(side, side)) < 1e-9 * std::sqrt(Dot(camera.up, camera.up)) || Dot(camera.up, camera.up) == 0)
    return Status::Invalid("splats: up is zero or parallel to the view direction");
  cam.right = Normalize(side);
  cam.up = Cross(cam.right, cam.forward);
  cam.samples = camera.size * options.supersample;
  cam.half = cam.samples * 0.5;
  cam.focal = cam.half / std::tan(camera.fov_deg * M_PI / 360.0);
  return cam;
}

// A point on screen: center and radius in samples, view depth in meters,
// and its box of covered samples (inclusive).
struct ScreenSplat {
  double x = 0, y = 0, radius = 0;
  float depth = 0;
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
  bool visible() const { return x0 <= x1 && y0 <= y1; }
};

// A disk in its tangent plane (SplatShapes::normal): center relative to the
// eye, unit normal, radius in meters (after the screen cap), and its clip
// line (direction 0: none). radius_m 0: the point's disk faces the camera.
struct OrientedSplat {
  V3 center{}, normal{}, clip{};
  double radius_m = 0, clip_m = 0;
};

}  // namespace

Expected<Image> RenderSplats(const PointCloud& cloud, const SplatShapes& shapes, const RenderCamera& camera,
                             const SplatOptions& options, SplatStats* stats, Image* depth_m, Image* samples) {
  PB_RETURN_IF_ERROR(Validate(cloud));
  const std::span<const float> radius_m = shapes.radius_m;
  if (radius_m.size() != cloud.size())
    return Status::Invalid("splats: " + std::to_string(radius_m.size()) + " radii for " +
                           std::to_string(cloud.size()) + " points");
  const bool oriented = !shapes.normal.empty();
  if (oriented && shapes.normal.size() != cloud.size() * 3)
    return Status::Invalid("splats: " + std::to_string(shapes.normal.size()) + " normal floats for " +
                           std::to_string(cloud.size()) + " points (3 each)");
  if (!shapes.clip.empty() && (!oriented || shapes.clip.size() != cloud.size() * 4))
    return Status::Invalid("splats: clip lines need normals and 4 floats per point, got " +
                           std::to_string(shapes.clip.size()) + " for " + std::to_string(cloud.size()) + " points");
  if (!shapes.sample_at.empty() && shapes.sample_at.size() != cloud.size() * 3)
    return Status::Invalid("splats: " + std::to_string(shapes.sample_at.size()) + " sample position floats for " +
                           std::to_string(cloud.size()) + " points (3 each)");
  if (cloud.size() >= size_t(kNone)) return Status::Invalid("splats: too many points");
  PB_ASSIGN_OR_RETURN(const SplatCamera cam, MakeCamera(camera, cloud.origin, options));
  const size_t n = cloud.size();
  const double max_radius = options.max_radius_px * options.supersample;

  std::vector<ScreenSplat> splats(n);
  std::vector<OrientedSplat> disks(oriented ? n : 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i < range.end(); ++i) {
      const float* p = &cloud.positions[i * 3];
      const V3 rel = Sub({double(p[0]), double(p[1]), double(p[2])}, cam.eye);
      double x, y;
      const double z = cam.Project(rel, x, y);
      const double r_m = radius_m[i];
      ScreenSplat& s = splats[i];
      if (!(z >= kNearPlaneM) || !(r_m > 0) || !std::isfinite(r_m)) continue;
      s.x = x;
      s.y = y;
      s.radius = std::min(cam.focal * r_m / z, max_radius);
      s.depth = float(z);
      double lo_x, hi_x, lo_y, hi_y;
      const bool tangent = oriented && (shapes.normal[i * 3] != 0 || shapes.normal[i * 3 + 1] != 0 ||
                                        shapes.normal[i * 3 + 2] != 0);
      if (!tangent) {
        // Samples whose centers (k + 0.5) lie within the radius of the center.
        lo_x = std::ceil(s.x - s.radius - 0.5), hi_x = std::floor(s.x + s.radius - 0.5);
        lo_y = std::ceil(s.y - s.radius - 0.5), hi_y = std::floor(s.y + s.radius - 0.5);
      } else {
        OrientedSplat& d = disks[i];
        const float* nf = &shapes.normal[i * 3];
        d.normal = Normalize({double(nf[0]), double(nf[1]), double(nf[2])});
        if (!Finite(d.normal)) continue;
        d.center = rel;
        d.radius_m = s.radius * z / cam.focal;  // the screen cap, in meters at the center's depth
        if (!shapes.clip.empty()) {
          const float* c = &shapes.clip[i * 4];
          d.clip = {double(c[0]), double(c[1]), double(c[2])};
          d.clip_m = c[3];
        }
        // The disk lies in the square center +- r a +- r b (a, b spanning its
        // plane); the square's projection, the hull of its corners', bounds it.
        const V3 helper = std::abs(d.normal[0]) < 0.9 ? V3{1, 0, 0} : V3{0, 1, 0};
        const V3 a = Normalize(Cross(d.normal, helper)), b = Cross(d.normal, a);
        lo_x = lo_y = HUGE_VAL;
        hi_x = hi_y = -HUGE_VAL;
        bool behind = false;
        for (const double sa : {-1.0, 1.0})
          for (const double sb : {-1.0, 1.0}) {
            V3 corner;
            for (int c = 0; c < 3; ++c) corner[c] = rel[c] + d.radius_m * (sa * a[c] + sb * b[c]);
            double cx, cy;
            const double cz = cam.Project(corner, cx, cy);
            if (!(cz >= kNearPlaneM)) behind = true;
            lo_x = std::min(lo_x, cx), hi_x = std::max(hi_x, cx);
            lo_y = std::min(lo_y, cy), hi_y = std::max(hi_y, cy);
          }
        if (behind) continue;  // a disk reaching behind the near plane is not drawn
        lo_x = std::ceil(lo_x - 0.5), hi_x = std::floor(hi_x - 0.5);
        lo_y = std::ceil(lo_y - 0.5), hi_y = std::floor(hi_y - 0.5);
      }
      if (!(hi_x >= 0 && hi_y >= 0 && lo_x <= cam.samples - 1 && lo_y <= cam.samples - 1)) continue;
      s.x0 = int(std::max(lo_x, 0.0));
      s.y0 = int(std::max(lo_y, 0.0));
      s.x1 = int(std::min(hi_x, double(cam.samples - 1)));
      s.y1 = int(std::min(hi_y, double(cam.samples - 1)));
    }
  });

  // Bin the splats by tile: counts, offsets, then each tile's list sorted by
  // point index (filled in parallel, so sorted afterwards).
  const int tiles_per_axis = (cam.samples + kTile - 1) / kTile;
  const size_t tile_count = size_t(tiles_per_axis) * tiles_per_axis;
  std::vector<std::atomic<uint32_t>> counts(tile_count);
  for (auto& c : counts) c.store(0, std::memory_order_relaxed);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i < range.end(); ++i) {
      const ScreenSplat& s = splats[i];
      if (!s.visible()) continue;
      for (int ty = s.y0 / kTile; ty <= s.y1 / kTile; ++ty)
        for (int tx = s.x0 / kTile; tx <= s.x1 / kTile; ++tx)
          counts[size_t(ty) * tiles_per_axis + tx].fetch_add(1, std::memory_order_relaxed);
    }
  });
  std::vector<size_t> offsets(tile_count + 1, 0);
  for (size_t t = 0; t < tile_count; ++t) offsets[t + 1] = offsets[t] + counts[t].load();
  std::vector<uint32_t> entries(offsets.back());
  std::vector<std::atomic<size_t>> cursor(tile_count);
  for (size_t t = 0; t < tile_count; ++t) cursor[t].store(offsets[t], std::memory_order_relaxed);
  std::atomic<size_t> drawn{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& range) {
    size_t drawn_here = 0;
    for (size_t i = range.begin(); i < range.end(); ++i) {
      const ScreenSplat& s = splats[i];
      if (!s.visible()) continue;
      ++drawn_here;
      for (int ty = s.y0 / kTile; ty <= s.y1 / kTile; ++ty)
        for (int tx = s.x0 / kTile; tx <= s.x1 / kTile; ++tx)
          entries[cursor[size_t(ty) * tiles_per_axis + tx].fetch_add(1, std::memory_order_relaxed)] = uint32_t(i);
    }
    drawn += drawn_here;
  });

  // Per sample: linear RGB and whether any splat covered it.
  const size_t sample_count = size_t(cam.samples) * cam.samples;
  std::vector<float> color(sample_count * 3, 0.0f);
  std::vector<uint8_t> covered(sample_count, 0);
  std::vector<float> sample_depth(depth_m ? sample_count : 0, 0.0f);
  // With `samples`: per sample the farthest depth that blends with its front
  // splat (infinity where no splat covers it).
  std::vector<double> visible_limit(samples ? sample_count : 0, std::numeric_limits<double>::infinity());
  const float gray = SrgbByteToLinear(kDefaultGray);
  std::array<float, 256> decode{};
  for (int v = 0; v < 256; ++v) decode[v] = SrgbByteToLinear(uint8_t(v));

  tbb::parallel_for(tbb::blocked_range<size_t>(0, tile_count, 1), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<float> depth(size_t(kTile) * kTile);
    std::vector<uint32_t> front(size_t(kTile) * kTile);
    std::vector<double> sum(size_t(kTile) * kTile * 4);
    for (size_t t = range.begin(); t < range.end(); ++t) {
      uint32_t* list = entries.data() + offsets[t];
      const size_t list_size = offsets[t + 1] - offsets[t];
      if (list_size == 0) continue;
      std::sort(list, list + list_size);
      const int tile_x0 = int(t % tiles_per_axis) * kTile, tile_y0 = int(t / tiles_per_axis) * kTile;
      const int tile_x1 = std::min(tile_x0 + kTile, cam.samples) - 1;
      const int tile_y1 = std::min(tile_y0 + kTile, cam.samples) - 1;
      std::fill(depth.begin(), depth.end(), std::numeric_limits<float>::infinity());
      std::fill(front.begin(), front.end(), kNone);
      std::fill(sum.begin(), sum.end(), 0.0);
      // Visits the samples of splat `i` inside this tile and its disk:
      // visit(local sample index, squared distance / squared radius, depth).
      auto for_each_sample = [&](uint32_t i, const auto& visit) {
        const ScreenSplat& s = splats[i];
        if (!oriented || disks[i].radius_m == 0) {
          const double r2 = s.radius * s.radius;
          for (int sy = std::max(s.y0, tile_y0); sy <= std::min(s.y1, tile_y1); ++sy) {
            const double dy = sy + 0.5 - s.y;
            for (int sx = std::max(s.x0, tile_x0); sx <= std::min(s.x1, tile_x1); ++sx) {
              const double dx = sx + 0.5 - s.x;
              const double d2 = dx * dx + dy * dy;
              if (d2 > r2) continue;
              visit(size_t(sy - tile_y0) * kTile + size_t(sx - tile_x0), r2 > 0 ? d2 / r2 : 0.0, s.depth);
            }
          }
          return;
        }
        // The sample's ray, eye + t * ray with ray . forward = 1 (t is the
        // view depth), meets the disk's plane at t = n . center / n . ray.
        const OrientedSplat& d = disks[i];
        const double r2 = d.radius_m * d.radius_m;
        const double height = Dot(d.normal, d.center);
        for (int sy = std::max(s.y0, tile_y0); sy <= std::min(s.y1, tile_y1); ++sy) {
          const double v = (cam.half - (sy + 0.5)) / cam.focal;
          for (int sx = std::max(s.x0, tile_x0); sx <= std::min(s.x1, tile_x1); ++sx) {
            const double u = (sx + 0.5 - cam.half) / cam.focal;
            V3 ray;
            for (int c = 0; c < 3; ++c) ray[c] = u * cam.right[c] + v * cam.up[c] + cam.forward[c];
            const double facing = Dot(d.normal, ray);
            if (facing == 0) continue;  // the disk seen exactly edge-on
            const double t = height / facing;
            if (!(t >= kNearPlaneM)) continue;
            V3 offset;
            for (int c = 0; c < 3; ++c) offset[c] = t * ray[c] - d.center[c];
            const double d2 = Dot(offset, offset);
            if (d2 > r2) continue;
            if (Dot(offset, d.clip) > d.clip_m) continue;
            visit(size_t(sy - tile_y0) * kTile + size_t(sx - tile_x0), r2 > 0 ? d2 / r2 : 0.0, float(t));
          }
        }
      };
      for (size_t e = 0; e < list_size; ++e) {
        const uint32_t i = list[e];
        for_each_sample(i, [&](size_t local, double, float z) {
          if (z < depth[local]) {  // strict: ties keep the lower index
            depth[local] = z;
            front[local] = i;
          }
        });
      }
      for (size_t e = 0; e < list_size; ++e) {
        const uint32_t i = list[e];
        float rgb[3] = {gray, gray, gray};
        if (cloud.has_colors())
          for (int c = 0; c < 3; ++c) rgb[c] = decode[cloud.colors[size_t(i) * 3 + c]];
        for_each_sample(i, [&](size_t local, double q, float z) {
          const double limit = double(depth[local]) + options.depth_tolerance * double(radius_m[front[local]]);
          if (!(double(z) <= limit)) return;
          const double w = 1.0 - q + 1.0 / 16;
          double* acc = &sum[local * 4];
          for (int c = 0; c < 3; ++c) acc[c] += w * rgb[c];
          acc[3] += w;
        });
      }
      for (int sy = tile_y0; sy <= tile_y1; ++sy)
        for (int sx = tile_x0; sx <= tile_x1; ++sx) {
          const size_t local = size_t(sy - tile_y0) * kTile + size_t(sx - tile_x0);
          if (front[local] == kNone) continue;
          const size_t global = size_t(sy) * cam.samples + sx;
          const double* acc = &sum[local * 4];
          for (int c = 0; c < 3; ++c) color[global * 3 + c] = float(acc[c] / acc[3]);
          covered[global] = 1;
          if (depth_m) sample_depth[global] = depth[local];
          if (samples)
            visible_limit[global] = double(depth[local]) + options.depth_tolerance * double(radius_m[front[local]]);
        }
    }
  });

  // Resolve as render.cc does: box average in linear light, sRGB bytes.
  const int size = camera.size, ss = options.supersample;
  Image image = Image::Make(size, size, 4, Image::PixelType::kU8);
  const double background[3] = {decode[options.background[0]], decode[options.background[1]],
                                decode[options.background[2]]};
  const double inv_count = 1.0 / double(ss * ss);
  std::atomic<size_t> covered_total{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, size), [&](const tbb::blocked_range<int>& rows) {
    size_t covered_here = 0;
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < size; ++x) {
        double rgb[3] = {0, 0, 0};
        int hits = 0;
        for (int j = 0; j < ss; ++j)
          for (int i = 0; i < ss; ++i) {
            const size_t s = size_t(y * ss + j) * cam.samples + size_t(x * ss + i);
            const bool hit = covered[s] != 0;
            hits += hit ? 1 : 0;
            for (int c = 0; c < 3; ++c) rgb[c] += hit ? double(color[s * 3 + c]) : background[c];
          }
        uint8_t* out = &image.at_u8(x, y, 0);
        for (int c = 0; c < 3; ++c) out[c] = LinearToSrgbByte(rgb[c] * inv_count);
        out[3] = hits > 0 ? 255 : 0;
        covered_here += size_t(hits);
      }
    covered_total += covered_here;
  });
  if (depth_m) {
    *depth_m = Image::Make(size, size, 1, Image::PixelType::kF32);
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        float nearest = 0;
        for (int j = 0; j < ss; ++j)
          for (int i = 0; i < ss; ++i) {
            const float d = sample_depth[size_t(y * ss + j) * cam.samples + size_t(x * ss + i)];
            if (d > 0 && (nearest == 0 || d < nearest)) nearest = d;
          }
        depth_m->f32()[size_t(y) * size + x] = nearest;
      }
  }
  size_t sample_pixels = 0;
  if (samples) {
    // One pass over the points in index order (each writes 255 or nothing,
    // so the mask does not depend on the order anyway). A point counts only
    // inside the hull of its pixel's sample centers (ss >= 2): see splat.h.
    *samples = Image::Make(size, size, 1, Image::PixelType::kU8);
    uint8_t* mask = samples->u8();
    const double lo = ss >= 2 ? 0.5 : 0.0, hi = ss >= 2 ? ss - 0.5 : double(ss);
    for (size_t i = 0; i < n; ++i) {
      if (!(splats[i].depth > 0)) continue;  // not drawn: behind the near plane, or no valid radius
      double x = splats[i].x, y = splats[i].y, depth = splats[i].depth;
      if (!shapes.sample_at.empty()) {
        const float* p = &shapes.sample_at[i * 3];
        depth = cam.Project(Sub({double(p[0]), double(p[1]), double(p[2])}, cam.eye), x, y);
        if (!(depth >= kNearPlaneM)) continue;
      }
      if (!(x >= 0 && y >= 0 && x < cam.samples && y < cam.samples)) continue;
      const double fx = x - std::floor(x / ss) * ss, fy = y - std::floor(y / ss) * ss;
      if (!(fx >= lo && fx <= hi && fy >= lo && fy <= hi)) continue;
      const int sx = int(x), sy = int(y);
      if (!(depth <= visible_limit[size_t(sy) * cam.samples + sx])) continue;
      uint8_t& m = mask[size_t(sy / ss) * size + size_t(sx / ss)];
      sample_pixels += m == 0 ? 1 : 0;
      m = 255;
    }
  }
  if (stats) {
    stats->sample_pixels = sample_pixels;
    stats->points = n;
    stats->drawn = drawn.load();
    stats->covered_samples = covered_total.load();
  }
  return image;
}

}  // namespace pb
