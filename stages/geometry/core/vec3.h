// Small 3-vector helpers on std::array<double, 3>, shared by the geometry
// code that works in double precision (rendering, splats, UV charts, the
// mesh fit). Each file keeps its own normalization, because they differ in
// what a zero vector becomes.
#pragma once

#include <array>
#include <cmath>

namespace pb::vec3 {

using V3 = std::array<double, 3>;

inline V3 Sub(const V3& a, const V3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline V3 Add(const V3& a, const V3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline V3 Scale(const V3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double Dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline V3 Cross(const V3& a, const V3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double Norm(const V3& a) { return std::sqrt(Dot(a, a)); }

}  // namespace pb::vec3
