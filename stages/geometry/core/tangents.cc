// Tangent frames: Lengyel 2001 per-triangle derivatives, corner-angle
// accumulation as MikkTSpace, Gram–Schmidt per vertex (see tangents.h).
#include "stages/geometry/core/tangents.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace pb {
namespace {

using Vec3 = std::array<double, 3>;

Vec3 Sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double Dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 Cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double Norm(const Vec3& a) { return std::sqrt(Dot(a, a)); }
Vec3 Scale(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }

Vec3 Position(const Mesh& mesh, uint32_t v) {
  return {mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
}

// Angle between unit-free edge vectors a and b, in [0, pi].
double Angle(const Vec3& a, const Vec3& b) { return std::atan2(Norm(Cross(a, b)), Dot(a, b)); }

// A unit vector orthogonal to the unit vector n: the coordinate axis least
// aligned with n, projected into n's plane.
Vec3 AnyTangent(const Vec3& n) {
  int axis = 0;
  for (int k = 1; k < 3; ++k) {
    if (std::abs(n[k]) < std::abs(n[axis])) axis = k;
  }
  Vec3 e{0, 0, 0};
  e[axis] = 1;
  Vec3 t = Sub(e, Scale(n, Dot(n, e)));
  return Scale(t, 1.0 / Norm(t));
}

}  // namespace

std::vector<float> ComputeVertexNormals(const Mesh& mesh) {
  const size_t n = mesh.vertex_count();
  std::vector<double> sum(3 * n, 0.0);
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* tri = &mesh.indices[3 * f];
    const Vec3 a = Position(mesh, tri[0]);
    const Vec3 face = Cross(Sub(Position(mesh, tri[1]), a), Sub(Position(mesh, tri[2]), a));
    for (int c = 0; c < 3; ++c) {
      for (int k = 0; k < 3; ++k) sum[3 * tri[c] + k] += face[k];
    }
  }
  std::vector<float> normals(3 * n);
  for (size_t v = 0; v < n; ++v) {
    const Vec3 s{sum[3 * v], sum[3 * v + 1], sum[3 * v + 2]};
    const double length = Norm(s);
    const Vec3 unit = length > 0 ? Scale(s, 1.0 / length) : Vec3{0, 0, 1};
    for (int k = 0; k < 3; ++k) normals[3 * v + k] = static_cast<float>(unit[k]);
  }
  return normals;
}

Expected<std::vector<float>> ComputeTangents(const Mesh& mesh, TangentReport* report) {
  PB_RETURN_IF_ERROR(Validate(mesh).WithContext("computing tangents"));
  if (!mesh.has_uvs()) {
    return Status::Invalid("computing tangents: the mesh has no uvs (unwrap it first)");
  }
  TangentReport local;
  TangentReport& out = report ? *report : local;
  out = TangentReport{};
  const size_t n = mesh.vertex_count();
  std::vector<float> computed_normals;
  if (!mesh.has_normals()) computed_normals = ComputeVertexNormals(mesh);
  const std::vector<float>& normals = mesh.has_normals() ? mesh.normals : computed_normals;

  // Accumulated per vertex: T (xyz) and B (xyz), in double so the order of
  // faces matters only at the last bit.
  std::vector<double> accum(6 * n, 0.0);
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* tri = &mesh.indices[3 * f];
    const Vec3 p[3] = {Position(mesh, tri[0]), Position(mesh, tri[1]), Position(mesh, tri[2])};
    const double u[3] = {mesh.uvs[2 * tri[0]], mesh.uvs[2 * tri[1]], mesh.uvs[2 * tri[2]]};
    const double v[3] = {mesh.uvs[2 * tri[0] + 1], mesh.uvs[2 * tri[1] + 1],
                         mesh.uvs[2 * tri[2] + 1]};
    const Vec3 e1 = Sub(p[1], p[0]), e2 = Sub(p[2], p[0]);
    const double du1 = u[1] - u[0], dv1 = v[1] - v[0], du2 = u[2] - u[0], dv2 = v[2] - v[0];
    const double det = du1 * dv2 - du2 * dv1;
    const double uv_extent = std::max({du1 * du1 + dv1 * dv1, du2 * du2 + dv2 * dv2,
                                       (du2 - du1) * (du2 - du1) + (dv2 - dv1) * (dv2 - dv1)});
    if (!(std::abs(det) > 1e-12 * uv_extent) || Norm(Cross(e1, e2)) == 0) {
      ++out.degenerate_uv_faces;
      continue;
    }
    Vec3 t = Scale(Sub(Scale(e1, dv2), Scale(e2, dv1)), 1.0 / det);
    Vec3 b = Scale(Sub(Scale(e2, du1), Scale(e1, du2)), 1.0 / det);
    const double t_length = Norm(t), b_length = Norm(b);
    if (t_length == 0 || b_length == 0 || !std::isfinite(t_length) || !std::isfinite(b_length)) {
      ++out.degenerate_uv_faces;
      continue;
    }
    t = Scale(t, 1.0 / t_length);
    b = Scale(b, 1.0 / b_length);
    for (int c = 0; c < 3; ++c) {
      const double angle = Angle(Sub(p[(c + 1) % 3], p[c]), Sub(p[(c + 2) % 3], p[c]));
      double* a = &accum[6 * tri[c]];
      for (int k = 0; k < 3; ++k) {
        a[k] += angle * t[k];
        a[3 + k] += angle * b[k];
      }
    }
  }

  std::vector<float> tangents(4 * n);
  for (size_t i = 0; i < n; ++i) {
    Vec3 normal{normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]};
    const double normal_length = Norm(normal);
    if (normal_length > 0 && std::isfinite(normal_length)) {
      normal = Scale(normal, 1.0 / normal_length);
    } else {
      // A zero normal in the input: fall back to this vertex's face normals.
      if (computed_normals.empty()) computed_normals = ComputeVertexNormals(mesh);
      normal = {computed_normals[3 * i], computed_normals[3 * i + 1], computed_normals[3 * i + 2]};
    }
    const double* a = &accum[6 * i];
    const Vec3 t_sum{a[0], a[1], a[2]}, b_sum{a[3], a[4], a[5]};
    Vec3 t = Sub(t_sum, Scale(normal, Dot(normal, t_sum)));
    const double length = Norm(t);
    double w = 1;
    // 1e-6 of the accumulated weight: below it T is (nearly) parallel to n.
    if (length > 1e-6 * Norm(t_sum) && length > 0) {
      t = Scale(t, 1.0 / length);
      w = Dot(Cross(normal, t), b_sum) < 0 ? -1 : 1;
    } else {
      t = AnyTangent(normal);
      ++out.fallback_vertices;
    }
    if (w < 0) ++out.mirrored_vertices;
    for (int k = 0; k < 3; ++k) tangents[4 * i + k] = static_cast<float>(t[k]);
    tangents[4 * i + 3] = static_cast<float>(w);
  }
  return tangents;
}

}  // namespace pb
