// Surface materials of the synthetic scenes: relief (meters along the
// surface's outward/visible normal, 0 = the base surface) and albedo
// (sRGB-encoded reflectance in [0, 1] per channel), analytic functions of
// surface coordinates or of the 3-D point. Shared by the rooms (scene.cc) and
// the open scenes built from objects (objects.cc). Every value is a pure
// function of its arguments (hashes of the seed, no random state).
//
// Coordinates: (u, v) are meters along the surface's two tangents (walls: u
// along the wall, v = height; floors: x, y); 3-D points are meters.
#pragma once

#include <array>
#include <cstdint>

#include "stages/geometry/synth/scene.h"

namespace pb {

using Albedo3 = std::array<double, 3>;

// Brick in running bond: faces at 0, joints recessed by joint_depth_m with a
// bevel of bevel_m. `wall` decorrelates the bricks of different walls.
double BrickRelief(const SynthBrick& brick, double u, double v);
Albedo3 BrickAlbedo(const SynthBrick& brick, uint64_t seed, int wall, double u, double v);
// Stone flags in rows along x, recessed joints, a low-frequency height field
// and a per-stone offset.
double StoneRelief(const SynthFloor& floor, uint64_t seed, double x, double y);
Albedo3 StoneAlbedo(const SynthFloor& floor, uint64_t seed, double x, double y);
// Off-white plaster, no relief.
Albedo3 PlasterAlbedo(uint64_t seed, double u, double v);

// Painted steel (the pump): `variant` picks the paint (0 blue-green, 1 gray,
// 2 red); rust streaks running down, and on variant 0 a band of yellow and
// black warning stripes (4 cm) at v in [0.55, 0.70] m over a third of the
// circumference. u: meters around, v: meters up.
Albedo3 PaintAlbedo(uint64_t seed, int variant, double u, double v);
// Wooden slats (the bench): slats `kWoodSlatM` wide along u, separated by
// 8 mm gaps 5 mm deep; grain along u.
inline constexpr double kWoodSlatM = 0.095;
double WoodRelief(double u, double v);
Albedo3 WoodAlbedo(uint64_t seed, double u, double v);
// Concrete / limestone: speckled light gray, 3-D point.
Albedo3 ConcreteAlbedo(uint64_t seed, double x, double y, double z);
// The sculpture's stone: warm marble with veins (3-D point), darkened by a
// patina in carved grooves (`groove` in [0, 1]: 1 at a groove's bottom), and
// a painted band of 3 cm ochre/cream tesserae where |band_coordinate| < 0.06.
Albedo3 MarbleAlbedo(uint64_t seed, double x, double y, double z, double groove, double band_coordinate,
                     double band_u);

}  // namespace pb
