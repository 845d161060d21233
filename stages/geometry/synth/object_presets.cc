// The open presets (objects.h) and their JSON description.
//
// facade: the inner corner of two brick facades (3.2 m high, open to the sky
//   and to the two other sides) on a stone-paved yard of 7.5 x 6.5 m, with a
//   pump (a painted cylinder with a motor on top and a pipe into the wall,
//   30 cm in front of it), a wooden bench on two legs 15 cm from the other
//   facade, and a free-standing fluted column with a square capital. Meant to
//   be scanned from ONE station in front: behind the pump, under the bench,
//   behind the column and beyond the edges nothing is scanned, which is where
//   screened Poisson closes the surface with invented membranes.
// sculpture: a carved organic blob (an ellipsoid 0.72 x 0.56 x 1.12 m with
//   nine smooth bumps, a waist and seven spiral grooves 3.5 cm deep, marble with veins,
//   patina in the grooves and a band of painted 3 cm tesserae) on a 0.95 m
//   concrete plinth on a stone-paved ground of 5 x 5 m, scanned by stations
//   on a ring of radius 1.9 m: curved, bumpy relief everywhere, where UV
//   charts fragment.
// Geometry is fixed per preset (the seed changes colors and the ground's
// relief, as for the rooms).
#include <cmath>

#include "stages/geometry/synth/objects.h"
#include "stages/geometry/synth/synth_math.h"

namespace pb {
namespace {

SynthPatch Patch(const Vec3& origin, const Vec3& axis_u, const Vec3& axis_v, double lu, double lv,
                 SynthMaterial material) {
  return {origin, axis_u, axis_v, lu, lv, material};
}

SynthObjects Facade() {
  SynthObjects o;
  // Ground x in [-3, 4.5], y in [-4.5, 2]; facade A at y = 2 facing -y; facade
  // B at x = -3 facing +x, ending at y = -2.5 (its free edge).
  o.patches.push_back(Patch({-3, -4.5, 0}, {1, 0, 0}, {0, 1, 0}, 7.5, 6.5, SynthMaterial::kStone));
  o.patches.push_back(Patch({-3, 2, 0}, {1, 0, 0}, {0, 0, 1}, 7.5, 3.2, SynthMaterial::kBrick));
  o.patches.push_back(Patch({-3, -2.5, 0}, {0, 1, 0}, {0, 0, 1}, 4.5, 3.2, SynthMaterial::kBrick));
  // Bench along facade B: seat and two legs.
  o.boxes.push_back({{-2.85, -1.6, 0.40}, {-2.40, 0.0, 0.46}, SynthMaterial::kWood});
  o.boxes.push_back({{-2.80, -1.50, 0.0}, {-2.45, -1.42, 0.40}, SynthMaterial::kConcrete});
  o.boxes.push_back({{-2.80, -0.18, 0.0}, {-2.45, -0.10, 0.40}, SynthMaterial::kConcrete});
  // The column's capital.
  o.boxes.push_back({{2.0, -0.1, 2.6}, {2.6, 0.5, 2.75}, SynthMaterial::kConcrete});
  // Pump body, motor, pipe into facade A; fluted column.
  o.cylinders.push_back({{-0.8, 1.35, 0}, {0, 0, 1}, 0.35, 1.0, 0, 0, SynthMaterial::kPaint, 0});
  o.cylinders.push_back({{-0.8, 1.35, 1.0}, {0, 0, 1}, 0.22, 0.35, 0, 0, SynthMaterial::kPaint, 1});
  o.cylinders.push_back({{-0.8, 1.35, 0.55}, {0, 1, 0}, 0.07, 0.65, 0, 0, SynthMaterial::kPaint, 2});
  o.cylinders.push_back({{2.3, 0.2, 0}, {0, 0, 1}, 0.22, 2.6, 16, 0.012, SynthMaterial::kConcrete, 0});
  // Station 0 at (0.6, -2.8, 1.5), facing the corner; more on an arc.
  o.stations = {{0.6, 0.2, 0}, 3.0, 1.5, -90, 30, false, 5};
  return o;
}

SynthObjects Sculpture() {
  SynthObjects o;
  o.patches.push_back(Patch({-2.5, -2.5, 0}, {1, 0, 0}, {0, 1, 0}, 5, 5, SynthMaterial::kStone));
  o.boxes.push_back({{-0.32, -0.32, 0}, {0.32, 0.32, 0.95}, SynthMaterial::kConcrete});
  SynthBlob blob;
  blob.center_m = {0, 0, 1.47};
  blob.semi_axes_m = {0.36, 0.28, 0.56};
  auto bump = [&](Vec3 direction, double amplitude, double width) {
    blob.bumps.push_back({synth::Normalize(direction), amplitude, width});
  };
  bump({0.8, 0, 0.45}, 0.22, 0.40);     // shoulders
  bump({-0.8, 0, 0.45}, 0.22, 0.40);
  bump({0, 0.1, 1}, 0.18, 0.30);        // a head
  bump({0.35, -0.9, 0.2}, 0.12, 0.25);  // chest
  bump({-0.35, -0.9, 0.2}, 0.12, 0.25);
  bump({0, 1, 0.1}, -0.10, 0.40);       // a hollow back
  bump({0.6, -0.6, -0.4}, 0.08, 0.15);  // small knots
  bump({-0.7, 0.5, -0.2}, 0.08, 0.15);
  bump({0.2, 0.7, 0.6}, 0.07, 0.12);
  blob.waist_depth = 0.12, blob.waist_z = -0.15, blob.waist_width = 0.25;
  blob.grooves = 7;
  blob.groove_depth_m = 0.035;
  blob.groove_twist = 1.6;
  PrepareBlob(blob);
  o.blobs.push_back(blob);
  o.stations = {{0, 0, 0}, 1.9, 1.75, -90, 0, true, 16};
  return o;
}

const char* MaterialName(SynthMaterial m) {
  switch (m) {
    case SynthMaterial::kBrick:
      return "brick";
    case SynthMaterial::kStone:
      return "stone";
    case SynthMaterial::kPaint:
      return "paint";
    case SynthMaterial::kWood:
      return "wood";
    case SynthMaterial::kConcrete:
      return "concrete";
    case SynthMaterial::kMarble:
      return "marble";
  }
  return "";
}

}  // namespace

bool IsObjectsPreset(const std::string& preset) { return preset == "facade" || preset == "sculpture"; }

std::optional<SynthObjects> MakeObjectsPreset(const std::string& preset) {
  if (preset == "facade") return Facade();
  if (preset == "sculpture") return Sculpture();
  return std::nullopt;
}

nlohmann::json ObjectsToJson(const SynthObjects& o) {
  nlohmann::json patches = nlohmann::json::array(), boxes = nlohmann::json::array();
  nlohmann::json cylinders = nlohmann::json::array(), blobs = nlohmann::json::array();
  for (const SynthPatch& p : o.patches) {
    patches.push_back({{"origin_m", p.origin_m},
                       {"axis_u", p.axis_u},
                       {"axis_v", p.axis_v},
                       {"length_u_m", p.length_u_m},
                       {"length_v_m", p.length_v_m},
                       {"material", MaterialName(p.material)}});
  }
  for (const SynthBox& b : o.boxes) {
    boxes.push_back({{"min_m", b.min_m}, {"max_m", b.max_m}, {"material", MaterialName(b.material)}});
  }
  for (const SynthCylinder& c : o.cylinders) {
    cylinders.push_back({{"base_m", c.base_m},
                         {"axis", c.axis},
                         {"radius_m", c.radius_m},
                         {"length_m", c.length_m},
                         {"flutes", c.flutes},
                         {"flute_depth_m", c.flute_depth_m},
                         {"material", MaterialName(c.material)},
                         {"variant", c.variant}});
  }
  for (const SynthBlob& b : o.blobs) {
    nlohmann::json bumps = nlohmann::json::array();
    for (const SynthBump& k : b.bumps) {
      bumps.push_back({{"direction", k.direction}, {"amplitude", k.amplitude}, {"width", k.width}});
    }
    blobs.push_back({{"center_m", b.center_m},
                     {"semi_axes_m", b.semi_axes_m},
                     {"bumps", bumps},
                     {"grooves", b.grooves},
                     {"groove_depth_m", b.groove_depth_m},
                     {"groove_twist", b.groove_twist},
                     {"waist", {{"depth", b.waist_depth}, {"z", b.waist_z}, {"width", b.waist_width}}},
                     {"material", MaterialName(b.material)}});
  }
  const SynthStationRing& r = o.stations;
  return {{"patches", patches},
          {"boxes", boxes},
          {"cylinders", cylinders},
          {"blobs", blobs},
          {"stations",
           {{"center_m", r.center_m},
            {"radius_m", r.radius_m},
            {"height_m", r.height_m},
            {"first_deg", r.first_deg},
            {"step_deg", r.step_deg},
            {"full_circle", r.full_circle},
            {"max_stations", r.max_stations}}}};
}

}  // namespace pb
