// Meshes for tests and benchmarks (test-only: no production code includes
// stages/geometry/testing/): an icosphere, a uv-mapped grid and a height
// field sheet, all generated, no files.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <utility>
#include <vector>

#include "stages/geometry/core/mesh.h"

namespace pb::testing {

// Unit icosphere: icosahedron subdivided `levels` times (20 * 4^levels
// faces), outward-facing, with normals and a red channel by height z.
inline Mesh Icosphere(int levels) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<std::array<double, 3>> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                          {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                          {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<uint32_t> f = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                             4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
                             6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
  auto normalize = [](std::array<double, 3> p) {
    const double l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return std::array<double, 3>{p[0] / l, p[1] / l, p[2] / l};
  };
  for (auto& p : v) p = normalize(p);
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
    auto mid = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      v.push_back(normalize({v[a][0] + v[b][0], v[a][1] + v[b][1], v[a][2] + v[b][2]}));
      const uint32_t id = static_cast<uint32_t>(v.size() - 1);
      midpoints.emplace(key, id);
      return id;
    };
    std::vector<uint32_t> next;
    next.reserve(4 * f.size());
    for (size_t i = 0; i < f.size(); i += 3) {
      const uint32_t a = f[i], b = f[i + 1], c = f[i + 2];
      const uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    f = std::move(next);
  }
  Mesh mesh;
  for (const auto& p : v) {
    for (int k = 0; k < 3; ++k) {
      mesh.positions.push_back(static_cast<float>(p[k]));
      mesh.normals.push_back(static_cast<float>(p[k]));
    }
    mesh.colors.insert(mesh.colors.end(),
                       {static_cast<uint8_t>(std::lround(127.5 * (p[2] + 1))), 100, 0});
  }
  mesh.indices = std::move(f);
  return mesh;
}

// The unit square [0,1]^2 at z = 0 as n x n quads (2 triangles each), uvs =
// (x, y): the atlas is covered, texel (x, y) of a size-S map has its centre
// at u = (x + 0.5) / S, v = 1 - (y + 0.5) / S, i.e. at that point in space.
inline Mesh LowGrid(int n) {
  Mesh mesh;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const float x = float(i) / float(n), y = float(j) / float(n);
      mesh.positions.insert(mesh.positions.end(), {x, y, 0.0f});
      mesh.uvs.insert(mesh.uvs.end(), {x, y});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
    }
  }
  return mesh;
}

// A sheet over [x0,x1] x [y0,y1] as n x n quads, counter-clockwise seen from
// +z, at height z(x, y), every vertex colored color(x, y). No normals.
inline Mesh Sheet(double x0, double x1, double y0, double y1, int n,
           const std::function<double(double, double)>& z,
           const std::function<std::array<uint8_t, 3>(double, double)>& color) {
  Mesh mesh;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const double x = x0 + (x1 - x0) * i / n, y = y0 + (y1 - y0) * j / n;
      mesh.positions.insert(mesh.positions.end(), {float(x), float(y), float(z(x, y))});
      const auto c = color(x, y);
      mesh.colors.insert(mesh.colors.end(), c.begin(), c.end());
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
    }
  }
  return mesh;
}

}  // namespace pb::testing
