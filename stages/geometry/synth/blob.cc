// The sculpture's blob (blob.h): radius function, implicit surface, closest
// points, ray hits and the derived bounds (PrepareBlob, objects.h).
#include "stages/geometry/synth/blob.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "stages/geometry/synth/synth_math.h"

namespace pb {
namespace {

using synth::Add;
using synth::Cross;
using synth::Dot;
using synth::Length;
using synth::MarchImplicit;
using synth::Normalize;
using synth::Perpendicular;
using synth::Scale;
using synth::Sub;
using synth::V3;

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kAngleStep = 1e-5;  // rad, finite differences on the sphere

// exp(-x) near 0 (same value and slope at 0), C3 and 0 from x = 4 on: cheap
// and compact.
double BumpKernel(double x) {
  if (x >= 4) return 0;
  const double a = 1 - 0.25 * x, a2 = a * a;
  return a2 * a2;
}

// Cell of unit direction w in a cube map of 6 x n x n cells.
size_t CubeCell(const V3& w, int n) {
  int a = 0;
  for (int k = 1; k < 3; ++k) {
    if (std::abs(w[k]) > std::abs(w[a])) a = k;
  }
  const double inv = 1 / std::abs(w[a]);
  const double u = w[(a + 1) % 3] * inv, v = w[(a + 2) % 3] * inv;
  const int i = std::clamp(static_cast<int>((u + 1) * 0.5 * n), 0, n - 1);
  const int j = std::clamp(static_cast<int>((v + 1) * 0.5 * n), 0, n - 1);
  const int face = 2 * a + (w[a] > 0 ? 1 : 0);
  return (size_t(face) * n + j) * n + i;
}

}  // namespace

double BlobGroove(const SynthBlob& b, const V3& w) {
  if (b.grooves == 0) return 0;
  const double fade = (1 - w[2] * w[2]) * (1 - w[2] * w[2]);
  const double phi = std::atan2(w[1], w[0]);
  const double c = std::cos(b.grooves * (phi + b.groove_twist * w[2]));
  return c > 0 ? fade * (c * c) * (c * c) : 0;  // in [0, 1]
}

double BlobRadius(const SynthBlob& b, const V3& w) {
  const double ex = w[0] / b.semi_axes_m[0], ey = w[1] / b.semi_axes_m[1], ez = w[2] / b.semi_axes_m[2];
  const double ellipsoid = 1 / std::sqrt(ex * ex + ey * ey + ez * ez);
  double bumps = 0;
  for (const SynthBump& k : b.bumps) bumps += k.amplitude * BumpKernel((1 - Dot(w, k.direction)) / (k.width * k.width));
  const double dz = (w[2] - b.waist_z) / b.waist_width;
  const double waist = 1 - b.waist_depth * BumpKernel(dz * dz);
  return ellipsoid * (1 + bumps) * waist - b.groove_depth_m * BlobGroove(b, w);
}

double BlobImplicit(const SynthBlob& b, const V3& p) {
  const V3 rel = Sub(p, b.center_m);
  const double rho = Length(rel);
  if (rho < 1e-12) return -b.r_min_m;
  return rho - BlobRadius(b, Scale(rel, 1 / rho));
}

V3 BlobGradient(const SynthBlob& b, const V3& p) {
  const V3 rel = Sub(p, b.center_m);
  const double rho = std::max(Length(rel), 1e-12);
  const V3 w = Scale(rel, 1 / rho);
  const V3 t1 = Perpendicular(w), t2 = Cross(w, t1);
  auto slope = [&](const V3& t) {
    return (BlobRadius(b, Normalize(Add(w, Scale(t, kAngleStep)))) -
            BlobRadius(b, Normalize(Sub(w, Scale(t, kAngleStep))))) /
           (2 * kAngleStep);
  };
  return Sub(w, Scale(Add(Scale(t1, slope(t1)), Scale(t2, slope(t2))), 1 / rho));
}

namespace {

// Moves q onto the surface along the gradient (Newton on the implicit).
V3 BlobProjectOnto(const SynthBlob& b, V3 q) {
  for (int it = 0; it < 40; ++it) {
    const double f = BlobImplicit(b, q);
    if (std::abs(f) < 1e-11) break;
    const V3 g = BlobGradient(b, q);
    const double g2 = std::max(Dot(g, g), 1e-12);
    V3 step = Scale(g, f / g2);
    const double len = Length(step), limit = 0.5 * Length(Sub(q, b.center_m)) + 1e-6;
    if (len > limit) step = Scale(step, limit / len);
    q = Sub(q, step);
  }
  return q;
}

}  // namespace

BlobClosest BlobClosestPoint(const SynthBlob& b, const V3& p) {
  BlobClosest out;
  const double f = BlobImplicit(b, p);
  if (std::abs(f) < 1e-5) {
    // On the surface to first order (error ~ f^2 / curvature radius < 1e-9 m).
    const V3 g = BlobGradient(b, p);
    const double g_len = Length(g);
    out.distance_m = f / g_len;
    out.normal = Scale(g, 1 / g_len);
    out.foot = Sub(p, Scale(out.normal, out.distance_m));
    return out;
  }
  // Two starting feet: along the gradient, and along the ray from the center.
  // From each, move along the surface toward p's tangential offset (halving
  // the move until the distance decreases): a descent to a local closest
  // point; the nearer of the two is taken.
  const V3 rel = Sub(p, b.center_m);
  const V3 w = Normalize(rel);
  const V3 starts[2] = {BlobProjectOnto(b, p), Add(b.center_m, Scale(w, BlobRadius(b, w)))};
  V3 best = starts[0];
  double best_distance = kInf;
  for (V3 q : starts) {
    double distance = Length(Sub(p, q));
    for (int it = 0; it < 40; ++it) {
      const V3 n = Normalize(BlobGradient(b, q));
      const V3 offset = Sub(p, q);
      const V3 tangential = Sub(offset, Scale(n, Dot(offset, n)));
      if (Length(tangential) < 1e-9) break;
      bool moved = false;
      for (double step = 1; step > 1e-3; step *= 0.5) {
        const V3 candidate = BlobProjectOnto(b, Add(q, Scale(tangential, step)));
        const double d = Length(Sub(p, candidate));
        if (d < distance) {
          q = candidate, distance = d, moved = true;
          break;
        }
      }
      if (!moved) break;
    }
    if (distance < best_distance) best = q, best_distance = distance;
  }
  out.foot = best;
  out.distance_m = f >= 0 ? best_distance : -best_distance;
  out.normal = Normalize(BlobGradient(b, best));
  return out;
}

double BlobRayHit(const SynthBlob& b, const V3& o, const V3& d) {
  // March only inside the bounding ellipsoid (E scaled by bound_scale).
  V3 os, ds;
  for (int a = 0; a < 3; ++a) {
    const double axis = b.bound_scale * b.semi_axes_m[a];
    os[a] = (o[a] - b.center_m[a]) / axis, ds[a] = d[a] / axis;
  }
  const double aq = Dot(ds, ds), bq = Dot(os, ds), cq = Dot(os, os) - 1;
  const double disc = bq * bq - aq * cq;
  if (disc < 0) return kInf;
  const double root = std::sqrt(disc);
  const double t0 = std::max((-bq - root) / aq, 1e-9), t1 = (-bq + root) / aq;
  if (!(t1 > t0)) return kInf;
  auto implicit = [&](double t) { return BlobImplicit(b, Add(o, Scale(d, t))); };
  auto step = [&](double t, double f_t) {
    const V3 rel = Sub(Add(o, Scale(d, t)), b.center_m);
    const double rho = Length(rel);
    if (b.cube_cells == 0 || rho < 1e-9) return f_t / b.lipschitz;
    const double local = b.local_lipschitz[CubeCell(Scale(rel, 1 / rho), b.cube_cells)];
    return std::max(f_t / b.lipschitz, std::min(f_t / local, 0.05 * rho));
  };
  return MarchImplicit(implicit, t0, t1, step, 1e-4);
}

void PrepareBlob(SynthBlob& b) {
  constexpr int kDirections = 40000;
  const double golden = kPi * (3 - std::sqrt(5.0));
  double r_min = kInf, r_max = 0, slope = 0, scale = 0;
  for (int k = 0; k < kDirections; ++k) {
    const double z = 1 - (k + 0.5) * 2.0 / kDirections, r = std::sqrt(1 - z * z);
    const V3 w = {r * std::cos(golden * k), r * std::sin(golden * k), z};
    const double radius = BlobRadius(b, w);
    r_min = std::min(r_min, radius), r_max = std::max(r_max, radius);
    const double ex = w[0] / b.semi_axes_m[0], ey = w[1] / b.semi_axes_m[1], ez = w[2] / b.semi_axes_m[2];
    scale = std::max(scale, radius * std::sqrt(ex * ex + ey * ey + ez * ez));
    const V3 g = BlobGradient(b, Add(b.center_m, Scale(w, radius)));
    // g = w - grad_T R / rho: its tangential part is the slope over the
    // radius, the term |grad f| adds to 1 (smaller farther out).
    slope = std::max(slope, Length(Sub(g, Scale(w, Dot(g, w)))));
  }
  b.r_min_m = 0.97 * r_min;
  b.r_max_m = 1.03 * r_max;
  b.bound_scale = 1.03 * scale;
  const double g = 1.25 * slope;
  b.lipschitz = std::sqrt(1 + g * g);
  // Local bounds: the slope over the directions within 0.12 rad of each
  // cube cell's center (a cell's half-diagonal is < 0.045 rad, a step's cone
  // < 0.05 rad), 32 directions on a spiral, 1.3x margin.
  constexpr int kCells = 32, kSamples = 32;
  constexpr double kRadius = 0.12;
  b.cube_cells = kCells;
  b.local_lipschitz.assign(size_t(6) * kCells * kCells, static_cast<float>(b.lipschitz));
  tbb::parallel_for(0, 6 * kCells, [&](int row) {
    const int face = row / kCells, j = row % kCells, a = face / 2;
    for (int i = 0; i < kCells; ++i) {
      V3 center;
      center[a] = face % 2 ? 1 : -1;
      center[(a + 1) % 3] = (i + 0.5) * 2.0 / kCells - 1;
      center[(a + 2) % 3] = (j + 0.5) * 2.0 / kCells - 1;
      center = Normalize(center);
      const V3 t1 = Perpendicular(center), t2 = Cross(center, t1);
      double cell_slope = 0;
      for (int k = 0; k < kSamples; ++k) {
        const double r = kRadius * std::sqrt((k + 0.5) / kSamples), angle = golden * k;
        const V3 w = Normalize(Add(center, Add(Scale(t1, r * std::cos(angle)), Scale(t2, r * std::sin(angle)))));
        const double radius = BlobRadius(b, w);
        const V3 gw = BlobGradient(b, Add(b.center_m, Scale(w, radius)));
        cell_slope = std::max(cell_slope, Length(Sub(gw, Scale(w, Dot(gw, w)))));
      }
      const double local_g = 1.3 * cell_slope;
      b.local_lipschitz[(size_t(face) * kCells + j) * kCells + i] =
          static_cast<float>(std::min(b.lipschitz, std::sqrt(1 + local_g * local_g)));
    }
  });
}

}  // namespace pb
