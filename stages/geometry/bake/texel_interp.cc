// Per-face texel interpolation of the point-based detail transfer.
//
// Source: "Point-based detail transfer", Detail Transfer Algorithm, lines
// 11-17 of the pseudo-code: triangulate the face's vertices plus the points
// mapped into it, and give every pixel of the face the linear interpolation
// inside the triangle of that triangulation that contains it. The authors'
// code used a 2-D CGAL Delaunay triangulation; so does kDelaunay.
// Departures, all documented in docs/bake-interpolation.md:
//   - samples at the same position (points on a corner, duplicate points)
//     become one vertex whose color and normal are their mean (CGAL would
//     keep one of them, which one depending on the insertion order);
//   - a texel whose sample point falls outside the triangulation by rounding
//     takes the clamped barycentric interpolation of the nearest hull face;
//   - a face whose UV corners are collinear has no 2-D triangulation: it
//     takes the nearest sample's value;
//   - normals are re-normalized; a zero interpolated normal takes the
//     corners' interpolated normal, then (0, 0, 1);
//   - with corner_samples false (bake.from_points' `neighbors`, whose
//     samples then include the neighbouring faces' points) the corners are
//     left out unless the points are fewer than three or on one line.
// kNearest, kIdw and kSplat are the campaign's alternatives; kSplat fills
// the texels no footprint covers by pull-push (Gortler et al. 1996, "The
// Lumigraph", sec. 3.3; Grossman & Dally 1998, "Point Sample Rendering").
//
// This is the only file that includes CGAL (pb_texel_interp): it uses the
// plain structs of texel_interp.h / bake_raster.h and nothing else of
// pb_geometry.
#include "stages/geometry/bake/texel_interp.h"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>

namespace pb {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<uint32_t, Kernel>;
using FaceBase = CGAL::Triangulation_face_base_2<Kernel>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
using Delaunay = CGAL::Delaunay_triangulation_2<Kernel, Tds>;
using Point = Kernel::Point_2;

// A sample's color and normal as one 6-vector: rgb, xyz.
using Value = std::array<double, 6>;
using Position = std::array<float, 2>;

Value ValueOf(const TexelSample& sample) {
  return {sample.color[0],  sample.color[1],  sample.color[2],
          sample.normal[0], sample.normal[1], sample.normal[2]};
}

bool Finite(const TexelSample& sample) {
  return std::isfinite(sample.s) && std::isfinite(sample.t);
}

struct Neighbor {
  double d2;  // squared distance, texels^2
  uint32_t index;
};

bool Closer(const Neighbor& a, const Neighbor& b) {
  return a.d2 < b.d2 || (a.d2 == b.d2 && a.index < b.index);
}

// A uniform bucket grid over 2-D positions (texel space) for nearest and
// radius queries, about `items_per_cell` items per cell and at most 1024
// cells a side. Items of a cell are in ascending index order.
class BucketGrid {
 public:
  void Build(std::span<const Position> positions, double items_per_cell) {
    assert(!positions.empty());
    double s_min = positions[0][0], s_max = s_min, t_min = positions[0][1], t_max = t_min;
    for (const Position& p : positions) {
      s_min = std::min<double>(s_min, p[0]), s_max = std::max<double>(s_max, p[0]);
      t_min = std::min<double>(t_min, p[1]), t_max = std::max<double>(t_max, p[1]);
    }
    double width = s_max - s_min, height = t_max - t_min, extent = std::max(width, height);
    double cells = std::max(1.0, double(positions.size()) / items_per_cell);
    cell_ = std::max({std::sqrt(width * height / cells), extent / std::min(cells, 1024.0), 1e-4});
    inv_cell_ = 1 / cell_;
    s0_ = s_min, t0_ = t_min;
    w_ = std::min(1024, int(width * inv_cell_) + 1);
    h_ = std::min(1024, int(height * inv_cell_) + 1);
    start_.assign(size_t(w_) * h_ + 1, 0);
    cell_of_.resize(positions.size());
    for (size_t i = 0; i < positions.size(); ++i) {
      cell_of_[i] = uint32_t(CellY(positions[i][1]) * w_ + CellX(positions[i][0]));
      ++start_[cell_of_[i] + 1];
    }
    for (size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    items_.resize(positions.size());
    fill_ = start_;
    for (size_t i = 0; i < positions.size(); ++i) items_[fill_[cell_of_[i]]++] = uint32_t(i);
  }

  // The k nearest items to q in `out`, sorted by (distance, index): ties go
  // to the lower index.
  void Nearest(std::span<const Position> positions, double qs, double qt, size_t k,
               std::vector<Neighbor>& out) const {
    out.clear();
    int cx = CellX(qs), cy = CellY(qt);
    int max_ring = std::max({cx, w_ - 1 - cx, cy, h_ - 1 - cy});
    auto visit = [&](int x, int y) {
      uint32_t cell = uint32_t(y * w_ + x);
      for (uint32_t j = start_[cell]; j < start_[cell + 1]; ++j) {
        uint32_t i = items_[j];
        double ds = positions[i][0] - qs, dt = positions[i][1] - qt;
        Neighbor candidate{ds * ds + dt * dt, i};
        if (out.size() < k) {
          out.push_back(candidate);
        } else if (Closer(candidate, out.back())) {
          out.back() = candidate;
        } else {
          continue;
        }
        for (size_t m = out.size() - 1; m > 0 && Closer(out[m], out[m - 1]); --m) {
          std::swap(out[m], out[m - 1]);
        }
      }
    };
    for (int r = 0; r <= max_ring; ++r) {
      // Items r rings away are at least (r - 1) cells from q; the margin
      // absorbs rounding in the cell assignment.
      double bound = (r - 1) * cell_ * (1 - 1e-6);
      if (out.size() == k && r >= 2 && out.back().d2 < bound * bound) break;
      int x0 = std::max(cx - r, 0), x1 = std::min(cx + r, w_ - 1);
      int y0 = std::max(cy - r, 0), y1 = std::min(cy + r, h_ - 1);
      if (cy - r >= 0) for (int x = x0; x <= x1; ++x) visit(x, cy - r);
      if (r > 0 && cy + r < h_) for (int x = x0; x <= x1; ++x) visit(x, cy + r);
      for (int y = std::max(cy - r + 1, y0); y <= std::min(cy + r - 1, y1); ++y) {
        if (r > 0 && cx - r >= 0) visit(cx - r, y);
        if (r > 0 && cx + r < w_) visit(cx + r, y);
      }
    }
  }

  // Calls f(index, squared distance) for every item within `radius` of q.
  template <class F>
  void ForEachWithin(std::span<const Position> positions, double qs, double qt, double radius,
                     F&& f) const {
    double r2 = radius * radius;
    int x0 = CellX(qs - radius), x1 = CellX(qs + radius);
    int y0 = CellY(qt - radius), y1 = CellY(qt + radius);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        uint32_t cell = uint32_t(y * w_ + x);
        for (uint32_t j = start_[cell]; j < start_[cell + 1]; ++j) {
          uint32_t i = items_[j];
          double ds = positions[i][0] - qs, dt = positions[i][1] - qt;
          double d2 = ds * ds + dt * dt;
          if (d2 <= r2) f(i, d2);
        }
      }
    }
  }

 private:
  int CellX(double s) const { return Clamp((s - s0_) * inv_cell_, w_); }
  int CellY(double t) const { return Clamp((t - t0_) * inv_cell_, h_); }
  static int Clamp(double c, int n) {
    return c <= 0 ? 0 : c >= n - 1 ? n - 1 : int(c);
  }

  double s0_ = 0, t0_ = 0, cell_ = 1, inv_cell_ = 1;
  int w_ = 1, h_ = 1;
  std::vector<uint32_t> start_, fill_, items_, cell_of_;
};

// Pull-push fill (Gortler et al. 1996, sec. 3.3) on a texel grid: cells
// with samples keep their mean, empty ones take the bilinearly upsampled
// coarser level. One level-0 cell per 2^shift texels a side; the shift
// grows only for faces whose texel bounding box is much larger than their
// texel count (long diagonal slivers), to bound memory.
class PullPush {
 public:
  void Reset(int x_min, int y_min, int x_max, int y_max, size_t texel_count) {
    x_min_ = x_min, y_min_ = y_min, shift_ = 0;
    const double max_cells = 16.0 * double(texel_count) + 4096;
    auto cells = [&](int shift) {
      return double(((x_max - x_min) >> shift) + 1) * double(((y_max - y_min) >> shift) + 1);
    };
    while (cells(shift_) > max_cells) ++shift_;
    int w = ((x_max - x_min) >> shift_) + 1, h = ((y_max - y_min) >> shift_) + 1;
    levels_used_ = 0;
    for (;;) {
      if (levels_.size() <= levels_used_) levels_.emplace_back();
      Level& level = levels_[levels_used_++];
      level.w = w, level.h = h;
      level.values.assign(size_t(w) * h, Value{});
      level.weights.assign(size_t(w) * h, 0.0);
      if (w == 1 && h == 1) break;
      w = (w + 1) / 2, h = (h + 1) / 2;
    }
  }

  // A sample of weight 1 at texel (x, y), clamped into the grid.
  void Add(double x, double y, const Value& value) {
    Level& level = levels_[0];
    int cx = CellOf(x, x_min_, level.w), cy = CellOf(y, y_min_, level.h);
    size_t c = size_t(cy) * level.w + cx;
    for (int k = 0; k < 6; ++k) level.values[c][k] += value[k];
    level.weights[c] += 1;
  }

  void Solve() {
    Level& base = levels_[0];
    for (size_t c = 0; c < base.values.size(); ++c) {
      if (base.weights[c] > 0) {
        for (double& v : base.values[c]) v /= base.weights[c];
        base.weights[c] = std::min(1.0, base.weights[c]);
      }
    }
    for (size_t l = 1; l < levels_used_; ++l) {  // pull
      const Level& fine = levels_[l - 1];
      Level& coarse = levels_[l];
      for (int y = 0; y < coarse.h; ++y) {
        for (int x = 0; x < coarse.w; ++x) {
          Value sum{};
          double weight = 0;
          for (int fy = 2 * y; fy < std::min(2 * y + 2, fine.h); ++fy) {
            for (int fx = 2 * x; fx < std::min(2 * x + 2, fine.w); ++fx) {
              size_t f = size_t(fy) * fine.w + fx;
              weight += fine.weights[f];
              for (int k = 0; k < 6; ++k) sum[k] += fine.weights[f] * fine.values[f][k];
            }
          }
          size_t c = size_t(y) * coarse.w + x;
          if (weight > 0) {
            for (int k = 0; k < 6; ++k) coarse.values[c][k] = sum[k] / weight;
          }
          coarse.weights[c] = std::min(1.0, weight);
        }
      }
    }
    for (size_t l = levels_used_ - 1; l-- > 0;) {  // push
      Level& fine = levels_[l];
      const Level& coarse = levels_[l + 1];
      for (int y = 0; y < fine.h; ++y) {
        for (int x = 0; x < fine.w; ++x) {
          size_t c = size_t(y) * fine.w + x;
          double w = fine.weights[c];
          if (w >= 1) continue;
          Value up = Bilinear(coarse, 0.5 * x - 0.25, 0.5 * y - 0.25);
          for (int k = 0; k < 6; ++k) fine.values[c][k] = w * fine.values[c][k] + (1 - w) * up[k];
        }
      }
    }
  }

  const Value& At(int x, int y) const {
    const Level& level = levels_[0];
    return level.values[size_t(CellOf(y, y_min_, level.h)) * level.w + CellOf(x, x_min_, level.w)];
  }

 private:
  struct Level {
    int w = 0, h = 0;
    std::vector<Value> values;
    std::vector<double> weights;
  };

  int CellOf(double texel, int origin, int n) const {
    double c = std::floor((std::floor(texel) - origin) / double(1 << shift_));
    return c <= 0 ? 0 : c >= n - 1 ? n - 1 : int(c);
  }

  static Value Bilinear(const Level& level, double x, double y) {
    x = std::clamp(x, 0.0, double(level.w - 1)), y = std::clamp(y, 0.0, double(level.h - 1));
    int x0 = int(x), y0 = int(y);
    int x1 = std::min(x0 + 1, level.w - 1), y1 = std::min(y0 + 1, level.h - 1);
    double ax = x - x0, ay = y - y0;
    const Value& a = level.values[size_t(y0) * level.w + x0];
    const Value& b = level.values[size_t(y0) * level.w + x1];
    const Value& c = level.values[size_t(y1) * level.w + x0];
    const Value& d = level.values[size_t(y1) * level.w + x1];
    Value v;
    for (int k = 0; k < 6; ++k) {
      v[k] = (1 - ay) * ((1 - ax) * a[k] + ax * b[k]) + ay * ((1 - ax) * c[k] + ax * d[k]);
    }
    return v;
  }

  int x_min_ = 0, y_min_ = 0, shift_ = 0;
  std::vector<Level> levels_;
  size_t levels_used_ = 0;
};

// Everything kept between faces.
struct InterpScratch {
  // Samples: the three corners (indices 0-2), then the finite points in the
  // order given; the interpolation uses those from `first` on (3: the
  // corners are left out, TexelInterpolationOptions::corner_samples).
  std::vector<Position> positions;
  size_t first = 0;
  std::vector<Value> values;
  std::vector<Value> texel_values;  // per texel, before normalization

  // kDelaunay.
  Delaunay triangulation;
  std::vector<Point> points;
  std::vector<std::pair<uint32_t, uint32_t>> order;  // (Morton code, sample)
  std::vector<Value> vertex_values;  // per triangulation vertex (its info)
  std::vector<uint32_t> vertex_counts;

  // kNearest, kIdw, kSplat.
  BucketGrid grid;
  std::vector<Neighbor> neighbors;
  std::vector<Position> texel_positions;
  std::vector<double> texel_weights;
  PullPush pull_push;
};

Value CornerBlend(const std::array<TexelSample, 3>& corners, const std::array<float, 3>& bary) {
  Value v;
  for (int k = 0; k < 6; ++k) {
    auto at = [&](int c) { return double(k < 3 ? corners[c].color[k] : corners[c].normal[k - 3]); };
    v[k] = double(bary[0]) * at(0) + double(bary[1]) * at(1) + double(bary[2]) * at(2);
  }
  return v;
}

void WriteOut(const Value& v, const Value& corner_blend, std::array<float, 3>& color,
              std::array<float, 3>& normal) {
  color = {float(v[0]), float(v[1]), float(v[2])};
  for (const Value* source : {&v, &corner_blend}) {
    const Value& n = *source;
    double length = std::sqrt(n[3] * n[3] + n[4] * n[4] + n[5] * n[5]);
    if (length > 1e-12 && std::isfinite(length)) {
      normal = {float(n[3] / length), float(n[4] / length), float(n[5] / length)};
      return;
    }
  }
  normal = {0, 0, 1};
}

void InterpolateNearest(InterpScratch& s, std::span<const BakeTexel> texels) {
  const std::span<const Position> used = std::span<const Position>(s.positions).subspan(s.first);
  s.grid.Build(used, 2);
  for (size_t i = 0; i < texels.size(); ++i) {
    s.grid.Nearest(used, texels[i].s, texels[i].t, 1, s.neighbors);
    s.texel_values[i] = s.values[s.first + s.neighbors[0].index];
  }
}

void InterpolateIdw(InterpScratch& s, std::span<const BakeTexel> texels,
                    const TexelInterpolationOptions& options) {
  const std::span<const Position> used = std::span<const Position>(s.positions).subspan(s.first);
  size_t k = size_t(std::clamp<int>(options.idw_neighbors, 1, int(used.size())));
  double power = std::isfinite(options.idw_power) ? std::max(0.0f, options.idw_power) : 2.0;
  s.grid.Build(used, 2);
  for (size_t i = 0; i < texels.size(); ++i) {
    s.grid.Nearest(used, texels[i].s, texels[i].t, k, s.neighbors);
    if (s.neighbors[0].d2 == 0) {
      s.texel_values[i] = s.values[s.first + s.neighbors[0].index];
      continue;
    }
    Value sum{};
    double weight_sum = 0;
    for (const Neighbor& n : s.neighbors) {
      double w = power == 2 ? 1 / n.d2 : std::pow(n.d2, -0.5 * power);
      weight_sum += w;
      for (int c = 0; c < 6; ++c) sum[c] += w * s.values[s.first + n.index][c];
    }
    for (int c = 0; c < 6; ++c) s.texel_values[i][c] = sum[c] / weight_sum;
  }
}

void InterpolateSplat(InterpScratch& s, std::span<const BakeTexel> texels,
                      const TexelInterpolationOptions& options) {
  double sigma = std::isfinite(options.splat_sigma_texels)
                     ? std::clamp<double>(options.splat_sigma_texels, 1e-3, 1e4)
                     : 1.0;
  double radius = 2 * sigma, inv_two_sigma2 = 1 / (2 * sigma * sigma);
  s.texel_positions.clear();
  for (const BakeTexel& texel : texels) s.texel_positions.push_back({texel.s, texel.t});
  s.grid.Build(s.texel_positions, 2);
  std::fill(s.texel_values.begin(), s.texel_values.end(), Value{});
  s.texel_weights.assign(texels.size(), 0.0);
  for (size_t p = 3; p < s.positions.size(); ++p) {
    const Value& value = s.values[p];
    s.grid.ForEachWithin(s.texel_positions, s.positions[p][0], s.positions[p][1], radius,
                         [&](uint32_t i, double d2) {
                           double w = std::exp(float(-d2 * inv_two_sigma2));
                           s.texel_weights[i] += w;
                           for (int c = 0; c < 6; ++c) s.texel_values[i][c] += w * value[c];
                         });
  }
  bool any_empty = false;
  int x_min = texels[0].x, x_max = x_min, y_min = texels[0].y, y_max = y_min;
  for (size_t i = 0; i < texels.size(); ++i) {
    x_min = std::min(x_min, texels[i].x), x_max = std::max(x_max, texels[i].x);
    y_min = std::min(y_min, texels[i].y), y_max = std::max(y_max, texels[i].y);
    if (s.texel_weights[i] > 0) {
      for (double& v : s.texel_values[i]) v /= s.texel_weights[i];
    } else {
      any_empty = true;
    }
  }
  if (!any_empty) return;
  s.pull_push.Reset(x_min, y_min, x_max, y_max, texels.size());
  for (size_t i = 0; i < texels.size(); ++i) {
    if (s.texel_weights[i] > 0) s.pull_push.Add(texels[i].x, texels[i].y, s.texel_values[i]);
  }
  for (size_t c = s.first; c < 3; ++c) s.pull_push.Add(s.positions[c][0], s.positions[c][1], s.values[c]);
  s.pull_push.Solve();
  for (size_t i = 0; i < texels.size(); ++i) {
    if (s.texel_weights[i] == 0) s.texel_values[i] = s.pull_push.At(texels[i].x, texels[i].y);
  }
}

// The samples from `first` on in Z (Morton) order of their positions
// quantized to 16 bits over their bounding box, ties by index: a spatial
// sort for the insertion. CGAL's spatial_sort (a Hilbert median sort after
// a shuffle) measured 10% slower per face for ~120 points.
void MortonOrder(std::span<const Position> positions, size_t first,
                 std::vector<std::pair<uint32_t, uint32_t>>& order) {
  order.clear();
  if (positions.size() <= first) return;
  float s_min = positions[first][0], s_max = s_min, t_min = positions[first][1], t_max = t_min;
  for (size_t i = first; i < positions.size(); ++i) {
    s_min = std::min(s_min, positions[i][0]), s_max = std::max(s_max, positions[i][0]);
    t_min = std::min(t_min, positions[i][1]), t_max = std::max(t_max, positions[i][1]);
  }
  double scale = 65535.0 / std::max({double(s_max) - s_min, double(t_max) - t_min, 1e-30});
  auto spread = [](uint32_t x) {  // bit i to bit 2i
    x = (x | (x << 8)) & 0x00ff00ffu;
    x = (x | (x << 4)) & 0x0f0f0f0fu;
    x = (x | (x << 2)) & 0x33333333u;
    return (x | (x << 1)) & 0x55555555u;
  };
  for (size_t i = first; i < positions.size(); ++i) {
    auto qs = uint32_t(std::min(65535.0, (double(positions[i][0]) - s_min) * scale));
    auto qt = uint32_t(std::min(65535.0, (double(positions[i][1]) - t_min) * scale));
    order.push_back({spread(qs) | (spread(qt) << 1), uint32_t(i)});
  }
  std::sort(order.begin(), order.end());
}

// Linear interpolation in the finite triangle `face` at q; barycentric
// coordinates clamped to >= 0 for a query that rounding put outside it.
Value InterpolateInFace(const Delaunay::Face_handle& face, const Point& q,
                        const std::vector<Value>& vertex_values) {
  const Point& p0 = face->vertex(0)->point();
  const Point& p1 = face->vertex(1)->point();
  const Point& p2 = face->vertex(2)->point();
  double x0 = p0.x(), y0 = p0.y(), x1 = p1.x(), y1 = p1.y(), x2 = p2.x(), y2 = p2.y();
  double det = (y1 - y2) * (x0 - x2) + (x2 - x1) * (y0 - y2);
  double w0 = ((y1 - y2) * (q.x() - x2) + (x2 - x1) * (q.y() - y2)) / det;
  double w1 = ((y2 - y0) * (q.x() - x2) + (x0 - x2) * (q.y() - y2)) / det;
  double w2 = 1 - w0 - w1;
  if (!(w0 >= 0 && w1 >= 0 && w2 >= 0)) {
    w0 = std::max(w0, 0.0), w1 = std::max(w1, 0.0), w2 = std::max(w2, 0.0);
    double sum = w0 + w1 + w2;
    if (sum > 0 && std::isfinite(sum)) {
      w0 /= sum, w1 /= sum, w2 /= sum;
    } else {
      w0 = w1 = w2 = 1.0 / 3;
    }
  }
  const Value& a = vertex_values[face->vertex(0)->info()];
  const Value& b = vertex_values[face->vertex(1)->info()];
  const Value& c = vertex_values[face->vertex(2)->info()];
  Value v;
  for (int k = 0; k < 6; ++k) v[k] = w0 * a[k] + w1 * b[k] + w2 * c[k];
  return v;
}

void InterpolateDelaunay(InterpScratch& s, std::span<const BakeTexel> texels) {
  Delaunay& dt = s.triangulation;
  s.points.clear();
  for (const Position& p : s.positions) s.points.emplace_back(p[0], p[1]);
  const bool corners_collinear =
      CGAL::orientation(s.points[0], s.points[1], s.points[2]) == CGAL::COLLINEAR;
  if (corners_collinear && s.first == 0) {
    InterpolateNearest(s, texels);
    return;
  }

  // Corners first (unless left out), so the hull is the face from the
  // start, then the points in Morton order, so that each insertion starts
  // its walk next to the previous one; a sample that lands on an existing
  // vertex is averaged into it.
  dt.clear();
  s.vertex_values.clear();
  s.vertex_counts.clear();
  MortonOrder(s.positions, 3, s.order);
  Delaunay::Face_handle hint;
  auto insert = [&](size_t i) {
    size_t before = dt.number_of_vertices();
    Delaunay::Vertex_handle v = dt.insert(s.points[i], hint);
    if (dt.number_of_vertices() == before) {
      Value& sum = s.vertex_values[v->info()];
      for (int k = 0; k < 6; ++k) sum[k] += s.values[i][k];
      ++s.vertex_counts[v->info()];
    } else {
      v->info() = uint32_t(s.vertex_values.size());
      s.vertex_values.push_back(s.values[i]);
      s.vertex_counts.push_back(1);
    }
    hint = v->face();
  };
  for (size_t i = s.first; i < 3; ++i) insert(i);
  for (const auto& [code, i] : s.order) insert(i);
  if (dt.dimension() < 2) {
    // The points without the corners lie on one line: the corners join
    // them, as they would have by default.
    if (corners_collinear) {
      InterpolateNearest(s, texels);
      return;
    }
    hint = Delaunay::Face_handle();
    for (size_t i = 0; i < 3; ++i) insert(i);
  }
  for (size_t v = 0; v < s.vertex_values.size(); ++v) {
    if (s.vertex_counts[v] == 1) continue;
    for (double& x : s.vertex_values[v]) x /= s.vertex_counts[v];
  }

  for (size_t i = 0; i < texels.size(); ++i) {
    Point q(texels[i].s, texels[i].t);
    Delaunay::Locate_type type;
    int li = 0;
    Delaunay::Face_handle face = dt.locate(q, type, li, hint);
    if (type == Delaunay::VERTEX) {
      s.texel_values[i] = s.vertex_values[face->vertex(li)->info()];
    } else {
      // On a hull edge, or outside the hull by rounding: the finite face
      // across the infinite face's finite edge.
      if (dt.is_infinite(face)) face = face->neighbor(face->index(dt.infinite_vertex()));
      s.texel_values[i] = InterpolateInFace(face, q, s.vertex_values);
    }
    hint = face;
  }
}

}  // namespace

struct FaceInterpolator::Scratch : InterpScratch {};

FaceInterpolator::FaceInterpolator() : scratch_(std::make_unique<Scratch>()) {}
FaceInterpolator::~FaceInterpolator() = default;
FaceInterpolator::FaceInterpolator(FaceInterpolator&&) noexcept = default;
FaceInterpolator& FaceInterpolator::operator=(FaceInterpolator&&) noexcept = default;

void FaceInterpolator::Interpolate(const std::array<TexelSample, 3>& corners,
                                   std::span<const TexelSample> points,
                                   std::span<const BakeTexel> texels,
                                   const TexelInterpolationOptions& options,
                                   std::vector<std::array<float, 3>>& colors,
                                   std::vector<std::array<float, 3>>& normals) {
  // A moved-from interpolator gets fresh scratch.
  if (!scratch_) scratch_ = std::make_unique<Scratch>();
  InterpScratch& s = *scratch_;
  colors.resize(texels.size());
  normals.resize(texels.size());
  if (texels.empty()) return;

  s.positions.clear();
  s.values.clear();
  bool corners_finite = true;
  for (const TexelSample& corner : corners) {
    corners_finite = corners_finite && Finite(corner);
    s.positions.push_back({corner.s, corner.t});
    s.values.push_back(ValueOf(corner));
  }
  for (const TexelSample& point : points) {
    if (!Finite(point)) continue;
    s.positions.push_back({point.s, point.t});
    s.values.push_back(ValueOf(point));
  }
  // No points (or corners without a usable position): the barycentric
  // interpolation of the corners, which is what bake.vertex_colors does.
  if (s.positions.size() == 3 || !corners_finite) {
    for (size_t i = 0; i < texels.size(); ++i) {
      Value v = CornerBlend(corners, texels[i].bary);
      WriteOut(v, v, colors[i], normals[i]);
    }
    return;
  }

  s.first = !options.corner_samples && s.positions.size() >= 6 ? 3 : 0;
  s.texel_values.resize(texels.size());
  switch (options.mode) {
    case TexelInterpolation::kDelaunay:
      InterpolateDelaunay(s, texels);
      break;
    case TexelInterpolation::kNearest:
      InterpolateNearest(s, texels);
      break;
    case TexelInterpolation::kIdw:
      InterpolateIdw(s, texels, options);
      break;
    case TexelInterpolation::kSplat:
      InterpolateSplat(s, texels, options);
      break;
  }
  for (size_t i = 0; i < texels.size(); ++i) {
    WriteOut(s.texel_values[i], CornerBlend(corners, texels[i].bary), colors[i], normals[i]);
  }
}

}  // namespace pb
