// The reference renderer (render.h): a two-pass rasterizer. Pass 1 writes a
// visibility buffer of 64-bit (depth, triangle) keys with atomic min, so the
// result does not depend on the order triangles are drawn in; pass 2 shades
// each sample from its triangle with ray-plane barycentrics (perspective
// correct without carrying clipped attributes). Departs from a GPU in two
// ways that do not change pictures measurably: it shades every sample (SSAA,
// with the LOD of the pixel footprint as MSAA would), and it has no far
// plane. Built with -ffp-contract=off -fno-fast-math (CMakeLists.txt).
#include "stages/geometry/render/render.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "stages/geometry/core/vec3.h"

namespace pb {
namespace {

using vec3::V3;
using vec3::Sub;
using vec3::Add;
using vec3::Scale;
using vec3::Dot;
using vec3::Cross;

// Zero stays zero.
V3 Normalize(const V3& a) {
  const double length = std::sqrt(Dot(a, a));
  return length > 0 ? Scale(a, 1.0 / length) : a;
}
bool Finite(const V3& a) { return std::isfinite(a[0]) && std::isfinite(a[1]) && std::isfinite(a[2]); }

double SrgbDecodeExact(double c) {
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

struct SrgbTables {
  std::array<float, 256> decode{};
  std::array<double, 255> thresholds{};  // linear value where byte k becomes k + 1
  SrgbTables() {
    for (int i = 0; i < 256; ++i) decode[i] = float(SrgbDecodeExact(i / 255.0));
    for (int i = 0; i < 255; ++i) thresholds[i] = SrgbDecodeExact((i + 0.5) / 255.0);
  }
};
const SrgbTables& Srgb() {
  static const SrgbTables tables;
  return tables;
}

// The camera frame with the eye in the coordinates the geometry uses.
struct CameraFrame {
  V3 eye{}, right{}, up{}, forward{};
  int samples = 0;     // per axis of the whole image (size * supersample)
  int supersample = 1;
  double focal = 0;    // in samples
  double half = 0;     // samples / 2
  V3 light{};          // unit, toward the light, world orientation

  // Ray direction (not unit) through sample-space point (px, py).
  V3 Ray(double px, double py) const {
    const double dx = (px - half) / focal, dy = (half - py) / focal;
    return Add(Add(Scale(right, dx), Scale(up, dy)), forward);
  }
};

Expected<CameraFrame> MakeFrame(const RenderCamera& camera, const std::array<double, 3>& origin,
                                const RenderOptions& options) {
  if (!(camera.size >= 1 && camera.size <= 16384))
    return Status::Invalid("render: size must be in [1, 16384], got " + std::to_string(camera.size));
  if (!(options.supersample >= 1 && options.supersample <= 16))
    return Status::Invalid("render: supersample must be in [1, 16], got " +
                           std::to_string(options.supersample));
  // The visibility buffer takes 8 bytes per sample: 2 GiB at the limit.
  if (camera.size * options.supersample > 16384)
    return Status::Invalid("render: size * supersample must be <= 16384 samples per axis, got " +
                           std::to_string(camera.size) + " * " + std::to_string(options.supersample));
  if (!(camera.fov_deg > 0 && camera.fov_deg < 180))
    return Status::Invalid("render: fov_deg must be in (0, 180), got " + std::to_string(camera.fov_deg));
  if (!Finite(camera.eye) || !Finite(camera.target) || !Finite(camera.up))
    return Status::Invalid("render: eye, target and up must be finite");
  if (!std::isfinite(options.ambient) || !std::isfinite(options.diffuse) || !Finite(options.light_camera) ||
      Dot(options.light_camera, options.light_camera) == 0)
    return Status::Invalid("render: ambient, diffuse and light_camera must be finite, light nonzero");
  CameraFrame frame;
  // Into mesh-local coordinates in double before anything is rounded.
  frame.eye = Sub(camera.eye, origin);
  const V3 view = Sub(camera.target, camera.eye);
  if (Dot(view, view) == 0) return Status::Invalid("render: eye and target are the same point");
  frame.forward = Normalize(view);
  const V3 side = Cross(frame.forward, camera.up);
  if (std::sqrt(Dot(side, side)) < 1e-9 * std::sqrt(Dot(camera.up, camera.up)) || Dot(camera.up, camera.up) == 0)
    return Status::Invalid("render: up is zero or parallel to the view direction");
  frame.right = Normalize(side);
  frame.up = Cross(frame.right, frame.forward);
  frame.supersample = options.supersample;
  frame.samples = camera.size * options.supersample;
  frame.half = frame.samples * 0.5;
  frame.focal = frame.half / std::tan(camera.fov_deg * M_PI / 360.0);
  const V3& l = options.light_camera;
  frame.light = Normalize(Add(Add(Scale(frame.right, l[0]), Scale(frame.up, l[1])), Scale(frame.forward, l[2])));
  return frame;
}

double Shade(const RenderOptions& options, const CameraFrame& cam, double albedo, const V3& normal) {
  if (options.lighting == RenderLighting::kUnlit) return albedo;
  const double lambert = std::max(0.0, Dot(normal, cam.light));
  return albedo * (options.ambient + options.diffuse * lambert);
}

// What a sample hit: nothing, a face's front, or its back (RenderStats).
enum class SampleHit { kNone, kFront, kBack };

// Resolves every pixel from its samples: `shade(px, py, rgb)` says what the
// sample hit and, when it hit something, sets its linear color. `covered`
// and `back` receive the samples that hit something, and a face's back.
template <typename ShadeSample>
Image Resolve(const CameraFrame& cam, int size, const RenderOptions& options, size_t* covered, size_t* back,
              const ShadeSample& shade) {
  Image image = Image::Make(size, size, 4, Image::PixelType::kU8);
  const SrgbTables& srgb = Srgb();
  const V3 background = {srgb.decode[options.background[0]], srgb.decode[options.background[1]],
                         srgb.decode[options.background[2]]};
  const int ss = cam.supersample;
  const double inv_count = 1.0 / double(ss * ss);
  std::atomic<size_t> covered_total{0}, back_total{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, size), [&](const tbb::blocked_range<int>& rows) {
    size_t covered_here = 0, back_here = 0;
    for (int y = rows.begin(); y < rows.end(); ++y) {
      for (int x = 0; x < size; ++x) {
        V3 sum = {0, 0, 0};
        int hits = 0;
        for (int j = 0; j < ss; ++j) {
          for (int i = 0; i < ss; ++i) {
            const int sx = x * ss + i, sy = y * ss + j;
            V3 rgb;
            if (const SampleHit hit = shade(sx, sy, rgb); hit != SampleHit::kNone) {
              ++hits;
              back_here += hit == SampleHit::kBack ? 1 : 0;
              sum = Add(sum, rgb);
            } else {
              sum = Add(sum, background);
            }
          }
        }
        uint8_t* out = &image.at_u8(x, y, 0);
        for (int c = 0; c < 3; ++c) out[c] = LinearToSrgbByte(sum[c] * inv_count);
        out[3] = hits > 0 ? 255 : 0;
        covered_here += size_t(hits);
      }
    }
    covered_total += covered_here;
    back_total += back_here;
  });
  if (covered) *covered = covered_total.load();
  if (back) *back = back_total.load();
  return image;
}

// ---- textures ----

std::array<float, 3> Lerp(const std::array<float, 3>& a, const std::array<float, 3>& b, float f) {
  return {a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f, a[2] + (b[2] - a[2]) * f};
}

// Texel `index` (x + y * width) of `level`, channel by channel.
std::array<float, 3> Texel(const MipTexture& texture, int level, size_t index) {
  if (level == 0 && !texture.level0_bytes.empty()) {
    const uint8_t* p = &texture.level0_bytes[index * 3];
    return {texture.byte_value[p[0]], texture.byte_value[p[1]], texture.byte_value[p[2]]};
  }
  const float* p = &texture.levels[level].rgb[index * 3];
  return {p[0], p[1], p[2]};
}

std::array<float, 3> SampleBilinear(const MipTexture& texture, int level_index, double u, double v) {
  const MipTexture::Level& level = texture.levels[level_index];
  double s = u * level.width - 0.5, t = (1.0 - v) * level.height - 0.5;
  // Clamp to edge; NaN goes to the edge too.
  if (!(s >= -1)) s = -1;
  if (!(s <= level.width)) s = level.width;
  if (!(t >= -1)) t = -1;
  if (!(t <= level.height)) t = level.height;
  const double fs = std::floor(s), ft = std::floor(t);
  const float fx = float(s - fs), fy = float(t - ft);
  const int x0 = std::clamp(int(fs), 0, level.width - 1), x1 = std::clamp(int(fs) + 1, 0, level.width - 1);
  const int y0 = std::clamp(int(ft), 0, level.height - 1), y1 = std::clamp(int(ft) + 1, 0, level.height - 1);
  auto texel = [&](int x, int y) { return Texel(texture, level_index, size_t(y) * level.width + x); };
  return Lerp(Lerp(texel(x0, y0), texel(x1, y0), fx), Lerp(texel(x0, y1), texel(x1, y1), fx), fy);
}

// uv and its change over one output pixel to the right (dx) and down (dy).
std::array<float, 3> SampleTrilinear(const MipTexture& texture, const std::array<double, 2>& uv,
                                     const std::array<double, 2>& duv_dx, const std::array<double, 2>& duv_dy) {
  const MipTexture::Level& base = texture.levels[0];
  const double ax = duv_dx[0] * base.width, ay = duv_dx[1] * base.height;
  const double bx = duv_dy[0] * base.width, by = duv_dy[1] * base.height;
  const double rho2 = std::max(ax * ax + ay * ay, bx * bx + by * by);
  double lod = rho2 > 0 ? 0.5 * std::log2(rho2) : 0.0;
  const double max_lod = double(texture.levels.size() - 1);
  if (!(lod > 0)) lod = 0;
  if (lod > max_lod) lod = max_lod;
  const int level = int(std::floor(lod));
  const float fraction = float(lod - level);
  std::array<float, 3> c = SampleBilinear(texture, level, uv[0], uv[1]);
  if (fraction > 0 && level + 1 < int(texture.levels.size()))
    c = Lerp(c, SampleBilinear(texture, level + 1, uv[0], uv[1]), fraction);
  return c;
}

// Level 0 from `image`: 8-bit maps keep their bytes (RGB, gray replicated)
// and decode through `byte_value` per fetch; other types are decoded once by
// `decode(image, sample index)`. Then the mip chain.
template <typename DecodeSample>
Expected<MipTexture> BuildTexture(const Image& image, const std::array<float, 256>& byte_value,
                                  const DecodeSample& decode) {
  if (image.width <= 0 || image.height <= 0 || image.channels < 1 || image.channels > 4 ||
      image.data.size() != image.sample_count() * image.bytes_per_sample())
    return Status::Invalid("render: texture is empty or malformed");
  MipTexture texture;
  const bool bytes = image.type == Image::PixelType::kU8;
  const size_t texels = size_t(image.width) * image.height;
  MipTexture::Level level0{image.width, image.height, {}};
  if (bytes) {
    texture.byte_value = byte_value;
    texture.level0_bytes.resize(texels * 3);
  } else {
    level0.rgb.resize(texels * 3);
  }
  const int channels = image.channels;
  tbb::parallel_for(0, image.height, [&](int y) {
    for (int x = 0; x < image.width; ++x) {
      const size_t out = (size_t(y) * image.width + x) * 3;
      for (int c = 0; c < 3; ++c) {
        const size_t sample = image.sample_index(x, y, channels >= 3 ? c : 0);  // gray replicated
        if (bytes)
          texture.level0_bytes[out + c] = image.u8()[sample];
        else
          level0.rgb[out + c] = decode(image, sample);
      }
    }
  });
  texture.levels.push_back(std::move(level0));
  while (texture.levels.back().width > 1 || texture.levels.back().height > 1) {
    const int prev_index = int(texture.levels.size()) - 1;
    const int prev_width = texture.levels.back().width, prev_height = texture.levels.back().height;
    MipTexture::Level next{std::max(1, prev_width / 2), std::max(1, prev_height / 2), {}};
    next.rgb.resize(size_t(next.width) * next.height * 3);
    tbb::parallel_for(0, next.height, [&](int y) {
      const int y0 = std::min(2 * y, prev_height - 1), y1 = std::min(2 * y + 1, prev_height - 1);
      for (int x = 0; x < next.width; ++x) {
        const int x0 = std::min(2 * x, prev_width - 1), x1 = std::min(2 * x + 1, prev_width - 1);
        auto at = [&](int xx, int yy) { return Texel(texture, prev_index, size_t(yy) * prev_width + xx); };
        const auto a = at(x0, y0), b = at(x1, y0), c = at(x0, y1), d = at(x1, y1);
        for (int k = 0; k < 3; ++k)
          next.rgb[(size_t(y) * next.width + x) * 3 + k] = (a[k] + b[k] + c[k] + d[k]) * 0.25f;
      }
    });
    texture.levels.push_back(std::move(next));
  }
  return texture;
}

// ---- rasterization ----

constexpr uint64_t kEmpty = std::numeric_limits<uint64_t>::max();

struct ScreenVertex {
  double x = 0, y = 0, inv_z = 0;
};

// Twice the signed area of (a, b, p), antisymmetric in a and b bit for bit.
double Orient(const ScreenVertex& a, const ScreenVertex& b, double px, double py) {
  return (a.x - px) * (b.y - py) - (a.y - py) * (b.x - px);
}

void RasterTriangle(const ScreenVertex& a, const ScreenVertex& b, const ScreenVertex& c, uint32_t triangle,
                    int samples, std::atomic<uint64_t>* visibility) {
  const double area = Orient(a, b, c.x, c.y);
  if (!(area != 0) || !std::isfinite(area)) return;
  const double sign = area > 0 ? 1.0 : -1.0;
  double x_lo = std::ceil(std::min({a.x, b.x, c.x}) - 0.5), x_hi = std::floor(std::max({a.x, b.x, c.x}) - 0.5);
  double y_lo = std::ceil(std::min({a.y, b.y, c.y}) - 0.5), y_hi = std::floor(std::max({a.y, b.y, c.y}) - 0.5);
  x_lo = std::max(x_lo, 0.0);
  y_lo = std::max(y_lo, 0.0);
  x_hi = std::min(x_hi, double(samples - 1));
  y_hi = std::min(y_hi, double(samples - 1));
  if (!(x_lo <= x_hi) || !(y_lo <= y_hi)) return;
  for (int sy = int(y_lo); sy <= int(y_hi); ++sy) {
    const double py = sy + 0.5;
    for (int sx = int(x_lo); sx <= int(x_hi); ++sx) {
      const double px = sx + 0.5;
      const double e0 = Orient(b, c, px, py) * sign, e1 = Orient(c, a, px, py) * sign,
                   e2 = Orient(a, b, px, py) * sign;
      if (e0 < 0 || e1 < 0 || e2 < 0) continue;
      const double sum = e0 + e1 + e2;
      const double inv_z = (e0 * a.inv_z + e1 * b.inv_z + e2 * c.inv_z) / sum;
      if (!(inv_z > 0)) continue;
      const float depth = float(1.0 / inv_z);
      const uint64_t key = (uint64_t(std::bit_cast<uint32_t>(depth)) << 32) | triangle;
      std::atomic<uint64_t>& slot = visibility[size_t(sy) * samples + sx];
      uint64_t current = slot.load(std::memory_order_relaxed);
      while (key < current && !slot.compare_exchange_weak(current, key, std::memory_order_relaxed)) {
      }
    }
  }
}

struct MeshRaster {
  const Mesh& mesh;
  const CameraFrame& cam;
  std::vector<V3> view;            // per vertex: (right, up, forward) coordinates
  std::vector<ScreenVertex> screen;  // per vertex, valid where view z >= near

  ScreenVertex Project(const V3& v) const {
    return {cam.half + cam.focal * v[0] / v[2], cam.half - cam.focal * v[1] / v[2], 1.0 / v[2]};
  }

  // Returns whether the face was cut by the near plane.
  bool DrawFace(uint32_t face, std::atomic<uint64_t>* visibility) const {
    const uint32_t* idx = &mesh.indices[size_t(face) * 3];
    const bool inside[3] = {view[idx[0]][2] >= kNearPlaneM, view[idx[1]][2] >= kNearPlaneM,
                            view[idx[2]][2] >= kNearPlaneM};
    if (inside[0] && inside[1] && inside[2]) {
      RasterTriangle(screen[idx[0]], screen[idx[1]], screen[idx[2]], face, cam.samples, visibility);
      return false;
    }
    if (!inside[0] && !inside[1] && !inside[2]) return false;
    // Sutherland-Hodgman against z = near; the cut point of an edge is
    // computed from its lower-indexed vertex so neighbours agree bit for bit.
    ScreenVertex polygon[4];
    int count = 0;
    for (int k = 0; k < 3; ++k) {
      const uint32_t p = idx[k], q = idx[(k + 1) % 3];
      const bool p_in = inside[k], q_in = inside[(k + 1) % 3];
      if (p_in) polygon[count++] = screen[p];
      if (p_in != q_in) {
        const uint32_t lo = std::min(p, q), hi = std::max(p, q);
        const V3& a = view[lo];
        const V3& b = view[hi];
        const double t = (kNearPlaneM - a[2]) / (b[2] - a[2]);
        V3 cut = Add(a, Scale(Sub(b, a), t));
        cut[2] = kNearPlaneM;
        polygon[count++] = Project(cut);
      }
    }
    for (int k = 1; k + 1 < count; ++k)
      RasterTriangle(polygon[0], polygon[k], polygon[k + 1], face, cam.samples, visibility);
    return true;
  }
};

struct Barycentric {
  double b[3];
};

// The ray d's intersection with the triangle's plane, as barycentrics
// (d dotted with the edge-pair cross products; eye at the origin).
Barycentric RayBarycentric(const V3 corner_cross[3], const V3& d) {
  const double w0 = Dot(d, corner_cross[0]), w1 = Dot(d, corner_cross[1]), w2 = Dot(d, corner_cross[2]);
  const double sum = w0 + w1 + w2;
  if (!(sum != 0) || !std::isfinite(sum)) return {{1.0 / 3, 1.0 / 3, 1.0 / 3}};
  return {{w0 / sum, w1 / sum, w2 / sum}};
}

template <size_t N>
std::array<double, N> Interpolate(const std::vector<float>& values, const uint32_t* idx, size_t stride,
                                  const Barycentric& bc) {
  std::array<double, N> out{};
  for (int k = 0; k < 3; ++k) {
    const float* v = &values[size_t(idx[k]) * stride];
    for (size_t c = 0; c < N; ++c) out[c] += bc.b[k] * double(v[c]);
  }
  return out;
}

}  // namespace

float SrgbByteToLinear(uint8_t value) { return Srgb().decode[value]; }

uint8_t LinearToSrgbByte(double linear) {
  const auto& t = Srgb().thresholds;
  if (!(linear >= 0)) return 0;  // negative and NaN
  return uint8_t(std::upper_bound(t.begin(), t.end(), linear) - t.begin());
}

Expected<MipTexture> BuildColorTexture(const Image& image) {
  const std::array<float, 256>& srgb = Srgb().decode;
  if (image.type == Image::PixelType::kU16) {
    std::vector<float> table(65536);
    for (int i = 0; i < 65536; ++i) table[i] = float(SrgbDecodeExact(i / 65535.0));
    return BuildTexture(image, srgb, [&](const Image& im, size_t i) { return table[im.u16()[i]]; });
  }
  return BuildTexture(image, srgb, [](const Image& im, size_t i) { return im.f32()[i]; });
}

Expected<MipTexture> BuildNormalTexture(const Image& image) {
  std::array<float, 256> unit{};
  for (int i = 0; i < 256; ++i) {
    const int c = i - 128;
    unit[i] = c >= 0 ? float(c) / 127.0f : float(c) / 128.0f;
  }
  if (image.type == Image::PixelType::kU16) {
    return BuildTexture(image, unit, [](const Image& im, size_t i) {
      const int c = int(im.u16()[i]) - 32768;
      return c >= 0 ? float(c) / 32767.0f : float(c) / 32768.0f;
    });
  }
  return BuildTexture(image, unit, [](const Image& im, size_t i) { return im.f32()[i]; });
}

Expected<Image> RenderMesh(const Mesh& mesh, const RenderMaterial& material, const RenderCamera& camera,
                           const RenderOptions& options, RenderStats* stats, Image* depth_m) {
  PB_RETURN_IF_ERROR(Validate(mesh));
  if (material.color && !mesh.has_uvs())
    return Status::Invalid("render: a color map needs a mesh with uvs");
  if (material.normal && (!material.color || !mesh.has_tangents()))
    return Status::Invalid("render: a normal map needs a color map and a mesh with uvs and tangents");
  if ((material.color && material.color->levels.empty()) || (material.normal && material.normal->levels.empty()))
    return Status::Invalid("render: texture without levels");
  if (mesh.face_count() >= size_t(std::numeric_limits<uint32_t>::max()))
    return Status::Invalid("render: too many faces");
  PB_ASSIGN_OR_RETURN(const CameraFrame cam, MakeFrame(camera, mesh.origin, options));

  MeshRaster raster{mesh, cam, std::vector<V3>(mesh.vertex_count()), std::vector<ScreenVertex>(mesh.vertex_count())};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.vertex_count(), 4096), [&](const auto& range) {
    for (size_t i = range.begin(); i < range.end(); ++i) {
      const float* p = &mesh.positions[i * 3];
      const V3 rel = Sub({double(p[0]), double(p[1]), double(p[2])}, cam.eye);
      const V3 v = {Dot(rel, cam.right), Dot(rel, cam.up), Dot(rel, cam.forward)};
      raster.view[i] = v;
      if (v[2] >= kNearPlaneM) raster.screen[i] = raster.Project(v);
    }
  });

  const size_t sample_count = size_t(cam.samples) * size_t(cam.samples);
  std::vector<std::atomic<uint64_t>> visibility(sample_count);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, sample_count, 1 << 16), [&](const auto& range) {
    for (size_t i = range.begin(); i < range.end(); ++i) visibility[i].store(kEmpty, std::memory_order_relaxed);
  });
  std::atomic<size_t> clipped{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.face_count(), 2048), [&](const auto& range) {
    size_t clipped_here = 0;
    for (size_t f = range.begin(); f < range.end(); ++f)
      clipped_here += raster.DrawFace(uint32_t(f), visibility.data()) ? 1 : 0;
    clipped += clipped_here;
  });

  const SrgbTables& srgb = Srgb();
  const double gray = srgb.decode[kDefaultGray];
  const double pixel_step = double(cam.supersample) / cam.focal;  // one output pixel, in ray units
  auto shade = [&](int sx, int sy, V3& rgb) {
    const uint64_t key = visibility[size_t(sy) * cam.samples + sx].load(std::memory_order_relaxed);
    if (key == kEmpty) return SampleHit::kNone;
    const uint32_t face = uint32_t(key & 0xffffffffu);
    const uint32_t* idx = &mesh.indices[size_t(face) * 3];
    V3 q[3];
    for (int k = 0; k < 3; ++k) {
      const float* p = &mesh.positions[size_t(idx[k]) * 3];
      q[k] = Sub({double(p[0]), double(p[1]), double(p[2])}, cam.eye);
    }
    const V3 corner_cross[3] = {Cross(q[1], q[2]), Cross(q[2], q[0]), Cross(q[0], q[1])};
    const V3 d = cam.Ray(sx + 0.5, sy + 0.5);
    const Barycentric bc = RayBarycentric(corner_cross, d);
    const V3 geometric = Cross(Sub(q[1], q[0]), Sub(q[2], q[0]));
    const bool back = Dot(geometric, d) > 0;  // seen from the back
    const SampleHit hit = back ? SampleHit::kBack : SampleHit::kFront;

    std::array<double, 2> uv{};
    std::array<double, 2> duv_dx{}, duv_dy{};
    if (material.color) {
      uv = Interpolate<2>(mesh.uvs, idx, 2, bc);
      const auto uv_x = Interpolate<2>(mesh.uvs, idx, 2, RayBarycentric(corner_cross, Add(d, Scale(cam.right, pixel_step))));
      const auto uv_y = Interpolate<2>(mesh.uvs, idx, 2, RayBarycentric(corner_cross, Sub(d, Scale(cam.up, pixel_step))));
      duv_dx = {uv_x[0] - uv[0], uv_x[1] - uv[1]};
      duv_dy = {uv_y[0] - uv[0], uv_y[1] - uv[1]};
    }
    V3 albedo = {gray, gray, gray};
    if (material.color) {
      const auto c = SampleTrilinear(*material.color, uv, duv_dx, duv_dy);
      albedo = {c[0], c[1], c[2]};
    } else if (mesh.has_colors()) {
      albedo = {0, 0, 0};
      for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) albedo[c] += bc.b[k] * double(srgb.decode[mesh.colors[size_t(idx[k]) * 3 + c]]);
    }
    if (options.lighting == RenderLighting::kUnlit) {
      rgb = albedo;
      return hit;
    }
    V3 n = mesh.has_normals() ? Normalize(Interpolate<3>(mesh.normals, idx, 3, bc)) : V3{0, 0, 0};
    if (Dot(n, n) == 0) n = Normalize(geometric);
    V3 normal = n;
    if (material.normal) {
      const auto c = SampleTrilinear(*material.normal, uv, duv_dx, duv_dy);
      const std::array<double, 4> t4 = Interpolate<4>(mesh.tangents, idx, 4, bc);
      const V3 t = Normalize(Sub({t4[0], t4[1], t4[2]}, Scale(n, Dot(n, {t4[0], t4[1], t4[2]}))));
      const V3 b = Scale(Cross(n, t), t4[3] >= 0 ? 1.0 : -1.0);
      normal = Add(Add(Scale(t, c[0]), Scale(b, c[1])), Scale(n, c[2]));
    }
    normal = Normalize(normal);
    if (back) normal = Scale(normal, -1.0);
    for (int c = 0; c < 3; ++c) rgb[c] = Shade(options, cam, albedo[c], normal);
    return hit;
  };
  size_t covered = 0, back_samples = 0;
  Image image = Resolve(cam, camera.size, options, &covered, &back_samples, shade);
  if (depth_m) {
    // The visibility keys hold the float depth in their upper 32 bits.
    *depth_m = Image::Make(camera.size, camera.size, 1, Image::PixelType::kF32);
    const int ss = cam.supersample;
    tbb::parallel_for(tbb::blocked_range<int>(0, camera.size), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < camera.size; ++x) {
          float nearest = 0;
          for (int j = 0; j < ss; ++j)
            for (int i = 0; i < ss; ++i) {
              const uint64_t key =
                  visibility[size_t(y * ss + j) * cam.samples + size_t(x * ss + i)].load(std::memory_order_relaxed);
              if (key == kEmpty) continue;
              const float d = std::bit_cast<float>(uint32_t(key >> 32));
              if (nearest == 0 || d < nearest) nearest = d;
            }
          depth_m->f32()[size_t(y) * camera.size + x] = nearest;
        }
    });
  }
  if (stats) {
    stats->triangles = mesh.face_count();
    stats->clipped = clipped.load();
    stats->covered_samples = covered;
    stats->back_samples = back_samples;
  }
  return image;
}

Expected<Image> RenderSynthScene(const SynthScene& scene, const RenderCamera& camera, const RenderOptions& options,
                                 RenderStats* stats) {
  PB_ASSIGN_OR_RETURN(const CameraFrame cam, MakeFrame(camera, {0, 0, 0}, options));
  auto shade = [&](int sx, int sy, V3& rgb) {
    const V3 d = Normalize(cam.Ray(sx + 0.5, sy + 0.5));
    const std::optional<SynthHit> hit = Intersect(scene, cam.eye, d);
    if (!hit) return SampleHit::kNone;
    const std::array<double, 3> albedo = HitAlbedo(scene, *hit);
    V3 normal = Normalize(SampleSurface(scene, hit->point).normal);
    if (Dot(normal, d) > 0) normal = Scale(normal, -1.0);
    for (int c = 0; c < 3; ++c) rgb[c] = Shade(options, cam, SrgbDecodeExact(albedo[c]), normal);
    return SampleHit::kFront;  // the truth's surfaces have no sides
  };
  size_t covered = 0;
  Image image = Resolve(cam, camera.size, options, &covered, nullptr, shade);
  if (stats) {
    *stats = RenderStats{};
    stats->covered_samples = covered;
  }
  return image;
}

}  // namespace pb
