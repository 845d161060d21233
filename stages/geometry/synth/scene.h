// SynthScene: an analytic scanned room with exact ground truth, the stand-in
// for the paper's castle scans (D11v3 interior room, NETower round tower, D31
// room), which are not public. See DESIGN.md "Synthetic scenes".
//
// Frame: meters, z up, the floor's base plane at z = 0, the room centered on
// the z axis. Shapes:
//   kBox    walls x = ±width/2, y = ±depth/2, flat ceiling at z = height.
//   kVault  the box with a semicircular barrel vault along x: side walls
//           (y = ±depth/2) rise to the springing line z = height - depth/2,
//           the vault is y² + (z - springing)² = (depth/2)², crown at
//           z = height; end walls (x = ±width/2) are lunettes up to the vault.
//   kTower  a round wall of radius width/2 (width == depth), flat ceiling.
// Walls are indexed: box/vault 0: y = -depth/2, 1: x = +width/2,
// 2: y = +depth/2, 3: x = -width/2 (counter-clockwise seen from above); the
// tower has one wall, 0. On wall k the surface coordinates are u = meters
// along the wall from its start corner (counter-clockwise; the tower starts at
// angle 0 on +x) and v = z.
//
// Surfaces and their relief (meters along the inward normal, i.e. toward the
// room's inside; 0 = the base surface):
//   walls: brick in running bond; brick faces at 0, mortar joints recessed by
//          brick.joint_depth_m with a small bevel at brick edges;
//   floor: stone flags in rows, joints recessed by floor.joint_depth_m, plus a
//          low-frequency height field and a per-stone offset (|relief| <= 1 cm);
//   ceiling / vault: smooth plaster (relief 0).
// Openings (doors, windows) are holes in a wall: nothing lies behind them, so
// a ray through one returns nothing. Reveals (the wall's thickness inside an
// opening) are not modeled: the wall is its inner face.
//
// Displaced surfaces: Intersect() hits the *base* surface, then moves the hit
// along the base normal by the relief there. The returned point therefore lies
// exactly on the true (displaced) surface, but up to |relief| * sin(incidence)
// (< 4 mm) off the ray; occlusion by relief (a brick edge shadowing a joint)
// is not modeled. SampleSurface() uses the same convention, so the distance
// of an Intersect() point is 0.
//
// Albedo: sRGB-encoded reflectance in [0, 1] per channel (the value a color
// camera would record under uniform white light), an analytic function of
// the 3-D point: per-brick colors hashed from (seed, wall, course, brick),
// gray mortar, per-stone floor colors, off-white plaster.
#pragma once

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/mesh.h"

namespace pb {

using Vec3 = std::array<double, 3>;

enum class SynthShape { kBox, kVault, kTower, kObjects };

struct SynthObjects;  // open scenes (objects.h)

// A door or window: a rectangle in a wall's (u, v) coordinates.
struct SynthOpening {
  std::string kind = "window";  // "door" or "window" (informative)
  int wall = 0;                 // wall index (see above)
  double center_u_m = 0;        // center along the wall, meters
  double sill_m = 0;            // bottom edge, meters above the floor base
  double width_m = 1;
  double height_m = 1;
};

struct SynthBrick {
  double length_m = 0.215;   // brick face, without joint
  double height_m = 0.065;
  double joint_m = 0.010;    // mortar joint width
  double joint_depth_m = 0.004;
  double bevel_m = 0.002;    // rounded brick edge
};

struct SynthFloor {
  double stone_length_m = 0.60;  // along x
  double stone_width_m = 0.40;   // along y (row width)
  double joint_m = 0.008;
  double joint_depth_m = 0.003;
  double unevenness_m = 0.007;    // amplitude of the low-frequency height field
  double stone_offset_m = 0.003;  // amplitude of the per-stone height offset
};

struct SynthScene {
  std::string preset;  // "room", "tower", "vault", "facade", "sculpture" or "" (custom)
  uint64_t seed = 1;   // colors and floor relief
  SynthShape shape = SynthShape::kBox;
  double width_m = 6.0;   // x extent (tower: diameter)
  double depth_m = 4.5;   // y extent (tower: diameter)
  double height_m = 3.2;  // floor base to ceiling (vault: to the crown)
  SynthBrick brick;
  SynthFloor floor;
  std::vector<SynthOpening> openings;
  // kObjects (presets "facade", "sculpture"): the elements; the dimensions
  // above are then the extent of the scene's bounds, informative only.
  std::shared_ptr<const SynthObjects> objects;
};

// Surface ids reported by Intersect and SampleSurface.
// Open scenes: brick facades are kWall, the ground kFloor, everything else
// (boxes, cylinders, blobs) kObject.
enum class SynthSurface { kWall, kFloor, kCeiling, kVault, kObject };

struct SurfaceSample {
  std::array<double, 3> albedo{};  // sRGB-encoded, [0, 1]
  Vec3 normal{};                   // true unit normal (relief included), into the room (open scenes: outward)
  double distance_m = 0;           // signed distance to the true surface, > 0 inside the room (open: outside)
  SynthSurface surface = SynthSurface::kWall;
  int wall = -1;                   // wall index for kWall, else -1
  bool in_opening = false;         // the nearest surface point is inside a door/window
};

struct SynthHit {
  double t = 0;       // ray parameter of the base-surface hit (dir is unit: meters)
  Vec3 point{};       // on the true surface (base hit moved by the relief)
  Vec3 base_normal{};  // unit, into the room
  SynthSurface surface = SynthSurface::kWall;
  int wall = -1;
  double u = 0, v = 0;  // surface coordinates of the base hit (floor/ceiling: x, y)
  int part = -1;        // open scenes: element * 8 + face (objects.h)
};

// The presets: "room" (6 x 4.5 x 3.2 m box, a door and two windows),
// "tower" (round, radius 3 m, height 6 m, a door and four slit windows),
// "vault" (7 x 4.5 m, springing 2.6 m, crown 4.85 m, a door and two
// windows). `size_m` (width, depth, height) overrides the dimensions; openings
// keep their size and their relative place along the wall, and are shrunk to
// fit small walls. The open presets (objects.h): "facade" (two brick facades
// meeting in a corner on a paved yard, open to the sky and the sides, with a
// pump, a bench and a fluted column, for one station in front) and
// "sculpture" (a carved blob on a plinth, stations around it); they take no
// size_m. Status::Invalid for an unknown preset or unusable size.
Expected<SynthScene> MakeSynthScene(const std::string& preset, uint64_t seed,
                                    const std::optional<Vec3>& size_m = std::nullopt);

// scene.json: {"format": "pointbake synthetic scene", "version": 1, "preset",
// "seed", "shape": "box"|"vault"|"tower", "size_m": [w, d, h], "brick": {...},
// "floor": {...}, "openings": [{"kind", "wall", "center_u_m", "sill_m",
// "width_m", "height_m"}]} with the field names of the structs above. Open
// presets: "shape": "objects" and "objects": their elements (objects.h's
// ObjectsToJson); reading rebuilds the preset and rejects a file whose
// elements differ from it (edited element lists are not supported).
inline constexpr int kSynthSceneVersion = 1;
nlohmann::json ToJson(const SynthScene& scene);
// Validates everything (errors name the key, e.g. "openings[1].width_m: must
// be > 0"); missing brick/floor fields take the defaults above.
Expected<SynthScene> SynthSceneFromJson(const nlohmann::json& json);
// Reads scene.json; errors are prefixed with the path.
Expected<SynthScene> ReadSynthScene(const std::string& path);

// Length of wall `wall` along u, and its top z at u (vault end walls are
// lunettes; otherwise height or the springing line).
double WallLength(const SynthScene& scene, int wall);
double WallTop(const SynthScene& scene, int wall, double u_m);
int WallCount(const SynthScene& scene);
// Axis-aligned box containing every surface point, relief included.
void SceneBounds(const SynthScene& scene, Vec3* min_m, Vec3* max_m);

// Ground truth at any 3-D point: the nearest surface's albedo and true normal
// at the point's projection, and the signed distance to the true surface.
// Meaningful inside the room and within a few centimeters of its surfaces;
// open scenes: anywhere (exactness in objects.h).
SurfaceSample SampleSurface(const SynthScene& scene, const Vec3& point);

// First surface hit by the ray origin + t * dir (dir unit length, origin
// inside the room; open scenes: outside every object), or nullopt if the ray
// leaves through an opening or into the sky.
std::optional<SynthHit> Intersect(const SynthScene& scene, const Vec3& origin, const Vec3& dir);
// The albedo at a hit (cheaper than SampleSurface: no nearest-surface search).
std::array<double, 3> HitAlbedo(const SynthScene& scene, const SynthHit& hit);

// The true surface as a triangle mesh: each surface tessellated on a grid of
// `cell_m` (opening edges kept exact), vertices displaced by the relief, with
// true normals and albedo colors (sRGB bytes) per vertex; triangles face into
// the room. Relief finer than cell_m (mortar joints at 10 mm cells) is
// aliased: evaluate SampleSurface for exact values.
Mesh SynthTruthMesh(const SynthScene& scene, double cell_m);

}  // namespace pb
