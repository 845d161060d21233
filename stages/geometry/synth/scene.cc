// The analytic synthetic scene (synth_scene.h): presets, scene.json, surface
// frames, relief, albedo, ray intersection and the truth mesh.
//
// Modeled on the paper's scanned rooms (interior room D11v3, round tower
// NETower, room D31: brick walls, stone floors, openings). Departures: walls
// have no thickness (no reveals in openings), relief is a displacement along
// the base normal (see the header), and nothing exists outside the room.
#include "stages/geometry/synth/scene.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>

#include "stages/geometry/synth/materials.h"
#include "stages/geometry/synth/objects.h"
#include "stages/geometry/synth/synth_math.h"

namespace pb {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();

using synth::Add;
using synth::Cross;
using synth::Dot;
using synth::Normalize;
using synth::Scale;
using synth::Sub;

// --- scene dimensions ---

double Radius(const SynthScene& s) { return s.width_m / 2; }
double Springing(const SynthScene& s) { return s.height_m - s.depth_m / 2; }

// Local frame of a surface at (u, v): base point, unit inward normal and unit
// tangents along u and v.
struct Frame {
  Vec3 base, normal, tangent_u, tangent_v;
};

Frame SurfaceFrame(const SynthScene& s, SynthSurface surface, int wall, double u, double v) {
  const double hw = s.width_m / 2, hd = s.depth_m / 2;
  switch (surface) {
    case SynthSurface::kFloor:
      return {{u, v, 0}, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}};
    case SynthSurface::kCeiling:
      return {{u, v, s.height_m}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0}};
    case SynthSurface::kVault: {
      const double r = hd, phi = v / r;
      return {{u, -r * std::cos(phi), Springing(s) + r * std::sin(phi)},
              {0, std::cos(phi), -std::sin(phi)},
              {1, 0, 0},
              {0, std::sin(phi), std::cos(phi)}};
    }
    case SynthSurface::kWall:
    case SynthSurface::kObject:  // open scenes have their own frames (objects.cc)
      break;
  }
  if (s.shape == SynthShape::kTower) {
    const double r = Radius(s), theta = u / r;
    const double c = std::cos(theta), sn = std::sin(theta);
    return {{r * c, r * sn, v}, {-c, -sn, 0}, {-sn, c, 0}, {0, 0, 1}};
  }
  switch (wall) {
    case 0:
      return {{-hw + u, -hd, v}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}};
    case 1:
      return {{hw, -hd + u, v}, {-1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    case 2:
      return {{hw - u, hd, v}, {0, -1, 0}, {-1, 0, 0}, {0, 0, 1}};
    default:
      return {{-hw, hd - u, v}, {1, 0, 0}, {0, -1, 0}, {0, 0, 1}};
  }
}

// --- relief (meters along the inward normal) and albedo per surface ---

double Relief(const SynthScene& s, SynthSurface surface, double u, double v) {
  if (surface == SynthSurface::kWall) return BrickRelief(s.brick, u, v);
  if (surface == SynthSurface::kFloor) return StoneRelief(s.floor, s.seed, u, v);
  return 0;  // plaster
}

std::array<double, 3> Albedo(const SynthScene& s, SynthSurface surface, int wall, double u, double v) {
  if (surface == SynthSurface::kWall) return BrickAlbedo(s.brick, s.seed, wall, u, v);
  if (surface == SynthSurface::kFloor) return StoneAlbedo(s.floor, s.seed, u, v);
  return PlasterAlbedo(s.seed, u, v);
}

bool InOpening(const SynthScene& s, int wall, double u, double v) {
  const double tower_circumference = 2 * kPi * Radius(s);
  for (const SynthOpening& o : s.openings) {
    if (o.wall != wall) continue;
    double du = u - o.center_u_m;
    if (s.shape == SynthShape::kTower) du = std::remainder(du, tower_circumference);
    if (std::abs(du) <= o.width_m / 2 && v >= o.sill_m && v <= o.sill_m + o.height_m) return true;
  }
  return false;
}

// True normal: the base normal tilted by the relief gradient (central
// differences; curvature of the tower and vault is negligible at 0.2 mm).
Vec3 TrueNormal(const SynthScene& s, SynthSurface surface, const Frame& frame, double u, double v) {
  if (surface == SynthSurface::kCeiling || surface == SynthSurface::kVault) return frame.normal;
  constexpr double kStep = 2e-4;
  const double du = (Relief(s, surface, u + kStep, v) - Relief(s, surface, u - kStep, v)) / (2 * kStep);
  const double dv = (Relief(s, surface, u, v + kStep) - Relief(s, surface, u, v - kStep)) / (2 * kStep);
  return Normalize(Sub(frame.normal, Add(Scale(frame.tangent_u, du), Scale(frame.tangent_v, dv))));
}

// --- JSON helpers ---

Status ReadNumber(const nlohmann::json& obj, const std::string& where, const char* key, double* out,
                  bool required, double min_exclusive = -kInf) {
  auto it = obj.find(key);
  if (it == obj.end()) {
    if (required) return Status::Invalid(where + key + ": missing");
    return Status::Ok();
  }
  if (!it->is_number()) return Status::Invalid(where + key + ": expected a number, got " + it->dump());
  const double value = it->get<double>();
  if (!std::isfinite(value) || value <= min_exclusive) {
    return Status::Invalid(where + key + ": must be > " + std::to_string(min_exclusive) + ", got " +
                           it->dump());
  }
  *out = value;
  return Status::Ok();
}

const char* ShapeName(SynthShape shape) {
  switch (shape) {
    case SynthShape::kBox:
      return "box";
    case SynthShape::kVault:
      return "vault";
    case SynthShape::kTower:
      return "tower";
    case SynthShape::kObjects:
      break;
  }
  return "objects";
}

// An open preset (objects.h): the elements, and the extent as the size.
Expected<SynthScene> MakeObjectsScene(const std::string& preset, uint64_t seed) {
  SynthScene scene;
  scene.preset = preset;
  scene.seed = seed;
  scene.shape = SynthShape::kObjects;
  std::optional<SynthObjects> objects = MakeObjectsPreset(preset);
  if (!objects) return Status::Invalid("unknown open scene preset '" + preset + "'");
  scene.objects = std::make_shared<const SynthObjects>(std::move(*objects));
  Vec3 lo, hi;
  ObjectsBounds(scene, &lo, &hi);
  scene.width_m = hi[0] - lo[0], scene.depth_m = hi[1] - lo[1], scene.height_m = hi[2] - lo[2];
  return scene;
}

// Keeps openings inside their walls after a size override.
void FitOpenings(SynthScene& scene) {
  for (SynthOpening& o : scene.openings) {
    const double length = WallLength(scene, o.wall);
    const double top = WallTop(scene, o.wall, o.center_u_m);
    o.width_m = std::min(o.width_m, 0.8 * length);
    o.center_u_m = std::clamp(o.center_u_m, o.width_m / 2 + 0.05, length - o.width_m / 2 - 0.05);
    o.height_m = std::min(o.height_m, 0.8 * top);
    o.sill_m = std::min(o.sill_m, top - o.height_m - 0.1);
    o.sill_m = std::max(o.sill_m, 0.0);
  }
}

}  // namespace

int WallCount(const SynthScene& scene) {
  if (scene.objects) return 0;
  return scene.shape == SynthShape::kTower ? 1 : 4;
}

double WallLength(const SynthScene& scene, int wall) {
  if (scene.shape == SynthShape::kTower) return 2 * kPi * Radius(scene);
  return (wall % 2 == 0) ? scene.width_m : scene.depth_m;
}

double WallTop(const SynthScene& scene, int wall, double u_m) {
  if (scene.shape != SynthShape::kVault) return scene.height_m;
  if (wall % 2 == 0) return Springing(scene);
  const double r = scene.depth_m / 2, y = u_m - r;  // end walls run along y
  return Springing(scene) + std::sqrt(std::max(0.0, r * r - y * y));
}

void SceneBounds(const SynthScene& scene, Vec3* min_m, Vec3* max_m) {
  if (scene.objects) return ObjectsBounds(scene, min_m, max_m);
  const double floor_low = scene.floor.unevenness_m + scene.floor.stone_offset_m + scene.floor.joint_depth_m;
  const double wall_out = scene.brick.joint_depth_m;
  *min_m = {-scene.width_m / 2 - wall_out, -scene.depth_m / 2 - wall_out, -floor_low};
  *max_m = {scene.width_m / 2 + wall_out, scene.depth_m / 2 + wall_out, scene.height_m};
}

Expected<SynthScene> MakeSynthScene(const std::string& preset, uint64_t seed, const std::optional<Vec3>& size_m) {
  if (IsObjectsPreset(preset)) {
    if (size_m) return Status::Invalid("size_m: preset '" + preset + "' has a fixed size");
    return MakeObjectsScene(preset, seed);
  }
  SynthScene scene;
  scene.preset = preset;
  scene.seed = seed;
  if (preset == "room") {
    scene.shape = SynthShape::kBox;
    scene.width_m = 6.0, scene.depth_m = 4.5, scene.height_m = 3.2;
  } else if (preset == "tower") {
    scene.shape = SynthShape::kTower;
    scene.width_m = 6.0, scene.depth_m = 6.0, scene.height_m = 6.0;
  } else if (preset == "vault") {
    scene.shape = SynthShape::kVault;
    scene.width_m = 7.0, scene.depth_m = 4.5, scene.height_m = 4.85;
  } else {
    return Status::Invalid("unknown synthetic scene preset '" + preset +
                           "' (expected room, tower, vault, facade or sculpture)");
  }
  if (size_m) {
    scene.width_m = (*size_m)[0], scene.depth_m = (*size_m)[1], scene.height_m = (*size_m)[2];
  }
  // Openings at relative places, then validated/fitted below.
  auto add = [&](const char* kind, int wall, double fraction, double sill, double width, double height) {
    scene.openings.push_back({kind, wall, fraction * WallLength(scene, wall), sill, width, height});
  };
  if (scene.shape == SynthShape::kTower) {
    if (scene.width_m != scene.depth_m) {
      return Status::Invalid("tower: size_m width and depth are the diameter and must be equal, got " +
                             std::to_string(scene.width_m) + " and " + std::to_string(scene.depth_m));
    }
    add("door", 0, 0.75, 0.0, 1.0, 2.1);
    add("window", 0, 0.05, 1.2, 0.15, 1.1);
    add("window", 0, 0.30, 1.4, 0.15, 1.1);
    add("window", 0, 0.50, 3.6, 0.15, 1.2);
    add("window", 0, 0.95, 3.8, 0.15, 1.2);
  } else {
    add("door", 0, 0.25, 0.0, 0.9, 2.05);
    add("window", 2, 0.30, 0.9, 1.0, 1.3);
    add("window", scene.shape == SynthShape::kVault ? 1 : 2, scene.shape == SynthShape::kVault ? 0.5 : 0.72,
        0.9, 1.0, 1.3);
  }
  if (!(scene.width_m > 0.5 && scene.depth_m > 0.5 && scene.height_m > 0.5) ||
      (scene.shape == SynthShape::kVault && Springing(scene) < 0.5)) {
    return Status::Invalid("size_m: room too small or vault crown below depth/2 + 0.5 m");
  }
  FitOpenings(scene);
  // Round trip through the validator so presets obey the same rules as files.
  return SynthSceneFromJson(ToJson(scene));
}

nlohmann::json ToJson(const SynthScene& s) {
  nlohmann::json openings = nlohmann::json::array();
  for (const SynthOpening& o : s.openings) {
    openings.push_back({{"kind", o.kind},
                        {"wall", o.wall},
                        {"center_u_m", o.center_u_m},
                        {"sill_m", o.sill_m},
                        {"width_m", o.width_m},
                        {"height_m", o.height_m}});
  }
  nlohmann::json j = {{"format", "pointbake synthetic scene"},
                      {"version", kSynthSceneVersion},
                      {"preset", s.preset},
                      {"seed", s.seed},
                      {"shape", ShapeName(s.shape)},
                      {"size_m", {s.width_m, s.depth_m, s.height_m}},
                      {"brick",
                       {{"length_m", s.brick.length_m},
                        {"height_m", s.brick.height_m},
                        {"joint_m", s.brick.joint_m},
                        {"joint_depth_m", s.brick.joint_depth_m},
                        {"bevel_m", s.brick.bevel_m}}},
                      {"floor",
                       {{"stone_length_m", s.floor.stone_length_m},
                        {"stone_width_m", s.floor.stone_width_m},
                        {"joint_m", s.floor.joint_m},
                        {"joint_depth_m", s.floor.joint_depth_m},
                        {"unevenness_m", s.floor.unevenness_m},
                        {"stone_offset_m", s.floor.stone_offset_m}}}};
  // An open scene carries its elements, a room its openings.
  if (s.objects) {
    j["objects"] = ObjectsToJson(*s.objects);
  } else {
    j["openings"] = openings;
  }
  return j;
}

Expected<SynthScene> SynthSceneFromJson(const nlohmann::json& j) {
  if (!j.is_object()) return Status::Invalid("synthetic scene: expected a JSON object");
  if (j.value("format", std::string()) != "pointbake synthetic scene") {
    return Status::Invalid("format: expected \"pointbake synthetic scene\"");
  }
  if (!j.contains("version") || !j["version"].is_number_integer() || j["version"] != kSynthSceneVersion) {
    return Status::Unsupported("version: expected " + std::to_string(kSynthSceneVersion));
  }
  SynthScene s;
  if (j.contains("preset")) {
    if (!j["preset"].is_string()) return Status::Invalid("preset: expected a string");
    s.preset = j["preset"].get<std::string>();
  }
  if (j.contains("seed")) {
    if (!j["seed"].is_number_integer()) return Status::Invalid("seed: expected an integer");
    s.seed = j["seed"].get<uint64_t>();
  }
  const std::string shape = j.value("shape", std::string());
  if (shape == "objects") {
    // Open presets are rebuilt from their name; the file's elements must be
    // the preset's (see scene.h).
    if (!IsObjectsPreset(s.preset)) {
      return Status::Invalid("preset: shape \"objects\" needs preset \"facade\" or \"sculpture\", got \"" +
                             s.preset + "\"");
    }
    PB_ASSIGN_OR_RETURN(SynthScene rebuilt, MakeObjectsScene(s.preset, s.seed));
    if (!j.contains("objects") || j["objects"] != ObjectsToJson(*rebuilt.objects)) {
      return Status::Invalid("objects: differ from preset '" + s.preset + "' (version " +
                             std::to_string(kSynthSceneVersion) + "); edited element lists are not supported");
    }
    if (j.contains("brick") || j.contains("floor")) {
      // Materials may be tuned like the rooms'; validated by the same code below.
      SynthScene materials = rebuilt;
      const nlohmann::json& b = j.value("brick", nlohmann::json::object());
      const nlohmann::json& f = j.value("floor", nlohmann::json::object());
      if (!b.is_object() || !f.is_object()) return Status::Invalid("brick, floor: expected objects");
      PB_RETURN_IF_ERROR(ReadNumber(b, "brick.", "length_m", &materials.brick.length_m, false, 0));
      PB_RETURN_IF_ERROR(ReadNumber(b, "brick.", "height_m", &materials.brick.height_m, false, 0));
      PB_RETURN_IF_ERROR(ReadNumber(b, "brick.", "joint_m", &materials.brick.joint_m, false, 0));
      PB_RETURN_IF_ERROR(ReadNumber(b, "brick.", "joint_depth_m", &materials.brick.joint_depth_m, false, -1e-300));
      PB_RETURN_IF_ERROR(ReadNumber(b, "brick.", "bevel_m", &materials.brick.bevel_m, false, 0));
      PB_RETURN_IF_ERROR(ReadNumber(f, "floor.", "stone_length_m", &materials.floor.stone_length_m, false, 0));
      PB_RETURN_IF_ERROR(ReadNumber(f, "floor.", "stone_width_m", &materials.floor.stone_width_m, false, 0));
      PB_RETURN_IF_ERROR(ReadNumber(f, "floor.", "joint_m", &materials.floor.joint_m, false, 0));
      PB_RETURN_IF_ERROR(ReadNumber(f, "floor.", "joint_depth_m", &materials.floor.joint_depth_m, false, -1e-300));
      PB_RETURN_IF_ERROR(ReadNumber(f, "floor.", "unevenness_m", &materials.floor.unevenness_m, false, -1e-300));
      PB_RETURN_IF_ERROR(ReadNumber(f, "floor.", "stone_offset_m", &materials.floor.stone_offset_m, false, -1e-300));
      return materials;
    }
    return rebuilt;
  }
  if (shape == "box") {
    s.shape = SynthShape::kBox;
  } else if (shape == "vault") {
    s.shape = SynthShape::kVault;
  } else if (shape == "tower") {
    s.shape = SynthShape::kTower;
  } else {
    return Status::Invalid("shape: expected \"box\", \"vault\", \"tower\" or \"objects\"");
  }
  const auto size = j.find("size_m");
  if (size == j.end() || !size->is_array() || size->size() != 3 || !(*size)[0].is_number() ||
      !(*size)[1].is_number() || !(*size)[2].is_number()) {
    return Status::Invalid("size_m: expected [width, depth, height] in meters");
  }
  s.width_m = (*size)[0], s.depth_m = (*size)[1], s.height_m = (*size)[2];
  if (!(s.width_m > 0 && s.depth_m > 0 && s.height_m > 0)) return Status::Invalid("size_m: must be > 0");
  if (s.shape == SynthShape::kTower && s.width_m != s.depth_m) {
    return Status::Invalid("size_m: a tower needs width == depth (the diameter)");
  }
  if (s.shape == SynthShape::kVault && !(Springing(s) > 0)) {
    return Status::Invalid("size_m: a vault needs height > depth / 2 (the vault's radius)");
  }
  if (j.contains("brick")) {
    const nlohmann::json& b = j["brick"];
    if (!b.is_object()) return Status::Invalid("brick: expected an object");
    PB_RETURN_IF_ERROR(ReadNumber(b, "brick.", "length_m", &s.brick.length_m, false, 0));
    PB_RETURN_IF_ERROR(ReadNumber(b, "brick.", "height_m", &s.brick.height_m, false, 0));
    PB_RETURN_IF_ERROR(ReadNumber(b, "brick.", "joint_m", &s.brick.joint_m, false, 0));
    PB_RETURN_IF_ERROR(ReadNumber(b, "brick.", "joint_depth_m", &s.brick.joint_depth_m, false, -1e-300));
    PB_RETURN_IF_ERROR(ReadNumber(b, "brick.", "bevel_m", &s.brick.bevel_m, false, 0));
  }
  if (j.contains("floor")) {
    const nlohmann::json& f = j["floor"];
    if (!f.is_object()) return Status::Invalid("floor: expected an object");
    PB_RETURN_IF_ERROR(ReadNumber(f, "floor.", "stone_length_m", &s.floor.stone_length_m, false, 0));
    PB_RETURN_IF_ERROR(ReadNumber(f, "floor.", "stone_width_m", &s.floor.stone_width_m, false, 0));
    PB_RETURN_IF_ERROR(ReadNumber(f, "floor.", "joint_m", &s.floor.joint_m, false, 0));
    PB_RETURN_IF_ERROR(ReadNumber(f, "floor.", "joint_depth_m", &s.floor.joint_depth_m, false, -1e-300));
    PB_RETURN_IF_ERROR(ReadNumber(f, "floor.", "unevenness_m", &s.floor.unevenness_m, false, -1e-300));
    PB_RETURN_IF_ERROR(ReadNumber(f, "floor.", "stone_offset_m", &s.floor.stone_offset_m, false, -1e-300));
  }
  if (j.contains("openings")) {
    if (!j["openings"].is_array()) return Status::Invalid("openings: expected an array");
    for (size_t i = 0; i < j["openings"].size(); ++i) {
      const nlohmann::json& o = j["openings"][i];
      const std::string where = "openings[" + std::to_string(i) + "].";
      if (!o.is_object()) return Status::Invalid(where.substr(0, where.size() - 1) + ": expected an object");
      SynthOpening opening;
      opening.kind = o.value("kind", std::string("window"));
      if (!o.contains("wall") || !o["wall"].is_number_integer()) {
        return Status::Invalid(where + "wall: expected an integer");
      }
      opening.wall = o["wall"].get<int>();
      if (opening.wall < 0 || opening.wall >= WallCount(s)) {
        return Status::Invalid(where + "wall: must be 0.." + std::to_string(WallCount(s) - 1));
      }
      PB_RETURN_IF_ERROR(ReadNumber(o, where, "center_u_m", &opening.center_u_m, true));
      PB_RETURN_IF_ERROR(ReadNumber(o, where, "sill_m", &opening.sill_m, true));
      PB_RETURN_IF_ERROR(ReadNumber(o, where, "width_m", &opening.width_m, true, 0));
      PB_RETURN_IF_ERROR(ReadNumber(o, where, "height_m", &opening.height_m, true, 0));
      const double length = WallLength(s, opening.wall);
      if (s.shape != SynthShape::kTower && (opening.center_u_m - opening.width_m / 2 < 0 ||
                                            opening.center_u_m + opening.width_m / 2 > length)) {
        return Status::Invalid(where + "center_u_m: the opening leaves its wall (length " +
                               std::to_string(length) + " m)");
      }
      if (opening.sill_m < 0 ||
          opening.sill_m + opening.height_m > WallTop(s, opening.wall, opening.center_u_m)) {
        return Status::Invalid(where + "sill_m: the opening leaves its wall vertically");
      }
      s.openings.push_back(opening);
    }
  }
  return s;
}

Expected<SynthScene> ReadSynthScene(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Status::Errno(path, "open");
  nlohmann::json j = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return Status::Corrupt(path + ": not valid JSON");
  Expected<SynthScene> scene = SynthSceneFromJson(j);
  if (!scene.ok()) return scene.status().WithContext(path);
  return scene;
}

SurfaceSample SampleSurface(const SynthScene& s, const Vec3& p) {
  if (s.objects) return ObjectsSample(s, p);
  // Candidates: (base distance, surface, wall, u, v); the nearest base surface wins.
  struct Candidate {
    double base_distance;
    SynthSurface surface;
    int wall;
    double u, v;
  };
  Candidate best{kInf, SynthSurface::kFloor, -1, p[0], p[1]};
  auto consider = [&best](Candidate c) {
    if (std::abs(c.base_distance) < std::abs(best.base_distance)) best = c;
  };
  const double hw = s.width_m / 2, hd = s.depth_m / 2;
  consider({p[2], SynthSurface::kFloor, -1, p[0], p[1]});
  if (s.shape == SynthShape::kTower) {
    const double r = Radius(s), rho = std::hypot(p[0], p[1]);
    double theta = std::atan2(p[1], p[0]);
    if (theta < 0) theta += 2 * kPi;
    consider({r - rho, SynthSurface::kWall, 0, r * theta, p[2]});
    consider({s.height_m - p[2], SynthSurface::kCeiling, -1, p[0], p[1]});
  } else {
    consider({hw - p[0], SynthSurface::kWall, 1, p[1] + hd, p[2]});
    consider({p[0] + hw, SynthSurface::kWall, 3, hd - p[1], p[2]});
    if (s.shape == SynthShape::kBox || p[2] <= Springing(s)) {
      consider({p[1] + hd, SynthSurface::kWall, 0, p[0] + hw, p[2]});
      consider({hd - p[1], SynthSurface::kWall, 2, hw - p[0], p[2]});
    }
    if (s.shape == SynthShape::kBox) {
      consider({s.height_m - p[2], SynthSurface::kCeiling, -1, p[0], p[1]});
    } else if (p[2] > Springing(s)) {
      const double dz = p[2] - Springing(s), rho = std::hypot(p[1], dz);
      consider({hd - rho, SynthSurface::kVault, -1, p[0], hd * std::atan2(dz, -p[1])});
    }
  }
  SurfaceSample out;
  out.surface = best.surface;
  out.wall = best.wall;
  const Frame frame = SurfaceFrame(s, best.surface, best.wall, best.u, best.v);
  out.distance_m = best.base_distance - Relief(s, best.surface, best.u, best.v);
  out.normal = TrueNormal(s, best.surface, frame, best.u, best.v);
  out.in_opening = best.surface == SynthSurface::kWall && InOpening(s, best.wall, best.u, best.v);
  out.albedo = out.in_opening ? std::array<double, 3>{0, 0, 0} : Albedo(s, best.surface, best.wall, best.u, best.v);
  return out;
}

std::optional<SynthHit> Intersect(const SynthScene& s, const Vec3& o, const Vec3& d) {
  if (s.objects) return ObjectsIntersect(s, o, d);
  // The room is convex, so the first hit is where the ray leaves it: the
  // smallest exit parameter over the bounding constraints.
  SynthHit hit;
  hit.t = kInf;
  auto take = [&hit](double t, SynthSurface surface, int wall) {
    if (t > 0 && t < hit.t) hit.t = t, hit.surface = surface, hit.wall = wall;
  };
  const double hw = s.width_m / 2, hd = s.depth_m / 2;
  if (d[2] < 0) take(-o[2] / d[2], SynthSurface::kFloor, -1);
  if (s.shape == SynthShape::kTower) {
    if (d[2] > 0) take((s.height_m - o[2]) / d[2], SynthSurface::kCeiling, -1);
    const double r = Radius(s);
    const double a = d[0] * d[0] + d[1] * d[1], b = o[0] * d[0] + o[1] * d[1];
    const double c = o[0] * o[0] + o[1] * o[1] - r * r;
    if (a > 0) take((-b + std::sqrt(std::max(0.0, b * b - a * c))) / a, SynthSurface::kWall, 0);
  } else {
    if (d[0] > 0) take((hw - o[0]) / d[0], SynthSurface::kWall, 1);
    if (d[0] < 0) take((-hw - o[0]) / d[0], SynthSurface::kWall, 3);
    if (s.shape == SynthShape::kBox) {
      if (d[2] > 0) take((s.height_m - o[2]) / d[2], SynthSurface::kCeiling, -1);
      if (d[1] < 0) take((-hd - o[1]) / d[1], SynthSurface::kWall, 0);
      if (d[1] > 0) take((hd - o[1]) / d[1], SynthSurface::kWall, 2);
    } else {
      // Lower box part {|y| <= r, z <= springing} united with the vault's
      // disk: convex, so the ray's exit is the later of the two exits.
      const double spring = Springing(s);
      double t_low = kInf;
      int low_wall = -1;
      if (d[1] < 0) t_low = (-hd - o[1]) / d[1], low_wall = 0;
      if (d[1] > 0) t_low = (hd - o[1]) / d[1], low_wall = 2;
      if (d[2] > 0 && (spring - o[2]) / d[2] < t_low) t_low = (spring - o[2]) / d[2], low_wall = -1;
      const double oz = o[2] - spring;
      const double a = d[1] * d[1] + d[2] * d[2], b = o[1] * d[1] + oz * d[2];
      const double c = o[1] * o[1] + oz * oz - hd * hd;
      const double disc = b * b - a * c;
      const double t_disk = (a > 0 && disc >= 0) ? (-b + std::sqrt(disc)) / a : -kInf;
      if (t_disk >= t_low || low_wall < 0) {
        take(std::max(t_disk, t_low), SynthSurface::kVault, -1);
      } else {
        take(t_low, SynthSurface::kWall, low_wall);
      }
    }
  }
  if (!std::isfinite(hit.t)) return std::nullopt;
  const Vec3 p = Add(o, Scale(d, hit.t));
  switch (hit.surface) {
    case SynthSurface::kFloor:
    case SynthSurface::kCeiling:
      hit.u = p[0], hit.v = p[1];
      break;
    case SynthSurface::kVault: {
      const double dz = std::max(0.0, p[2] - Springing(s));
      hit.u = p[0], hit.v = hd * std::atan2(dz, -p[1]);
      break;
    }
    case SynthSurface::kWall:
      hit.v = p[2];
      if (s.shape == SynthShape::kTower) {
        double theta = std::atan2(p[1], p[0]);
        if (theta < 0) theta += 2 * kPi;
        hit.u = Radius(s) * theta;
      } else {
        hit.u = hit.wall == 0 ? p[0] + hw : hit.wall == 1 ? p[1] + hd : hit.wall == 2 ? hw - p[0] : hd - p[1];
      }
      if (InOpening(s, hit.wall, hit.u, hit.v)) return std::nullopt;
      break;
    case SynthSurface::kObject:  // not in rooms
      break;
  }
  const Frame frame = SurfaceFrame(s, hit.surface, hit.wall, hit.u, hit.v);
  hit.base_normal = frame.normal;
  hit.point = Add(frame.base, Scale(frame.normal, Relief(s, hit.surface, hit.u, hit.v)));
  return hit;
}

std::array<double, 3> HitAlbedo(const SynthScene& scene, const SynthHit& hit) {
  if (scene.objects) return ObjectsHitAlbedo(scene, hit);
  return Albedo(scene, hit.surface, hit.wall, hit.u, hit.v);
}

namespace {

// Sorted grid coordinates from lo to hi, about cell apart, including `edges`
// that fall inside (opening borders), so openings are cut exactly.
std::vector<double> GridLines(double lo, double hi, double cell, std::vector<double> edges) {
  const int n = std::max(1, static_cast<int>(std::ceil((hi - lo) / cell - 1e-9)));
  std::vector<double> lines;
  for (int i = 0; i <= n; ++i) lines.push_back(lo + (hi - lo) * i / n);
  for (double e : edges) {
    if (e > lo && e < hi) lines.push_back(e);
  }
  std::sort(lines.begin(), lines.end());
  std::vector<double> out;
  for (double x : lines) {
    if (out.empty() || x - out.back() > 1e-6) {
      out.push_back(x);
    } else {
      out.back() = std::max(out.back(), x);  // keep opening edges exact
    }
  }
  return out;
}

// Adds one surface patch as a grid of quads. `map(u, v, &u2, &v2)` clamps a
// grid vertex onto the surface's domain (tower disks, lunettes); `keep(u, v)`
// says whether the cell centered at (u, v) belongs to the surface.
template <typename Map, typename Keep>
void AddPatch(const SynthScene& s, SynthSurface surface, int wall, const std::vector<double>& us,
              const std::vector<double>& vs, Map map, Keep keep, Mesh& mesh) {
  const size_t nu = us.size(), nv = vs.size(), base = mesh.vertex_count();
  mesh.positions.resize(3 * (base + nu * nv));
  mesh.normals.resize(3 * (base + nu * nv));
  mesh.colors.resize(3 * (base + nu * nv));
  tbb::parallel_for(size_t{0}, nv, [&](size_t j) {
    for (size_t i = 0; i < nu; ++i) {
      double u = us[i], v = vs[j];
      map(&u, &v);
      const Frame frame = SurfaceFrame(s, surface, wall, u, v);
      const Vec3 p = Add(frame.base, Scale(frame.normal, Relief(s, surface, u, v)));
      const Vec3 n = TrueNormal(s, surface, frame, u, v);
      const std::array<double, 3> a = Albedo(s, surface, wall, u, v);
      const size_t k = base + j * nu + i;
      for (int c = 0; c < 3; ++c) {
        mesh.positions[3 * k + c] = static_cast<float>(p[c]);
        mesh.normals[3 * k + c] = static_cast<float>(n[c]);
        mesh.colors[3 * k + c] = static_cast<uint8_t>(std::lround(std::clamp(a[c], 0.0, 1.0) * 255));
      }
    }
  });
  // Orientation: counter-clockwise seen from inside the room.
  const Frame frame = SurfaceFrame(s, surface, wall, us[0], vs[0]);
  const bool flip = Dot(Cross(frame.tangent_u, frame.tangent_v), frame.normal) < 0;
  auto pos = [&](size_t k) {
    return Vec3{mesh.positions[3 * k], mesh.positions[3 * k + 1], mesh.positions[3 * k + 2]};
  };
  auto add_triangle = [&](size_t a, size_t b, size_t c) {
    if (flip) std::swap(b, c);
    const Vec3 area = Cross(Sub(pos(b), pos(a)), Sub(pos(c), pos(a)));
    if (Dot(area, area) < 1e-16) return;  // collapsed by clamping
    mesh.indices.insert(mesh.indices.end(),
                        {static_cast<uint32_t>(a), static_cast<uint32_t>(b), static_cast<uint32_t>(c)});
  };
  for (size_t j = 0; j + 1 < nv; ++j) {
    for (size_t i = 0; i + 1 < nu; ++i) {
      if (!keep((us[i] + us[i + 1]) / 2, (vs[j] + vs[j + 1]) / 2, us[i], us[i + 1], vs[j], vs[j + 1])) {
        continue;
      }
      const size_t k00 = base + j * nu + i, k10 = k00 + 1, k01 = k00 + nu, k11 = k01 + 1;
      add_triangle(k00, k10, k11);
      add_triangle(k00, k11, k01);
    }
  }
}

// Drops vertices no triangle uses (opening cells, clamped corners).
void Compact(Mesh& mesh) {
  std::vector<uint32_t> remap(mesh.vertex_count(), UINT32_MAX);
  for (uint32_t index : mesh.indices) remap[index] = 0;
  uint32_t next = 0;
  for (size_t k = 0; k < remap.size(); ++k) {
    if (remap[k] == 0) {
      remap[k] = next;
      for (int c = 0; c < 3; ++c) {
        mesh.positions[3 * next + c] = mesh.positions[3 * k + c];
        mesh.normals[3 * next + c] = mesh.normals[3 * k + c];
        mesh.colors[3 * next + c] = mesh.colors[3 * k + c];
      }
      ++next;
    }
  }
  for (uint32_t& index : mesh.indices) index = remap[index];
  mesh.positions.resize(3 * size_t{next});
  mesh.normals.resize(3 * size_t{next});
  mesh.colors.resize(3 * size_t{next});
}

}  // namespace

Mesh SynthTruthMesh(const SynthScene& s, double cell_m) {
  if (s.objects) return ObjectsTruthMesh(s, cell_m);
  Mesh mesh;
  const double hw = s.width_m / 2, hd = s.depth_m / 2;
  auto no_map = [](double*, double*) {};
  auto keep_all = [](double, double, double, double, double, double) { return true; };
  for (int wall = 0; wall < WallCount(s); ++wall) {
    std::vector<double> u_edges, v_edges;
    for (const SynthOpening& o : s.openings) {
      if (o.wall != wall) continue;
      u_edges.push_back(o.center_u_m - o.width_m / 2);
      u_edges.push_back(o.center_u_m + o.width_m / 2);
      v_edges.push_back(o.sill_m);
      v_edges.push_back(o.sill_m + o.height_m);
    }
    const double length = WallLength(s, wall);
    double top = 0;
    for (double u = 0; u <= length; u += cell_m / 4) top = std::max(top, WallTop(s, wall, u));
    auto clamp_top = [&s, wall](double* u, double* v) { *v = std::min(*v, WallTop(s, wall, *u)); };
    auto keep_wall = [&s, wall](double u, double v, double u0, double u1, double, double) {
      return !InOpening(s, wall, u, v) && v < std::max(WallTop(s, wall, u0), WallTop(s, wall, u1));
    };
    AddPatch(s, SynthSurface::kWall, wall, GridLines(0, length, cell_m, u_edges),
             GridLines(0, top, cell_m, v_edges), clamp_top, keep_wall, mesh);
  }
  if (s.shape == SynthShape::kTower) {
    const double r = Radius(s);
    auto clamp_disk = [r](double* x, double* y) {
      const double rho = std::hypot(*x, *y);
      if (rho > r) *x *= r / rho, *y *= r / rho;
    };
    auto keep_disk = [r](double, double, double x0, double x1, double y0, double y1) {
      const double x = std::min(std::abs(x0), std::abs(x1)), y = std::min(std::abs(y0), std::abs(y1));
      return std::hypot(x, y) < r;  // some corner inside
    };
    const std::vector<double> lines = GridLines(-r, r, cell_m, {});
    AddPatch(s, SynthSurface::kFloor, -1, lines, lines, clamp_disk, keep_disk, mesh);
    AddPatch(s, SynthSurface::kCeiling, -1, lines, lines, clamp_disk, keep_disk, mesh);
  } else {
    const std::vector<double> xs = GridLines(-hw, hw, cell_m, {}), ys = GridLines(-hd, hd, cell_m, {});
    AddPatch(s, SynthSurface::kFloor, -1, xs, ys, no_map, keep_all, mesh);
    if (s.shape == SynthShape::kBox) {
      AddPatch(s, SynthSurface::kCeiling, -1, xs, ys, no_map, keep_all, mesh);
    } else {
      AddPatch(s, SynthSurface::kVault, -1, xs, GridLines(0, kPi * hd, cell_m, {}), no_map, keep_all, mesh);
    }
  }
  Compact(mesh);
  return mesh;
}

}  // namespace pb
