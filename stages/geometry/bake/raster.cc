#include "stages/geometry/bake/raster.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <string>

#include "stages/geometry/core/tangents.h"

namespace pb {
namespace {

constexpr uint32_t kEdgeBit = 0x80000000u;

using Vec2 = std::array<double, 2>;

// A face's UV triangle in texel space with edge functions that are >= 0
// inside whatever the winding. Degenerate when its area is (nearly) zero.
struct TexelTriangle {
  Vec2 p[3];
  double sign = 1;   // +1 or -1: orientation of p in texel space
  double area2 = 0;  // twice the signed area
  double min_x = 0, max_x = 0, min_y = 0, max_y = 0;  // bounding box
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // inclusive texel bounds, clipped

  bool degenerate() const { return x1 < x0 || y1 < y0; }

  // Edge function of edge i (p[i] -> p[i+1]) at q, scaled to be >= 0 inside.
  double Edge(int i, double qx, double qy) const {
    const Vec2& a = p[i];
    const Vec2& b = p[(i + 1) % 3];
    return sign * ((b[0] - a[0]) * (qy - a[1]) - (b[1] - a[1]) * (qx - a[0]));
  }
  // How far edge i's function may go below zero for a texel whose square
  // touches the edge line: the centre is at most half a texel away in each
  // axis.
  double EdgeSlack(int i) const {
    const Vec2& a = p[i];
    const Vec2& b = p[(i + 1) % 3];
    return 0.5 * (std::abs(b[0] - a[0]) + std::abs(b[1] - a[1]));
  }
};

TexelTriangle MakeTexelTriangle(const Mesh& mesh, uint32_t face, int size) {
  TexelTriangle tri;
  for (int k = 0; k < 3; ++k) {
    tri.p[k] = TexelPosition(mesh, mesh.indices[3 * size_t(face) + k], size);
  }
  tri.area2 = (tri.p[1][0] - tri.p[0][0]) * (tri.p[2][1] - tri.p[0][1]) -
              (tri.p[1][1] - tri.p[0][1]) * (tri.p[2][0] - tri.p[0][0]);
  // Relative to the triangle's extent: slivers below this have no usable
  // barycentric coordinates.
  double extent2 = 0;
  for (int k = 0; k < 3; ++k) {
    const Vec2& a = tri.p[k];
    const Vec2& b = tri.p[(k + 1) % 3];
    extent2 = std::max(extent2, (b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]));
  }
  if (!(std::abs(tri.area2) > 1e-12 * extent2) || !std::isfinite(tri.area2)) return tri;
  tri.sign = tri.area2 > 0 ? 1.0 : -1.0;
  tri.min_x = std::min({tri.p[0][0], tri.p[1][0], tri.p[2][0]});
  tri.max_x = std::max({tri.p[0][0], tri.p[1][0], tri.p[2][0]});
  tri.min_y = std::min({tri.p[0][1], tri.p[1][1], tri.p[2][1]});
  tri.max_y = std::max({tri.p[0][1], tri.p[1][1], tri.p[2][1]});
  // Every texel whose square could touch the triangle (Classify decides).
  tri.x0 = std::max(0, int(std::floor(tri.min_x)) - 1);
  tri.y0 = std::max(0, int(std::floor(tri.min_y)) - 1);
  tri.x1 = std::min(size - 1, int(std::floor(tri.max_x)) + 1);
  tri.y1 = std::min(size - 1, int(std::floor(tri.max_y)) + 1);
  return tri;
}

// 0: not touched, 1: centre inside, 2: conservative edge texel.
int Classify(const TexelTriangle& tri, int x, int y) {
  const double qx = x + 0.5, qy = y + 0.5;
  bool inside = true;
  for (int i = 0; i < 3; ++i) {
    const double e = tri.Edge(i, qx, qy);
    if (e < 0) {
      inside = false;
      if (e + tri.EdgeSlack(i) < 0) return 0;
    }
  }
  if (inside) return 1;
  // The edge slack test alone accepts texels past a sharp vertex; the square
  // must also overlap the triangle's bounding box (with the edges, the
  // separating axis test of a square and a triangle: exact).
  if (x + 1 < tri.min_x || x > tri.max_x || y + 1 < tri.min_y || y > tri.max_y) return 0;
  return 2;
}

// Barycentric coordinates of q in the triangle, clamped to >= 0 and
// renormalized.
std::array<float, 3> Barycentric(const TexelTriangle& tri, double qx, double qy) {
  // sign * Edge(i) is the raw signed double area of the edge and q, and the
  // edge opposite corner k is edge k + 1.
  const double b0 = std::max(0.0, tri.sign * tri.Edge(1, qx, qy) / tri.area2);
  const double b1 = std::max(0.0, tri.sign * tri.Edge(2, qx, qy) / tri.area2);
  const double b2 = std::max(0.0, tri.sign * tri.Edge(0, qx, qy) / tri.area2);
  const double sum = b0 + b1 + b2;
  if (!(sum > 0)) return {1.0f / 3, 1.0f / 3, 1.0f / 3};
  return {float(b0 / sum), float(b1 / sum), float(b2 / sum)};
}

// The point of the triangle nearest to q (Ericson, Real-Time Collision
// Detection, 5.1.5, in 2-D).
Vec2 ClosestPointOnTriangle(const TexelTriangle& tri, Vec2 q) {
  auto sub = [](Vec2 a, Vec2 b) { return Vec2{a[0] - b[0], a[1] - b[1]}; };
  auto dot = [](Vec2 a, Vec2 b) { return a[0] * b[0] + a[1] * b[1]; };
  const Vec2 a = tri.p[0], b = tri.p[1], c = tri.p[2];
  const Vec2 ab = sub(b, a), ac = sub(c, a), ap = sub(q, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec2 bp = sub(q, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {a[0] + v * ab[0], a[1] + v * ab[1]};
  }
  const Vec2 cp = sub(q, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {a[0] + w * ac[0], a[1] + w * ac[1]};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {b[0] + w * (c[0] - b[0]), b[1] + w * (c[1] - b[1])};
  }
  return q;  // inside (a texel the edge functions called outside by rounding)
}

int ArenaThreads(int threads) {
  return threads > 0 ? threads : tbb::this_task_arena::max_concurrency();
}

std::array<float, 3> Normalized(std::array<float, 3> v, std::array<float, 3> fallback) {
  const float length = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (!(length > 1e-20f) || !std::isfinite(length)) return fallback;
  return {v[0] / length, v[1] / length, v[2] / length};
}

std::array<float, 3> Cross(const std::array<float, 3>& a, const std::array<float, 3>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

float Dot(const std::array<float, 3>& a, const std::array<float, 3>& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

uint8_t EncodeUnit(float c) {
  const float clamped = std::clamp(c, -1.0f, 1.0f);
  return static_cast<uint8_t>(std::lround((clamped + 1.0f) * 127.5f));
}

float DecodeUnit(uint8_t c) { return float(c) / 127.5f - 1.0f; }

}  // namespace

Expected<BakeRaster> BakeRaster::Build(const Mesh& mesh, int size, int threads) {
  if (size < 1 || size > 32768) {
    return Status::Invalid("bake: texture size must be in [1, 32768], got " + std::to_string(size));
  }
  if (!mesh.has_uvs()) return Status::Invalid("bake: the mesh has no uvs (run uv.unwrap first)");
  PB_RETURN_IF_ERROR(Validate(mesh));
  if (mesh.face_count() >= kEdgeBit) {
    return Status::Invalid("bake: more than 2^31 faces");
  }
  BakeRaster raster;
  raster.size_ = size;
  raster.cells_.assign(size_t(size) * size_t(size), BakeRaster::kNoFace);
  uint32_t* cells = raster.cells_.data();
  tbb::task_arena arena(ArenaThreads(threads));
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.face_count(), 1024),
                      [&](const tbb::blocked_range<size_t>& range) {
      for (size_t face = range.begin(); face < range.end(); ++face) {
        const TexelTriangle tri = MakeTexelTriangle(mesh, uint32_t(face), size);
        if (tri.degenerate()) continue;
        for (int y = tri.y0; y <= tri.y1; ++y) {
          for (int x = tri.x0; x <= tri.x1; ++x) {
            const int kind = Classify(tri, x, y);
            if (kind == 0) continue;
            const uint32_t key = uint32_t(face) | (kind == 2 ? kEdgeBit : 0u);
            std::atomic_ref<uint32_t> cell(cells[size_t(y) * size_t(size) + size_t(x)]);
            uint32_t current = cell.load(std::memory_order_relaxed);
            while (key < current &&
                   !cell.compare_exchange_weak(current, key, std::memory_order_relaxed)) {
            }
          }
        }
      }
    });
  });
  for (const uint32_t cell : raster.cells_) {
    if (cell == kNoFace) continue;
    ++raster.covered_;
    if (cell & kEdgeBit) ++raster.edge_;
  }
  return raster;
}

uint32_t BakeRaster::owner(int x, int y) const {
  assert(x >= 0 && x < size_ && y >= 0 && y < size_);
  const uint32_t cell = cells_[size_t(y) * size_t(size_) + size_t(x)];
  return cell == kNoFace ? kNoFace : (cell & ~kEdgeBit);
}

bool BakeRaster::centre_inside(int x, int y) const {
  assert(x >= 0 && x < size_ && y >= 0 && y < size_);
  const uint32_t cell = cells_[size_t(y) * size_t(size_) + size_t(x)];
  return cell != kNoFace && !(cell & kEdgeBit);
}

void BakeRaster::TexelsOf(const Mesh& mesh, uint32_t face, std::vector<BakeTexel>& out) const {
  out.clear();
  const TexelTriangle tri = MakeTexelTriangle(mesh, face, size_);
  if (tri.degenerate()) return;
  for (int y = tri.y0; y <= tri.y1; ++y) {
    const uint32_t* row = cells_.data() + size_t(y) * size_t(size_);
    for (int x = tri.x0; x <= tri.x1; ++x) {
      const uint32_t cell = row[x];
      if ((cell & ~kEdgeBit) != face || cell == kNoFace) continue;
      Vec2 sample{x + 0.5, y + 0.5};
      if (cell & kEdgeBit) sample = ClosestPointOnTriangle(tri, sample);
      BakeTexel texel;
      texel.x = x;
      texel.y = y;
      texel.s = float(sample[0]);
      texel.t = float(sample[1]);
      texel.bary = Barycentric(tri, sample[0], sample[1]);
      out.push_back(texel);
    }
  }
}

void ForEachBakeFace(const Mesh& mesh, const BakeRaster& raster, int threads,
                     const std::function<void(uint32_t, std::span<const BakeTexel>)>& bake_face,
                     const std::function<void(double)>& progress) {
  const size_t faces = mesh.face_count();
  tbb::enumerable_thread_specific<std::vector<BakeTexel>> scratch;
  tbb::task_arena arena(ArenaThreads(threads));
  // Batches so that progress is reported from this thread between them.
  constexpr size_t kBatches = 64;
  const size_t batch = std::max<size_t>(1, (faces + kBatches - 1) / kBatches);
  for (size_t begin = 0; begin < faces; begin += batch) {
    const size_t end = std::min(faces, begin + batch);
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, 64),
                        [&](const tbb::blocked_range<size_t>& range) {
        std::vector<BakeTexel>& texels = scratch.local();
        for (size_t face = range.begin(); face < range.end(); ++face) {
          raster.TexelsOf(mesh, uint32_t(face), texels);
          if (!texels.empty()) bake_face(uint32_t(face), texels);
        }
      });
    });
    if (progress) progress(double(end) / double(faces));
  }
}

TexelFrame FrameAt(const Mesh& mesh, uint32_t face, const std::array<float, 3>& bary) {
  assert(mesh.has_normals() && mesh.has_tangents());
  TexelFrame frame;
  std::array<float, 3> normal{}, tangent{};
  float handedness = 0;
  for (int k = 0; k < 3; ++k) {
    const size_t v = mesh.indices[3 * size_t(face) + k];
    const float b = bary[k];
    for (int c = 0; c < 3; ++c) {
      frame.position[c] += b * mesh.positions[3 * v + c];
      normal[c] += b * mesh.normals[3 * v + c];
      tangent[c] += b * mesh.tangents[4 * v + c];
    }
    handedness += b * mesh.tangents[4 * v + 3];
  }
  frame.normal = Normalized(normal, {0, 0, 1});
  const float along = Dot(tangent, frame.normal);
  std::array<float, 3> projected{tangent[0] - along * frame.normal[0],
                                 tangent[1] - along * frame.normal[1],
                                 tangent[2] - along * frame.normal[2]};
  // As tangents.h: the coordinate axis least aligned with n when the
  // interpolated tangent is unusable.
  int axis = 0;
  for (int c = 1; c < 3; ++c) {
    if (std::abs(frame.normal[c]) < std::abs(frame.normal[axis])) axis = c;
  }
  std::array<float, 3> fallback{};
  fallback[axis] = 1;
  const float fallback_along = frame.normal[axis];
  fallback = Normalized({fallback[0] - fallback_along * frame.normal[0],
                         fallback[1] - fallback_along * frame.normal[1],
                         fallback[2] - fallback_along * frame.normal[2]},
                        {1, 0, 0});
  frame.tangent = Normalized(projected, fallback);
  const float w = handedness < 0 ? -1.0f : 1.0f;
  const std::array<float, 3> b = Cross(frame.normal, frame.tangent);
  frame.bitangent = {w * b[0], w * b[1], w * b[2]};
  return frame;
}

std::array<float, 3> ToTangentSpace(const TexelFrame& frame, const std::array<float, 3>& world) {
  return Normalized({Dot(world, frame.tangent), Dot(world, frame.bitangent), Dot(world, frame.normal)},
                    {0, 0, 1});
}

Expected<Mesh> PrepareBakeMesh(Mesh mesh) {
  PB_RETURN_IF_ERROR(Validate(mesh));
  if (!mesh.has_uvs()) return Status::Invalid("bake: the mesh has no uvs (run uv.unwrap first)");
  if (!mesh.has_normals()) mesh.normals = ComputeVertexNormals(mesh);
  PB_ASSIGN_OR_RETURN(mesh.tangents, ComputeTangents(mesh));
  return mesh;
}

BakeMaps BakeMaps::Make(int size, bool float_normals) {
  BakeMaps maps;
  maps.color = Image::Make(size, size, 3, Image::PixelType::kU8);
  if (float_normals) {
    maps.normal = Image::Make(size, size, 3, Image::PixelType::kF32);
    float* n = maps.normal.f32();
    for (size_t i = 0; i < maps.normal.sample_count(); i += 3) n[i + 2] = 1.0f;
  } else {
    maps.normal = Image::Make(size, size, 3, Image::PixelType::kU8);
    uint8_t* n = maps.normal.u8();
    for (size_t i = 0; i < maps.normal.sample_count(); i += 3) {
      n[i] = EncodeUnit(0);
      n[i + 1] = EncodeUnit(0);
      n[i + 2] = EncodeUnit(1);
    }
  }
  return maps;
}

void BakeMaps::SetColor(int x, int y, const std::array<float, 3>& srgb) {
  for (int c = 0; c < 3; ++c) {
    const float v = std::isfinite(srgb[c]) ? std::clamp(srgb[c], 0.0f, 255.0f) : 0.0f;
    color.at_u8(x, y, c) = static_cast<uint8_t>(std::lround(v));
  }
}

void BakeMaps::SetNormal(int x, int y, const std::array<float, 3>& tangent_space) {
  for (int c = 0; c < 3; ++c) {
    const float v = std::isfinite(tangent_space[c]) ? std::clamp(tangent_space[c], -1.0f, 1.0f)
                                                    : (c == 2 ? 1.0f : 0.0f);
    if (normal.type == Image::PixelType::kF32) {
      normal.at_f32(x, y, c) = v;
    } else {
      normal.at_u8(x, y, c) = EncodeUnit(v);
    }
  }
}

size_t DilateBakeMaps(BakeMaps& maps, const BakeRaster& raster, int passes, int threads) {
  const int size = raster.size();
  assert(maps.color.width == size && maps.normal.width == size);
  std::vector<uint8_t> filled(size_t(size) * size_t(size));
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) filled[size_t(y) * size + x] = raster.owner(x, y) != BakeRaster::kNoFace;
  }
  struct NewTexel {
    int x;
    std::array<float, 3> color;
    std::array<float, 3> normal;
  };
  const bool float_normals = maps.normal.type == Image::PixelType::kF32;
  auto normal_at = [&](int x, int y) -> std::array<float, 3> {
    if (float_normals) return {maps.normal.at_f32(x, y, 0), maps.normal.at_f32(x, y, 1), maps.normal.at_f32(x, y, 2)};
    return {DecodeUnit(maps.normal.at_u8(x, y, 0)), DecodeUnit(maps.normal.at_u8(x, y, 1)),
            DecodeUnit(maps.normal.at_u8(x, y, 2))};
  };
  size_t total = 0;
  std::vector<std::vector<NewTexel>> rows(size);
  tbb::task_arena arena(ArenaThreads(threads));
  for (int pass = 0; pass < passes; ++pass) {
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<int>(0, size, 16), [&](const tbb::blocked_range<int>& range) {
        for (int y = range.begin(); y < range.end(); ++y) {
          std::vector<NewTexel>& row = rows[y];
          row.clear();
          for (int x = 0; x < size; ++x) {
            if (filled[size_t(y) * size + x]) continue;
            int count = 0;
            std::array<float, 3> color{}, normal{};
            for (int dy = -1; dy <= 1; ++dy) {
              const int ny = y + dy;
              if (ny < 0 || ny >= size) continue;
              for (int dx = -1; dx <= 1; ++dx) {
                const int nx = x + dx;
                if ((dx == 0 && dy == 0) || nx < 0 || nx >= size) continue;
                if (!filled[size_t(ny) * size + nx]) continue;
                ++count;
                const std::array<float, 3> n = normal_at(nx, ny);
                for (int c = 0; c < 3; ++c) {
                  color[c] += maps.color.at_u8(nx, ny, c);
                  normal[c] += n[c];
                }
              }
            }
            if (count == 0) continue;
            for (int c = 0; c < 3; ++c) color[c] /= float(count);
            row.push_back({x, color, Normalized(normal, {0, 0, 1})});
          }
        }
      });
    });
    size_t added = 0;
    for (int y = 0; y < size; ++y) {
      for (const NewTexel& texel : rows[y]) {
        maps.SetColor(texel.x, y, texel.color);
        maps.SetNormal(texel.x, y, texel.normal);
        filled[size_t(y) * size + texel.x] = 1;
      }
      added += rows[y].size();
    }
    total += added;
    if (added == 0) break;
  }
  return total;
}

}  // namespace pb
