// Open synthetic scenes built from analytic elements (objects.h): distance,
// normals, ray intersection, albedo and the truth mesh of patches, boxes,
// cylinders and star-shaped blobs. The presets are in object_presets.cc.
//
// Fluted cylinders are ray marched (synth_math.h's MarchImplicit); the blob
// is in blob.cc.
#include "stages/geometry/synth/objects.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "stages/geometry/synth/blob.h"
#include "stages/geometry/synth/materials.h"
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
constexpr double kReliefStep = 2e-4;  // m, finite differences of relief

// Global element index: patches, then boxes, cylinders, blobs. A hit's or a
// sample's `part` is element * 8 + face.
enum class Kind { kPatch, kBox, kCylinder, kBlob };
struct ElementRef {
  Kind kind;
  int index;
};
ElementRef Element(const SynthObjects& o, int element) {
  const int p = static_cast<int>(o.patches.size()), b = static_cast<int>(o.boxes.size());
  const int c = static_cast<int>(o.cylinders.size());
  if (element < p) return {Kind::kPatch, element};
  if (element < p + b) return {Kind::kBox, element - p};
  if (element < p + b + c) return {Kind::kCylinder, element - p - b};
  return {Kind::kBlob, element - p - b - c};
}
int ElementCount(const SynthObjects& o) {
  return static_cast<int>(o.patches.size() + o.boxes.size() + o.cylinders.size() + o.blobs.size());
}

// What every element reports for a point: signed distance to its (displaced)
// surface, > 0 outside; the face; surface coordinates and the true normal.
struct Local {
  double distance = kInf;
  int face = 0;
  double u = 0, v = 0;
  V3 normal{0, 0, 1};
  V3 foot{};  // closest surface point (blobs) or the point itself
};

// --- patches ---

V3 PatchNormal(const SynthPatch& p) { return Cross(p.axis_u, p.axis_v); }

double PatchRelief(const SynthScene& s, const SynthPatch& p, double u, double v) {
  switch (p.material) {
    case SynthMaterial::kBrick:
      return BrickRelief(s.brick, u, v);
    case SynthMaterial::kStone:
      return StoneRelief(s.floor, s.seed, u, v);
    case SynthMaterial::kWood:
      return WoodRelief(u, v);
    default:
      return 0;
  }
}

// Normal of a relief r(u, v) over a plane with tangents tu, tv and normal n.
template <typename ReliefFn>
V3 ReliefNormal(const V3& n, const V3& tu, const V3& tv, double u, double v, ReliefFn relief) {
  const double du = (relief(u + kReliefStep, v) - relief(u - kReliefStep, v)) / (2 * kReliefStep);
  const double dv = (relief(u, v + kReliefStep) - relief(u, v - kReliefStep)) / (2 * kReliefStep);
  return Normalize(Sub(n, Add(Scale(tu, du), Scale(tv, dv))));
}

Local PatchLocal(const SynthScene& s, const SynthPatch& p, const V3& point, bool with_normal = true) {
  const V3 rel = Sub(point, p.origin_m), n = PatchNormal(p);
  const double u = Dot(rel, p.axis_u), v = Dot(rel, p.axis_v), w = Dot(rel, n);
  const double cu = std::clamp(u, 0.0, p.length_u_m), cv = std::clamp(v, 0.0, p.length_v_m);
  Local out;
  out.u = cu, out.v = cv;
  out.foot = point;
  auto relief = [&](double a, double b) { return PatchRelief(s, p, a, b); };
  out.normal = with_normal ? ReliefNormal(n, p.axis_u, p.axis_v, cu, cv, relief) : n;
  if (cu == u && cv == v && w > -kPatchMassM) {
    out.distance = w - relief(u, v);
  } else {
    out.distance = std::sqrt((u - cu) * (u - cu) + (v - cv) * (v - cv) + w * w);  // from the side or far behind
  }
  return out;
}

// --- boxes ---

double BoxRelief(const SynthBox& b, int face, double u, double v) {
  return (b.material == SynthMaterial::kWood && face == 5) ? WoodRelief(u, v) : 0;
}

// Face f: axis f / 2, side f % 2 (1 = max); tangents along axes (a+1)%3, (a+2)%3.
void BoxFaceFrame(int face, V3* n, V3* tu, V3* tv) {
  const int a = face / 2;
  *n = {0, 0, 0}, *tu = {0, 0, 0}, *tv = {0, 0, 0};
  (*n)[a] = face % 2 ? 1 : -1;
  (*tu)[(a + 1) % 3] = 1;
  (*tv)[(a + 2) % 3] = 1;
}

Local BoxLocal(const SynthBox& b, const V3& p, bool with_normal = true) {
  V3 q;
  int axis = 0;
  for (int a = 0; a < 3; ++a) {
    const double c = (b.min_m[a] + b.max_m[a]) / 2, h = (b.max_m[a] - b.min_m[a]) / 2;
    q[a] = std::abs(p[a] - c) - h;
    if (q[a] > q[axis]) axis = a;
  }
  Local out;
  const double c = (b.min_m[axis] + b.max_m[axis]) / 2;
  out.face = 2 * axis + (p[axis] > c ? 1 : 0);
  const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
  out.u = std::clamp(p[ua], b.min_m[ua], b.max_m[ua]) - b.min_m[ua];
  out.v = std::clamp(p[va], b.min_m[va], b.max_m[va]) - b.min_m[va];
  out.foot = p;
  const double outside = Length({std::max(q[0], 0.0), std::max(q[1], 0.0), std::max(q[2], 0.0)});
  out.distance = outside + std::min(q[axis], 0.0) - BoxRelief(b, out.face, out.u, out.v);
  V3 n, tu, tv;
  BoxFaceFrame(out.face, &n, &tu, &tv);
  const int face = out.face;
  out.normal = with_normal ? ReliefNormal(n, tu, tv, out.u, out.v,
                                          [&](double a, double bb) { return BoxRelief(b, face, a, bb); })
                           : n;
  return out;
}

// --- cylinders ---

struct CylFrame {
  V3 e1, e2;
};
CylFrame CylinderFrame(const SynthCylinder& c) {
  const V3 e1 = Perpendicular(c.axis);
  return {e1, Cross(c.axis, e1)};
}

// Flute relief (<= 0) at angle theta and its derivative.
double FluteRelief(const SynthCylinder& c, double theta) {
  if (c.flutes == 0) return 0;
  return -c.flute_depth_m * 0.5 * (1 + std::cos(c.flutes * theta));
}
double FluteSlope(const SynthCylinder& c, double theta) {
  if (c.flutes == 0) return 0;
  return c.flute_depth_m * 0.5 * c.flutes * std::sin(c.flutes * theta);
}

struct CylCoords {
  double h, x, y, rho, theta;  // theta in [0, 2 pi)
};
CylCoords CylinderCoords(const SynthCylinder& c, const CylFrame& f, const V3& p) {
  const V3 rel = Sub(p, c.base_m);
  CylCoords k;
  k.h = Dot(rel, c.axis), k.x = Dot(rel, f.e1), k.y = Dot(rel, f.e2);
  k.rho = std::hypot(k.x, k.y);
  k.theta = std::atan2(k.y, k.x);
  if (k.theta < 0) k.theta += 2 * kPi;
  return k;
}

// Inside/outside function of the solid (sign exact, magnitude a distance to
// first order): max(radial, axial).
double CylinderImplicit(const SynthCylinder& c, const CylCoords& k) {
  return std::max(k.rho - (c.radius_m + FluteRelief(c, k.theta)), std::max(-k.h, k.h - c.length_m));
}

Local CylinderLocal(const SynthCylinder& c, const V3& p) {
  const CylFrame f = CylinderFrame(c);
  const CylCoords k = CylinderCoords(c, f, p);
  const double slope = FluteSlope(c, k.theta) / std::max(k.rho, 1e-9);
  const double radial = (k.rho - (c.radius_m + FluteRelief(c, k.theta))) / std::sqrt(1 + slope * slope);
  const double axial = std::max(-k.h, k.h - c.length_m);
  Local out;
  out.foot = p;
  out.distance = (radial > 0 && axial > 0) ? std::hypot(radial, axial) : std::max(radial, axial);
  if (radial >= axial) {
    out.face = 0;
    out.u = c.radius_m * k.theta, out.v = std::clamp(k.h, 0.0, c.length_m);
    const V3 r_hat = Add(Scale(f.e1, std::cos(k.theta)), Scale(f.e2, std::sin(k.theta)));
    const V3 t_hat = Add(Scale(f.e1, -std::sin(k.theta)), Scale(f.e2, std::cos(k.theta)));
    out.normal = Normalize(Sub(r_hat, Scale(t_hat, FluteSlope(c, k.theta) / std::max(k.rho, 1e-9))));
  } else {
    out.face = k.h < c.length_m / 2 ? 1 : 2;
    out.u = k.x, out.v = k.y;
    out.normal = out.face == 1 ? Scale(c.axis, -1) : c.axis;
  }
  return out;
}

// --- blobs (blob.h) ---

Local BlobLocal(const SynthBlob& b, const V3& p) {
  const BlobClosest closest = BlobClosestPoint(b, p);
  Local out;
  out.distance = closest.distance_m;
  out.foot = closest.foot;
  out.normal = closest.normal;
  return out;
}

// --- per element ---

// with_normal = false: patches and boxes skip their relief normal (the
// distance search needs only the winner's).
Local ElementLocal(const SynthScene& s, int element, const V3& p, bool with_normal = true) {
  const SynthObjects& o = *s.objects;
  const ElementRef e = Element(o, element);
  switch (e.kind) {
    case Kind::kPatch:
      return PatchLocal(s, o.patches[e.index], p, with_normal);
    case Kind::kBox:
      return BoxLocal(o.boxes[e.index], p, with_normal);
    case Kind::kCylinder:
      return CylinderLocal(o.cylinders[e.index], p);
    case Kind::kBlob:
      return BlobLocal(o.blobs[e.index], p);
  }
  return {};
}

// A cheap lower bound of the element's |distance| (blobs: the bounding
// sphere), to skip expensive elements.
double DistanceLowerBound(const SynthObjects& o, int element, const V3& p) {
  const ElementRef e = Element(o, element);
  if (e.kind != Kind::kBlob) return 0;
  const SynthBlob& b = o.blobs[e.index];
  const double rho = Length(Sub(p, b.center_m));
  if (rho > b.r_max_m) return rho - b.r_max_m;
  return std::abs(BlobImplicit(b, p)) / b.lipschitz;
}

// Inside the solid of `element` (patches: within their mass).
bool Inside(const SynthScene& s, int element, const V3& p) {
  const SynthObjects& o = *s.objects;
  const ElementRef e = Element(o, element);
  switch (e.kind) {
    case Kind::kPatch: {
      const SynthPatch& q = o.patches[e.index];
      const V3 rel = Sub(p, q.origin_m);
      const double u = Dot(rel, q.axis_u), v = Dot(rel, q.axis_v), w = Dot(rel, PatchNormal(q));
      return u > 0 && u < q.length_u_m && v > 0 && v < q.length_v_m && w < 0 && w > -kPatchMassM;
    }
    case Kind::kBox: {
      const SynthBox& b = o.boxes[e.index];
      for (int a = 0; a < 3; ++a) {
        if (!(p[a] > b.min_m[a] && p[a] < b.max_m[a])) return false;
      }
      return true;
    }
    case Kind::kCylinder: {
      const SynthCylinder& c = o.cylinders[e.index];
      return CylinderImplicit(c, CylinderCoords(c, CylinderFrame(c), p)) < 0;
    }
    case Kind::kBlob:
      return BlobImplicit(o.blobs[e.index], p) < 0;
  }
  return false;
}

// --- ray intersection per element: t of the first hit (> 1e-9), or kInf ---

struct ElementHit {
  double t = kInf;
  V3 point{};
};

ElementHit IntersectPatch(const SynthScene& s, const SynthPatch& p, const V3& o, const V3& d) {
  const V3 n = PatchNormal(p);
  const double denom = Dot(d, n);
  if (denom == 0) return {};
  const double t = -Dot(Sub(o, p.origin_m), n) / denom;
  if (!(t > 1e-9)) return {};
  const V3 x = Add(o, Scale(d, t));
  const double u = Dot(Sub(x, p.origin_m), p.axis_u), v = Dot(Sub(x, p.origin_m), p.axis_v);
  if (u < 0 || u > p.length_u_m || v < 0 || v > p.length_v_m) return {};
  return {t, Add(x, Scale(n, PatchRelief(s, p, u, v)))};
}

ElementHit IntersectBox(const SynthBox& b, const V3& o, const V3& d) {
  double t_near = -kInf, t_far = kInf;
  int face = -1;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0) {
      if (o[a] < b.min_m[a] || o[a] > b.max_m[a]) return {};
      continue;
    }
    double t0 = (b.min_m[a] - o[a]) / d[a], t1 = (b.max_m[a] - o[a]) / d[a];
    int f0 = 2 * a, f1 = 2 * a + 1;
    if (t0 > t1) std::swap(t0, t1), std::swap(f0, f1);
    if (t0 > t_near) t_near = t0, face = f0;
    t_far = std::min(t_far, t1);
  }
  if (!(t_near <= t_far) || !(t_near > 1e-9) || face < 0) return {};
  const V3 x = Add(o, Scale(d, t_near));
  const int ua = (face / 2 + 1) % 3, va = (face / 2 + 2) % 3;
  V3 n, tu, tv;
  BoxFaceFrame(face, &n, &tu, &tv);
  return {t_near, Add(x, Scale(n, BoxRelief(b, face, x[ua] - b.min_m[ua], x[va] - b.min_m[va])))};
}

ElementHit IntersectCylinder(const SynthCylinder& c, const V3& o, const V3& d) {
  const CylFrame f = CylinderFrame(c);
  const V3 rel = Sub(o, c.base_m);
  const double ox = Dot(rel, f.e1), oy = Dot(rel, f.e2), oh = Dot(rel, c.axis);
  const double dx = Dot(d, f.e1), dy = Dot(d, f.e2), dh = Dot(d, c.axis);
  double t_in = -kInf, t_out = kInf;
  const double a = dx * dx + dy * dy, bq = ox * dx + oy * dy, cq = ox * ox + oy * oy - c.radius_m * c.radius_m;
  if (a < 1e-18) {
    if (cq > 0) return {};
  } else {
    const double disc = bq * bq - a * cq;
    if (disc < 0) return {};
    const double root = std::sqrt(disc);
    t_in = (-bq - root) / a, t_out = (-bq + root) / a;
  }
  if (dh == 0) {
    if (oh < 0 || oh > c.length_m) return {};
  } else {
    double h0 = (0 - oh) / dh, h1 = (c.length_m - oh) / dh;
    if (h0 > h1) std::swap(h0, h1);
    t_in = std::max(t_in, h0), t_out = std::min(t_out, h1);
  }
  if (!(t_in < t_out) || !(t_in > 1e-9)) return {};
  double t = t_in;
  if (c.flutes > 0) {
    const double rho_min = c.radius_m - c.flute_depth_m;
    const double g = c.flute_depth_m * 0.5 * c.flutes / rho_min;
    auto implicit = [&](double tt) { return CylinderImplicit(c, CylinderCoords(c, f, Add(o, Scale(d, tt)))); };
    const double lipschitz = 1.2 * std::sqrt(1 + g * g);
    t = MarchImplicit(implicit, t_in, t_out, [lipschitz](double, double f_t) { return f_t / lipschitz; }, 1e-4);
    if (!std::isfinite(t)) return {};
  }
  return {t, Add(o, Scale(d, t))};
}

ElementHit IntersectBlob(const SynthBlob& b, const V3& o, const V3& d) {
  const double t = BlobRayHit(b, o, d);
  if (!std::isfinite(t)) return {};
  return {t, Add(o, Scale(d, t))};
}

ElementHit IntersectElement(const SynthScene& s, int element, const V3& o, const V3& d) {
  const SynthObjects& obj = *s.objects;
  const ElementRef e = Element(obj, element);
  switch (e.kind) {
    case Kind::kPatch:
      return IntersectPatch(s, obj.patches[e.index], o, d);
    case Kind::kBox:
      return IntersectBox(obj.boxes[e.index], o, d);
    case Kind::kCylinder:
      return IntersectCylinder(obj.cylinders[e.index], o, d);
    case Kind::kBlob:
      return IntersectBlob(obj.blobs[e.index], o, d);
  }
  return {};
}

// --- albedo ---

std::array<double, 3> ElementAlbedo(const SynthScene& s, int element, const Local& local, const V3& p) {
  const SynthObjects& o = *s.objects;
  const ElementRef e = Element(o, element);
  SynthMaterial material = SynthMaterial::kConcrete;
  int variant = 0;
  switch (e.kind) {
    case Kind::kPatch:
      material = o.patches[e.index].material;
      break;
    case Kind::kBox:
      material = o.boxes[e.index].material;
      break;
    case Kind::kCylinder:
      material = o.cylinders[e.index].material, variant = o.cylinders[e.index].variant;
      break;
    case Kind::kBlob: {
      const SynthBlob& b = o.blobs[e.index];
      const V3 w = Normalize(Sub(p, b.center_m));
      const double band_u = std::atan2(w[1], w[0]) * b.semi_axes_m[0];
      return MarbleAlbedo(s.seed, p[0], p[1], p[2], BlobGroove(b, w), p[2] - (b.center_m[2] + 0.10), band_u);
    }
  }
  switch (material) {
    case SynthMaterial::kBrick:
      return BrickAlbedo(s.brick, s.seed, element, local.u, local.v);
    case SynthMaterial::kStone:
      return StoneAlbedo(s.floor, s.seed, local.u, local.v);
    case SynthMaterial::kPaint:
      return local.face == 0 ? PaintAlbedo(s.seed, variant, local.u, local.v)
                             : PaintAlbedo(s.seed, variant == 0 ? 1 : variant, local.u, local.v + 5);
    case SynthMaterial::kWood:
      return local.face == 5 ? WoodAlbedo(s.seed, local.u, local.v) : WoodAlbedo(s.seed, local.u + local.v, 0.04);
    case SynthMaterial::kConcrete:
    case SynthMaterial::kMarble:
      break;
  }
  return ConcreteAlbedo(s.seed, p[0], p[1], p[2]);
}

SynthSurface SurfaceKind(const SynthObjects& o, int element) {
  const ElementRef e = Element(o, element);
  if (e.kind != Kind::kPatch) return SynthSurface::kObject;
  return o.patches[e.index].material == SynthMaterial::kBrick ? SynthSurface::kWall : SynthSurface::kFloor;
}

// The element nearest to p (see objects.h: outside all, the smallest
// distance; inside, the deepest containing element).
int NearestElement(const SynthScene& s, const V3& p, Local* local) {
  const int n = ElementCount(*s.objects);
  int best = -1, deepest = -1;
  Local best_local, deepest_local;
  for (int e = 0; e < n; ++e) {
    if (best >= 0 && deepest < 0 && DistanceLowerBound(*s.objects, e, p) >= best_local.distance) continue;
    const Local l = ElementLocal(s, e, p, /*with_normal=*/false);
    if (l.distance < 0) {
      if (deepest < 0 || l.distance < deepest_local.distance) deepest = e, deepest_local = l;
    } else if (best < 0 || l.distance < best_local.distance) {
      best = e, best_local = l;
    }
  }
  const int winner = deepest >= 0 ? deepest : best;
  *local = deepest >= 0 ? deepest_local : best_local;
  const Kind kind = Element(*s.objects, winner).kind;
  if (kind == Kind::kPatch || kind == Kind::kBox) *local = ElementLocal(s, winner, p);
  return winner;
}

}  // namespace

SurfaceSample ObjectsSample(const SynthScene& s, const Vec3& p) {
  Local local;
  const int element = NearestElement(s, p, &local);
  SurfaceSample out;
  out.distance_m = local.distance;
  out.normal = local.normal;
  out.surface = SurfaceKind(*s.objects, element);
  out.wall = out.surface == SynthSurface::kWall ? element : -1;
  out.albedo = ElementAlbedo(s, element, local, local.foot);
  return out;
}

std::optional<SynthHit> ObjectsIntersect(const SynthScene& s, const Vec3& origin, const Vec3& dir) {
  const int n = ElementCount(*s.objects);
  ElementHit best;
  int best_element = -1;
  for (int e = 0; e < n; ++e) {
    const ElementHit h = IntersectElement(s, e, origin, dir);
    if (h.t < best.t) best = h, best_element = e;
  }
  if (best_element < 0) return std::nullopt;
  const Local local = ElementLocal(s, best_element, best.point);
  SynthHit hit;
  hit.t = best.t;
  hit.point = best.point;
  hit.base_normal = local.normal;
  hit.surface = SurfaceKind(*s.objects, best_element);
  hit.wall = hit.surface == SynthSurface::kWall ? best_element : -1;
  hit.part = best_element * 8 + local.face;
  hit.u = local.u, hit.v = local.v;
  return hit;
}

std::array<double, 3> ObjectsHitAlbedo(const SynthScene& s, const SynthHit& hit) {
  Local local;
  local.face = hit.part % 8;
  local.u = hit.u, local.v = hit.v;
  return ElementAlbedo(s, hit.part / 8, local, hit.point);
}

bool ObjectsInside(const SynthScene& s, const Vec3& p) {
  const int n = ElementCount(*s.objects);
  for (int e = 0; e < n; ++e) {
    if (Inside(s, e, p)) return true;
  }
  return false;
}

double ObjectsArea(const SynthObjects& o) {
  double area = 0;
  for (const SynthPatch& p : o.patches) area += p.length_u_m * p.length_v_m;
  for (const SynthBox& b : o.boxes) {
    const double x = b.max_m[0] - b.min_m[0], y = b.max_m[1] - b.min_m[1], z = b.max_m[2] - b.min_m[2];
    area += 2 * (x * y + y * z + z * x);
  }
  for (const SynthCylinder& c : o.cylinders) area += 2 * kPi * c.radius_m * (c.length_m + c.radius_m);
  for (const SynthBlob& b : o.blobs) area += 4 * kPi * std::pow((b.r_min_m + b.r_max_m) / 2, 2);
  return area;
}

void ObjectsBounds(const SynthScene& s, Vec3* min_m, Vec3* max_m) {
  const SynthObjects& o = *s.objects;
  V3 lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
  auto grow = [&](const V3& p, double margin) {
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a] - margin), hi[a] = std::max(hi[a], p[a] + margin);
  };
  const double relief = std::max(s.brick.joint_depth_m, s.floor.unevenness_m + s.floor.stone_offset_m +
                                                            s.floor.joint_depth_m);
  for (const SynthPatch& p : o.patches) {
    for (double a : {0.0, p.length_u_m}) {
      for (double b : {0.0, p.length_v_m}) {
        grow(Add(p.origin_m, Add(Scale(p.axis_u, a), Scale(p.axis_v, b))), relief);
      }
    }
  }
  for (const SynthBox& b : o.boxes) grow(b.min_m, 0), grow(b.max_m, 0);
  for (const SynthCylinder& c : o.cylinders) {
    grow(c.base_m, c.radius_m), grow(Add(c.base_m, Scale(c.axis, c.length_m)), c.radius_m);
  }
  for (const SynthBlob& b : o.blobs) grow(b.center_m, b.r_max_m);
  *min_m = lo, *max_m = hi;
}

Expected<std::vector<Vec3>> ObjectsStations(const SynthObjects& o, int count) {
  const SynthStationRing& ring = o.stations;
  if (count > ring.max_stations) {
    return Status::Invalid("stations: this scene has room for at most " + std::to_string(ring.max_stations) +
                           " stations, got " + std::to_string(count));
  }
  std::vector<Vec3> out;
  for (int k = 0; k < count; ++k) {
    double offset_deg;
    if (ring.full_circle) {
      offset_deg = 360.0 * k / count;
    } else {
      offset_deg = ring.step_deg * ((k + 1) / 2) * (k % 2 == 1 ? 1 : -1);
    }
    const double a = (ring.first_deg + offset_deg) * kPi / 180;
    out.push_back({ring.center_m[0] + ring.radius_m * std::cos(a), ring.center_m[1] + ring.radius_m * std::sin(a),
                   ring.height_m + 0.05 * ((k % 3) - 1)});
  }
  return out;
}

namespace {

struct GridVertex {
  V3 position, normal;
  std::array<double, 3> albedo;
};

// Adds a grid of nu x nv vertices (vertex(i, j)) as quads split in two
// triangles, keeping a cell when keep(i, j) (the cell's lower corner), each
// triangle wound counter-clockwise seen from the side its vertex normals
// point to.
template <typename VertexFn, typename KeepFn>
void AddGrid(int nu, int nv, VertexFn vertex, KeepFn keep, Mesh& mesh) {
  const size_t base = mesh.vertex_count(), count = size_t(nu) * nv;
  mesh.positions.resize(3 * (base + count));
  mesh.normals.resize(3 * (base + count));
  mesh.colors.resize(3 * (base + count));
  tbb::parallel_for(0, nv, [&](int j) {
    for (int i = 0; i < nu; ++i) {
      const GridVertex g = vertex(i, j);
      const size_t k = base + size_t(j) * nu + i;
      for (int c = 0; c < 3; ++c) {
        mesh.positions[3 * k + c] = static_cast<float>(g.position[c]);
        mesh.normals[3 * k + c] = static_cast<float>(g.normal[c]);
        mesh.colors[3 * k + c] = static_cast<uint8_t>(std::lround(std::clamp(g.albedo[c], 0.0, 1.0) * 255));
      }
    }
  });
  std::vector<std::vector<uint32_t>> rows(nv > 0 ? nv - 1 : 0);
  auto pos = [&](size_t k) { return V3{mesh.positions[3 * k], mesh.positions[3 * k + 1], mesh.positions[3 * k + 2]}; };
  auto nrm = [&](size_t k) { return V3{mesh.normals[3 * k], mesh.normals[3 * k + 1], mesh.normals[3 * k + 2]}; };
  tbb::parallel_for(0, std::max(0, nv - 1), [&](int j) {
    for (int i = 0; i + 1 < nu; ++i) {
      if (!keep(i, j)) continue;
      const size_t k00 = base + size_t(j) * nu + i, k10 = k00 + 1, k01 = k00 + nu, k11 = k01 + 1;
      for (const auto& tri : {std::array<size_t, 3>{k00, k10, k11}, std::array<size_t, 3>{k00, k11, k01}}) {
        const V3 area = Cross(Sub(pos(tri[1]), pos(tri[0])), Sub(pos(tri[2]), pos(tri[0])));
        if (Dot(area, area) < 1e-16) continue;  // collapsed (a pole, a cap center)
        const V3 normal = Add(Add(nrm(tri[0]), nrm(tri[1])), nrm(tri[2]));
        const bool flip = Dot(area, normal) < 0;
        rows[j].insert(rows[j].end(), {static_cast<uint32_t>(tri[0]), static_cast<uint32_t>(flip ? tri[2] : tri[1]),
                                       static_cast<uint32_t>(flip ? tri[1] : tri[2])});
      }
    }
  });
  for (const std::vector<uint32_t>& row : rows) mesh.indices.insert(mesh.indices.end(), row.begin(), row.end());
}

// A cell is hidden when the point 1 mm off its center, along its normal, is
// inside another element (a face on the ground, the ground under a box, the
// part of a pipe inside the pump).
bool Hidden(const SynthScene& s, int element, const V3& center, const V3& normal) {
  const V3 probe = Add(center, Scale(Normalize(normal), 0.001));
  const int n = ElementCount(*s.objects);
  for (int e = 0; e < n; ++e) {
    if (e != element && Inside(s, e, probe)) return true;
  }
  return false;
}

int Divisions(double length_m, double cell_m) {
  return std::max(1, static_cast<int>(std::ceil(length_m / cell_m - 1e-9)));
}

void AddPatchMesh(const SynthScene& s, int element, const SynthPatch& p, double cell, Mesh& mesh) {
  const int nu = Divisions(p.length_u_m, cell) + 1, nv = Divisions(p.length_v_m, cell) + 1;
  const V3 n = PatchNormal(p);
  auto at = [&](double u, double v) {
    return Add(p.origin_m, Add(Scale(p.axis_u, u), Scale(p.axis_v, v)));
  };
  auto uv = [&](int i, int j) {
    return std::array<double, 2>{p.length_u_m * i / (nu - 1), p.length_v_m * j / (nv - 1)};
  };
  AddGrid(
      nu, nv,
      [&](int i, int j) {
        const auto [u, v] = uv(i, j);
        const V3 base = at(u, v);
        const Local local = PatchLocal(s, p, base);
        return GridVertex{Add(base, Scale(n, PatchRelief(s, p, u, v))), local.normal,
                          ElementAlbedo(s, element, local, base)};
      },
      [&](int i, int j) {
        const auto [u0, v0] = uv(i, j);
        const auto [u1, v1] = uv(i + 1, j + 1);
        return !Hidden(s, element, at((u0 + u1) / 2, (v0 + v1) / 2), n);
      },
      mesh);
}

void AddBoxMesh(const SynthScene& s, int element, const SynthBox& b, double cell, Mesh& mesh) {
  for (int face = 0; face < 6; ++face) {
    V3 n, tu, tv;
    BoxFaceFrame(face, &n, &tu, &tv);
    const int a = face / 2, ua = (a + 1) % 3, va = (a + 2) % 3;
    const double lu = b.max_m[ua] - b.min_m[ua], lv = b.max_m[va] - b.min_m[va];
    const int nu = Divisions(lu, cell) + 1, nv = Divisions(lv, cell) + 1;
    auto at = [&](double u, double v) {
      V3 p;
      p[a] = face % 2 ? b.max_m[a] : b.min_m[a];
      p[ua] = b.min_m[ua] + u, p[va] = b.min_m[va] + v;
      return p;
    };
    AddGrid(
        nu, nv,
        [&](int i, int j) {
          const double u = lu * i / (nu - 1), v = lv * j / (nv - 1);
          const V3 base = at(u, v);
          Local local;
          local.face = face, local.u = u, local.v = v;
          local.normal = ReliefNormal(n, tu, tv, u, v, [&](double x, double y) { return BoxRelief(b, face, x, y); });
          return GridVertex{Add(base, Scale(n, BoxRelief(b, face, u, v))), local.normal,
                            ElementAlbedo(s, element, local, base)};
        },
        [&](int i, int j) {
          return !Hidden(s, element, at(lu * (i + 0.5) / (nu - 1), lv * (j + 0.5) / (nv - 1)), n);
        },
        mesh);
  }
}

void AddCylinderMesh(const SynthScene& s, int element, const SynthCylinder& c, double cell, Mesh& mesh) {
  const CylFrame f = CylinderFrame(c);
  // At least 8 segments per flute so the flutes are resolved.
  const int segments = std::max({Divisions(2 * kPi * c.radius_m, cell), 8 * c.flutes, 24});
  const int rows = Divisions(c.length_m, cell) + 1, rings = Divisions(c.radius_m, cell) + 1;
  auto radial = [&](double theta) { return Add(Scale(f.e1, std::cos(theta)), Scale(f.e2, std::sin(theta))); };
  auto side_point = [&](double theta, double h, double scale) {
    return Add(c.base_m, Add(Scale(c.axis, h), Scale(radial(theta), scale * (c.radius_m + FluteRelief(c, theta)))));
  };
  auto vertex_at = [&](const V3& p) {
    const Local local = CylinderLocal(c, p);
    return GridVertex{p, local.normal, ElementAlbedo(s, element, local, p)};
  };
  // Side: theta around (the seam vertex repeated), h along.
  AddGrid(
      segments + 1, rows,
      [&](int i, int j) {
        const double theta = 2 * kPi * (i % segments) / segments, h = c.length_m * j / (rows - 1);
        GridVertex g = vertex_at(side_point(theta, h, 1));
        const CylCoords k = CylinderCoords(c, f, g.position);
        Local local;
        local.face = 0, local.u = c.radius_m * theta, local.v = h;
        const V3 t_hat = Add(Scale(f.e1, -std::sin(theta)), Scale(f.e2, std::cos(theta)));
        g.normal = Normalize(Sub(radial(theta), Scale(t_hat, FluteSlope(c, theta) / std::max(k.rho, 1e-9))));
        g.albedo = ElementAlbedo(s, element, local, g.position);
        return g;
      },
      [&](int i, int j) {
        const double theta = 2 * kPi * (i + 0.5) / segments, h = c.length_m * (j + 0.5) / (rows - 1);
        return !Hidden(s, element, side_point(theta, h, 1), radial(theta));
      },
      mesh);
  // Caps: rings from the center out to the (fluted) rim.
  for (int cap = 1; cap <= 2; ++cap) {
    const double h = cap == 1 ? 0 : c.length_m;
    const V3 n = cap == 1 ? Scale(c.axis, -1) : c.axis;
    AddGrid(
        segments + 1, rings,
        [&](int i, int j) {
          const double theta = 2 * kPi * (i % segments) / segments;
          const V3 p = side_point(theta, h, static_cast<double>(j) / (rings - 1));
          const CylCoords k = CylinderCoords(c, f, p);
          Local local;
          local.face = cap, local.u = k.x, local.v = k.y;
          return GridVertex{p, n, ElementAlbedo(s, element, local, p)};
        },
        [&](int i, int j) {
          const double theta = 2 * kPi * (i + 0.5) / segments;
          return !Hidden(s, element, side_point(theta, h, (j + 0.5) / (rings - 1)), n);
        },
        mesh);
  }
}

void AddBlobMesh(const SynthScene& s, int element, const SynthBlob& b, double cell, Mesh& mesh) {
  // A cube sphere: each cube face a grid, directions normalized.
  const int n = Divisions(0.5 * kPi * b.r_max_m, cell) + 1;
  for (int face = 0; face < 6; ++face) {
    const int a = face / 2;
    const double sign = face % 2 ? 1 : -1;
    auto direction = [&](double x, double y) {
      V3 w;
      w[a] = sign, w[(a + 1) % 3] = x, w[(a + 2) % 3] = y;
      return Normalize(w);
    };
    auto surface = [&](const V3& w) { return Add(b.center_m, Scale(w, BlobRadius(b, w))); };
    AddGrid(
        n, n,
        [&](int i, int j) {
          const V3 w = direction(2.0 * i / (n - 1) - 1, 2.0 * j / (n - 1) - 1);
          const V3 p = surface(w);
          Local local;
          return GridVertex{p, Normalize(BlobGradient(b, p)), ElementAlbedo(s, element, local, p)};
        },
        [&](int i, int j) {
          const V3 w = direction(2.0 * (i + 0.5) / (n - 1) - 1, 2.0 * (j + 0.5) / (n - 1) - 1);
          return !Hidden(s, element, surface(w), w);
        },
        mesh);
  }
}

}  // namespace

Mesh ObjectsTruthMesh(const SynthScene& s, double cell_m) {
  const SynthObjects& o = *s.objects;
  Mesh mesh;
  int element = 0;
  for (const SynthPatch& p : o.patches) AddPatchMesh(s, element++, p, cell_m, mesh);
  for (const SynthBox& b : o.boxes) AddBoxMesh(s, element++, b, cell_m, mesh);
  for (const SynthCylinder& c : o.cylinders) AddCylinderMesh(s, element++, c, cell_m, mesh);
  for (const SynthBlob& b : o.blobs) AddBlobMesh(s, element++, b, cell_m, mesh);
  // Drop vertices no triangle uses (hidden cells).
  std::vector<uint32_t> remap(mesh.vertex_count(), UINT32_MAX);
  for (uint32_t index : mesh.indices) remap[index] = 0;
  uint32_t next = 0;
  for (size_t k = 0; k < remap.size(); ++k) {
    if (remap[k] != 0) continue;
    remap[k] = next;
    for (int c = 0; c < 3; ++c) {
      mesh.positions[3 * next + c] = mesh.positions[3 * k + c];
      mesh.normals[3 * next + c] = mesh.normals[3 * k + c];
      mesh.colors[3 * next + c] = mesh.colors[3 * k + c];
    }
    ++next;
  }
  for (uint32_t& index : mesh.indices) index = remap[index];
  mesh.positions.resize(3 * size_t{next});
  mesh.normals.resize(3 * size_t{next});
  mesh.colors.resize(3 * size_t{next});
  return mesh;
}

}  // namespace pb
