// Small shared helpers of the synthetic scenes (scene.cc, materials.cc,
// objects.cc): counter-based hashing (no global random state, so every value
// is a pure function of its arguments and scans are identical for any thread
// count), value noise, 3-vector arithmetic and ray marching. Internal to
// pb_synth.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace pb::synth {

using V3 = std::array<double, 3>;

inline uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
inline uint64_t Hash(uint64_t a, uint64_t b, uint64_t c = 0, uint64_t d = 0) {
  return SplitMix64(SplitMix64(SplitMix64(SplitMix64(a) ^ b) ^ c) ^ d);
}
// Uniform in [0, 1).
inline double Unit(uint64_t h) { return static_cast<double>(h >> 11) * 0x1.0p-53; }
inline uint64_t Key(int64_t i) { return static_cast<uint64_t>(i); }

inline double SmoothStep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

// Value noise in [0, 1] on a unit lattice, smoothly interpolated.
inline double ValueNoise(uint64_t seed, double x, double y) {
  const double fx = std::floor(x), fy = std::floor(y);
  const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
  const double sx = SmoothStep(x - fx), sy = SmoothStep(y - fy);
  auto at = [&](int64_t dx, int64_t dy) { return Unit(Hash(seed, Key(ix + dx), Key(iy + dy), 77)); };
  const double a = at(0, 0) + (at(1, 0) - at(0, 0)) * sx;
  const double b = at(0, 1) + (at(1, 1) - at(0, 1)) * sx;
  return a + (b - a) * sy;
}

// Value noise in [0, 1] on a unit 3-D lattice (curved surfaces, where no 2-D
// parameterization is free of seams).
inline double ValueNoise3(uint64_t seed, double x, double y, double z) {
  const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy), iz = static_cast<int64_t>(fz);
  const double sx = SmoothStep(x - fx), sy = SmoothStep(y - fy), sz = SmoothStep(z - fz);
  auto at = [&](int64_t dx, int64_t dy, int64_t dz) {
    return Unit(Hash(seed, Key(ix + dx), Key(iy + dy), Key(iz + dz)));
  };
  double plane[2];
  for (int dz = 0; dz < 2; ++dz) {
    const double a = at(0, 0, dz) + (at(1, 0, dz) - at(0, 0, dz)) * sx;
    const double b = at(0, 1, dz) + (at(1, 1, dz) - at(0, 1, dz)) * sx;
    plane[dz] = a + (b - a) * sy;
  }
  return plane[0] + (plane[1] - plane[0]) * sz;
}

inline V3 Add(const V3& a, const V3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline V3 Sub(const V3& a, const V3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline V3 Scale(const V3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double Dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline V3 Cross(const V3& a, const V3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double Length(const V3& a) { return std::sqrt(Dot(a, a)); }
inline V3 Normalize(const V3& a) {
  const double n = Length(a);
  return n > 0 ? Scale(a, 1 / n) : a;
}

// A unit vector perpendicular to the unit `axis`.
inline V3 Perpendicular(const V3& axis) {
  const V3 helper = std::abs(axis[2]) < 0.9 ? V3{0, 0, 1} : V3{1, 0, 0};
  return Normalize(Cross(axis, helper));
}

// Ray marching of implicit surfaces after Hart, "Sphere tracing" (The Visual
// Computer 12, 1996): steps of f / L with L a Lipschitz bound of f.
// Departures: a minimum step (no feature here is thinner than 1e-4 m), then
// regula falsi to 1e-9 m on the first sign change, so grazing rays end in
// bounded time.
// First sign change of f along [t0, t1] (f(t0) > 0 expected), marching with
// steps step(t, f) (a distance the surface is known not to be within; at
// least min_step), then regula falsi.
template <typename Fn, typename StepFn>
double MarchImplicit(Fn f, double t0, double t1, StepFn step, double min_step) {
  double t = t0, value = f(t);
  if (value <= 0) return t0;
  while (t < t1) {
    const double next = std::min(t1, t + std::max(step(t, value), min_step));
    const double next_value = f(next);
    if (next_value <= 0) {
      // Regula falsi with the Illinois modification on [t, next].
      double lo = t, hi = next, f_lo = value, f_hi = next_value;
      int side = 0;
      for (int it = 0; it < 60 && hi - lo > 1e-9; ++it) {
        double mid = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        if (!(mid > lo && mid < hi)) mid = 0.5 * (lo + hi);
        const double f_mid = f(mid);
        if (f_mid > 0) {
          lo = mid, f_lo = f_mid;
          if (side == -1) f_hi *= 0.5;
          side = -1;
        } else {
          hi = mid, f_hi = f_mid;
          if (side == 1) f_lo *= 0.5;
          side = 1;
          if (f_mid == 0) break;
        }
        if (std::abs(f_mid) < 1e-10) {
          if (f_mid > 0) hi = lo;  // within 1e-10 m of the surface: close enough
          break;
        }
      }
      return hi;
    }
    if (next >= t1) break;
    t = next, value = next_value;
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace pb::synth
