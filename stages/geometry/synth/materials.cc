// Materials of the synthetic scenes (materials.h). The brick and stone
// functions are the rooms' (moved here unchanged, so rooms keep their bytes).
#include "stages/geometry/synth/materials.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "stages/geometry/synth/synth_math.h"

namespace pb {
namespace {

using synth::Hash;
using synth::Key;
using synth::SmoothStep;
using synth::SplitMix64;
using synth::Unit;
using synth::ValueNoise;
using synth::ValueNoise3;

constexpr double kPi = std::numbers::pi;

struct BrickCell {
  int64_t course = 0, index = 0;
  double edge_m = 0;  // distance inside the brick face to its nearest edge; <= 0 in mortar
};

BrickCell LocateBrick(const SynthBrick& b, double u, double v) {
  const double course_h = b.height_m + b.joint_m, cell_len = b.length_m + b.joint_m;
  BrickCell cell;
  cell.course = static_cast<int64_t>(std::floor(v / course_h));
  const double lv = v - static_cast<double>(cell.course) * course_h;
  const double shifted = u + ((cell.course & 1) ? cell_len / 2 : 0);  // running bond
  cell.index = static_cast<int64_t>(std::floor(shifted / cell_len));
  const double lu = shifted - static_cast<double>(cell.index) * cell_len;
  cell.edge_m = std::min({lu - b.joint_m, cell_len - lu, lv - b.joint_m, course_h - lv});
  return cell;
}

struct StoneCell {
  int64_t row = 0, index = 0;
  double edge_m = 0;
};

StoneCell LocateStone(const SynthFloor& f, uint64_t seed, double x, double y) {
  StoneCell cell;
  cell.row = static_cast<int64_t>(std::floor(y / f.stone_width_m));
  const double ly = y - static_cast<double>(cell.row) * f.stone_width_m;
  const double shifted = x + Unit(Hash(seed, 0xF100, Key(cell.row))) * f.stone_length_m;
  cell.index = static_cast<int64_t>(std::floor(shifted / f.stone_length_m));
  const double lx = shifted - static_cast<double>(cell.index) * f.stone_length_m;
  cell.edge_m = std::min({lx - f.joint_m, f.stone_length_m - lx, ly - f.joint_m, f.stone_width_m - ly});
  return cell;
}

double FloorField(const SynthFloor& f, uint64_t seed, double x, double y) {
  const double p1 = 2 * kPi * Unit(Hash(seed, 0xF1E1, 1));
  const double p2 = 2 * kPi * Unit(Hash(seed, 0xF1E1, 2));
  const double p3 = 2 * kPi * Unit(Hash(seed, 0xF1E1, 3));
  return f.unevenness_m * (0.6 * std::sin(2 * kPi * x / 1.7 + p1) * std::sin(2 * kPi * y / 2.3 + p2) +
                           0.4 * std::sin(2 * kPi * (0.6 * x + 0.8 * y) / 3.1 + p3));
}

Albedo3 Clamp01(double r, double g, double b) {
  return {std::clamp(r, 0.0, 1.0), std::clamp(g, 0.0, 1.0), std::clamp(b, 0.0, 1.0)};
}

}  // namespace

double BrickRelief(const SynthBrick& brick, double u, double v) {
  const BrickCell cell = LocateBrick(brick, u, v);
  return -brick.joint_depth_m * (1 - SmoothStep(cell.edge_m / brick.bevel_m));
}

Albedo3 BrickAlbedo(const SynthBrick& brick, uint64_t seed, int wall, double u, double v) {
  const BrickCell cell = LocateBrick(brick, u, v);
  if (cell.edge_m <= 0) {
    const double k = 0.93 + 0.10 * ValueNoise(seed ^ 0x307, u / 0.02, v / 0.02);
    return {0.68 * k, 0.66 * k, 0.62 * k};
  }
  const uint64_t h = Hash(seed, Key(wall + 1), Key(cell.course), Key(cell.index));
  double k = 0.75 + 0.40 * Unit(SplitMix64(h ^ 1));
  if (Unit(SplitMix64(h ^ 2)) < 0.1) k *= 0.65;  // an over-burnt brick
  const double red_shift = 0.10 * (Unit(SplitMix64(h ^ 3)) - 0.5);
  const double yellow_shift = 0.08 * (Unit(SplitMix64(h ^ 4)) - 0.5);
  const double grain = 0.96 + 0.08 * ValueNoise(h, u / 0.03, v / 0.03);
  return {std::clamp((0.62 + red_shift) * k * grain, 0.0, 1.0),
          std::clamp((0.33 + yellow_shift) * k * grain, 0.0, 1.0),
          std::clamp((0.23 + 0.5 * yellow_shift) * k * grain, 0.0, 1.0)};
}

double StoneRelief(const SynthFloor& floor, uint64_t seed, double x, double y) {
  const StoneCell cell = LocateStone(floor, seed, x, y);
  const double stone = floor.stone_offset_m * (2 * Unit(Hash(seed, 0xF200, Key(cell.row), Key(cell.index))) - 1);
  const double face = SmoothStep(cell.edge_m / 0.003);
  return FloorField(floor, seed, x, y) + face * stone - (1 - face) * floor.joint_depth_m;
}

Albedo3 StoneAlbedo(const SynthFloor& floor, uint64_t seed, double x, double y) {
  const StoneCell cell = LocateStone(floor, seed, x, y);
  if (cell.edge_m <= 0) return {0.36, 0.34, 0.31};
  const uint64_t h = Hash(seed, 0xF300, Key(cell.row), Key(cell.index));
  const double k = 0.80 + 0.35 * Unit(SplitMix64(h ^ 1));
  const double warm = 0.06 * (Unit(SplitMix64(h ^ 2)) - 0.5);
  const double grain = 0.95 + 0.10 * ValueNoise(h, x / 0.05, y / 0.05);
  return {std::clamp((0.56 + warm) * k * grain, 0.0, 1.0), std::clamp(0.52 * k * grain, 0.0, 1.0),
          std::clamp((0.46 - warm) * k * grain, 0.0, 1.0)};
}

Albedo3 PlasterAlbedo(uint64_t seed, double u, double v) {
  const double k = 0.97 + 0.05 * ValueNoise(seed ^ 0xCE1, u / 0.5, v / 0.5);
  return {0.88 * k, 0.86 * k, 0.82 * k};
}

Albedo3 PaintAlbedo(uint64_t seed, int variant, double u, double v) {
  static constexpr double kPaint[3][3] = {{0.12, 0.36, 0.44}, {0.55, 0.56, 0.57}, {0.62, 0.13, 0.10}};
  const double* paint = kPaint[std::clamp(variant, 0, 2)];
  const double wear = 0.94 + 0.08 * ValueNoise(seed ^ 0xA11, u / 0.08, v / 0.08);
  double r = paint[0] * wear, g = paint[1] * wear, b = paint[2] * wear;
  // Rust streaks: narrow in u, long in v, strongest low down.
  const double streak = ValueNoise(seed ^ 0x2057, u / 0.02, v / 0.35);
  const double rust = SmoothStep((streak - 0.72) / 0.12) * (0.4 + 0.6 * SmoothStep(1 - v));
  r += rust * (0.45 - r), g += rust * (0.22 - g), b += rust * (0.10 - b);
  if (variant == 0 && v >= 0.55 && v <= 0.70 && u >= 0.2 && u <= 0.9) {
    const double stripe = std::fmod(u + v + 10.0, 0.08);
    if (stripe < 0.04) return {0.85, 0.70, 0.08};
    return {0.06, 0.06, 0.06};
  }
  return Clamp01(r, g, b);
}

double WoodRelief(double u, double v) {
  (void)u;
  constexpr double kGap = 0.008, kDepth = 0.005;
  const double local = v - std::floor(v / kWoodSlatM) * kWoodSlatM;  // [0, slat)
  const double edge = std::min(local - kGap, kWoodSlatM - local);     // <= 0 in the gap
  return -kDepth * (1 - SmoothStep(edge / 0.002));
}

Albedo3 WoodAlbedo(uint64_t seed, double u, double v) {
  const int64_t slat = static_cast<int64_t>(std::floor(v / kWoodSlatM));
  const uint64_t h = Hash(seed, 0x3D00D, Key(slat));
  const double k = 0.80 + 0.30 * Unit(h);
  const double grain = 0.85 + 0.25 * ValueNoise(h, u / 0.25, v / 0.004);
  if (WoodRelief(u, v) < -0.004) return {0.12, 0.09, 0.07};  // dark gap
  return Clamp01(0.52 * k * grain, 0.34 * k * grain, 0.20 * k * grain);
}

Albedo3 ConcreteAlbedo(uint64_t seed, double x, double y, double z) {
  const double cloud = ValueNoise3(seed ^ 0xC0C, x / 0.15, y / 0.15, z / 0.15);
  const double speck = ValueNoise3(seed ^ 0x5BEC, x / 0.006, y / 0.006, z / 0.006);
  double k = 0.88 + 0.14 * cloud;
  if (speck > 0.82) k *= 0.72;
  return Clamp01(0.66 * k, 0.64 * k, 0.60 * k);
}

Albedo3 MarbleAlbedo(uint64_t seed, double x, double y, double z, double groove, double band_coordinate,
                     double band_u) {
  if (std::abs(band_coordinate) < 0.06) {
    // Tesserae: 3 cm cells with 3 mm dark joints, alternating ochre and cream.
    const double cu = band_u / 0.03, cv = (band_coordinate + 0.06) / 0.03;
    const double fu = cu - std::floor(cu), fv = cv - std::floor(cv);
    if (fu < 0.1 || fv < 0.1) return {0.25, 0.20, 0.16};
    const int64_t iu = static_cast<int64_t>(std::floor(cu)), iv = static_cast<int64_t>(std::floor(cv));
    const double k = 0.92 + 0.12 * Unit(Hash(seed, 0x7E55, Key(iu), Key(iv)));
    if ((iu + iv) % 2 == 0) return Clamp01(0.78 * k, 0.48 * k, 0.16 * k);
    return Clamp01(0.90 * k, 0.86 * k, 0.74 * k);
  }
  const double turbulence = ValueNoise3(seed ^ 0x3A, x / 0.08, y / 0.08, z / 0.08) +
                            0.5 * ValueNoise3(seed ^ 0x3B, x / 0.03, y / 0.03, z / 0.03);
  const double vein = std::pow(std::abs(std::sin(2 * kPi * (x + 0.6 * z) / 0.11 + 5 * turbulence)), 30.0);
  double r = 0.86, g = 0.78, b = 0.68;  // warm marble
  r -= 0.30 * vein, g -= 0.30 * vein, b -= 0.24 * vein;
  const double patina = 0.7 * SmoothStep(1.5 * groove);
  return Clamp01(r * (1 - patina) + 0.20 * patina, g * (1 - patina) + 0.24 * patina,
                 b * (1 - patina) + 0.16 * patina);
}

}  // namespace pb
