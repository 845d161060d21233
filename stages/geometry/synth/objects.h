// Open synthetic scenes built from analytic elements (presets "facade" and
// "sculpture"): what the closed rooms of scene.h lack. Real scans are not
// boxes seen from inside; they are scanned from one side, with open sides and
// unscanned space behind and under objects (where Poisson invents surface),
// and they hold curved, carved objects (where UV charts fragment).
//
// Elements (meters, z up; each is solid, the true surface is the boundary of
// their union):
//   patch     a one-sided rectangle origin + s*axis_u + t*axis_v, s in
//             [0, length_u], t in [0, length_v]; the visible side is
//             axis_u x axis_v. The ground and facades; the kPatchMassM behind
//             it count as solid (walls and ground have mass), so faces of
//             other elements lying on a patch are hidden.
//   box       axis-aligned; faces 0..5 = -x, +x, -y, +y, -z, +z.
//   cylinder  capped, base center + axis * [0, length]; faces 0 side, 1 base
//             cap, 2 far cap; optional flutes (rounded grooves carved along
//             the axis) of depth flute_depth_m.
//   blob      star-shaped about its center: radius along the unit direction w
//             R(w) = E(w) (1 + sum_k a_k K((1 - w.c_k) / s_k^2)) W(w) - G(w),
//             K(x) = (1 - x/4)^4 for x < 4, else 0 (an exp(-x) with compact
//             support), E the ellipsoid of semi-axes `semi_axes_m`, W a waist
//             1 - depth K(((w_z - z) / width)^2), G carved
//             spiral grooves (count, depth, twist; profile cos^4), fading
//             toward the poles.
//
// Exactness (the ground truth): ray hits are on the ray and on the true
// surface (patches and boxes: the base surface moved by the relief along its
// normal, the rooms' convention, scene.h; smooth cylinders: exact; fluted
// cylinders and blobs: ray marching with a Lipschitz bound, then regula falsi
// to 1e-9 m). Distances: patches and boxes as the rooms (distance along the
// normal to the displaced surface); cylinders exact, fluted ones to first
// order (error < 1e-4 m within 1 cm of the surface); blobs by a descent to
// the closest surface point from two starts (the gradient's and the radial
// foot): exact (< 2e-6 m) where the point is nearer than the local radius of
// curvature (>= 2 mm in the grooves); farther, the nearer of two local
// closest points, which a concave groove can make an overestimate. Outside all
// elements the distance to their union is the minimum over the elements
// (exact); inside, the distance to the boundary of the deepest containing
// element (exact except within that distance of a joint between elements).
// Normals: the gradient of the element's implicit function (finite
// differences of the relief over 2e-4 m / 1e-5 rad, as the rooms).
#pragma once

#include <array>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/mesh.h"
#include "stages/geometry/synth/scene.h"

namespace pb {

inline constexpr double kPatchMassM = 0.3;

enum class SynthMaterial { kBrick, kStone, kPaint, kWood, kConcrete, kMarble };

struct SynthPatch {
  Vec3 origin_m{}, axis_u{}, axis_v{};  // axes unit and orthogonal
  double length_u_m = 1, length_v_m = 1;
  SynthMaterial material = SynthMaterial::kStone;
};

struct SynthBox {
  Vec3 min_m{}, max_m{};
  SynthMaterial material = SynthMaterial::kConcrete;
};

struct SynthCylinder {
  Vec3 base_m{};
  Vec3 axis{0, 0, 1};  // unit
  double radius_m = 0.1, length_m = 1;
  int flutes = 0;
  double flute_depth_m = 0;
  SynthMaterial material = SynthMaterial::kPaint;
  int variant = 0;  // paint color (materials.h)
};

struct SynthBump {
  Vec3 direction{};       // unit
  double amplitude = 0;   // relative to E(w)
  double width = 0.3;     // s_k, radians (about)
};

struct SynthBlob {
  Vec3 center_m{};
  Vec3 semi_axes_m{0.3, 0.3, 0.5};
  std::vector<SynthBump> bumps;
  int grooves = 0;
  double groove_depth_m = 0;
  double groove_twist = 0;  // radians of turn per unit of w_z
  // A waist: the radius times (1 - waist_depth K(((w_z - waist_z) / waist_width)^2)).
  double waist_depth = 0, waist_z = 0, waist_width = 0.2;
  SynthMaterial material = SynthMaterial::kMarble;
  // Derived by the preset (not in scene.json's description of the shape):
  // radius bounds and the Lipschitz bound of |p - c| - R(w) used to march rays.
  double r_min_m = 0, r_max_m = 0, lipschitz = 1;
  double bound_scale = 1;  // max R(w) / E(w): the blob lies in E scaled by this
  // Lipschitz bounds per direction cell of a cube map (6 x n x n), each the
  // bound over the directions within 0.12 rad of the cell's center: rays
  // march with it in steps up to 0.05 |p - c| (so they stay in that cone).
  int cube_cells = 0;
  std::vector<float> local_lipschitz;
};

// Scanner stations on a ring around `center_m` at ~height_m: station k at
// azimuth first_deg + offset_k. `full_circle`: offsets 360 k / count;
// else 0, +step, -step, +2 step, -2 step, ... up to max_stations.
struct SynthStationRing {
  Vec3 center_m{};
  double radius_m = 3, height_m = 1.5, first_deg = -90, step_deg = 30;
  bool full_circle = false;
  int max_stations = 16;
};

struct SynthObjects {
  std::vector<SynthPatch> patches;
  std::vector<SynthBox> boxes;
  std::vector<SynthCylinder> cylinders;
  std::vector<SynthBlob> blobs;
  SynthStationRing stations;
};

// Fills a blob's derived r_min_m, r_max_m, bound_scale, local_lipschitz
// and lipschitz (of |p - c| - R(w)
// outside the blob: sqrt(1 + max |grad_T R| / R)^2)) from 40,000 directions
// (with margins: 3 % on the radii, 1.25x on the slope; the directions are
// 0.018 rad apart, the narrowest feature ~0.1 rad wide).
void PrepareBlob(SynthBlob& blob);

// "facade" or "sculpture"; nullopt for other names.
std::optional<SynthObjects> MakeObjectsPreset(const std::string& preset);
bool IsObjectsPreset(const std::string& preset);
// The elements as JSON (scene.json's "objects"; see scene.h).
nlohmann::json ObjectsToJson(const SynthObjects& objects);

// The queries of scene.h for a scene with `objects` (shape kObjects); the
// scene supplies the seed and the brick and stone parameters.
SurfaceSample ObjectsSample(const SynthScene& scene, const Vec3& point);
std::optional<SynthHit> ObjectsIntersect(const SynthScene& scene, const Vec3& origin, const Vec3& dir);
std::array<double, 3> ObjectsHitAlbedo(const SynthScene& scene, const SynthHit& hit);
Mesh ObjectsTruthMesh(const SynthScene& scene, double cell_m);
void ObjectsBounds(const SynthScene& scene, Vec3* min_m, Vec3* max_m);
// Whether p is inside an element's solid (patches: within their mass),
// relief ignored; the truth mesh hides the cells whose outside lies in one.
bool ObjectsInside(const SynthScene& scene, const Vec3& p);
// Total area of the elements' surfaces (hidden parts included), m^2.
double ObjectsArea(const SynthObjects& objects);
// Status::Invalid when count exceeds the ring's max_stations.
Expected<std::vector<Vec3>> ObjectsStations(const SynthObjects& objects, int count);

}  // namespace pb
