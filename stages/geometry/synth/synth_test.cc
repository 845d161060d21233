// Tests of the synthetic scene (synth_scene.h) and the simulated scanner
// (synth_scanner.h).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numbers>

#include "stages/geometry/synth/scanner.h"
#include "stages/geometry/synth/scene.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

SynthScene Preset(const std::string& name) {
  Expected<SynthScene> scene = MakeSynthScene(name, 1);
  EXPECT_TRUE(scene.ok()) << scene.status().message();
  return scene.value();
}

SynthScanResult Scan(const SynthScene& scene, uint64_t points, uint64_t seed = 1, int stations = 3) {
  SynthScanOptions options;
  options.target_points = points;
  options.seed = seed;
  options.stations = stations;
  Expected<SynthScanResult> result = SimulateScan(scene, options);
  EXPECT_TRUE(result.ok()) << result.status().message();
  return std::move(result).value();
}

Vec3 PointAt(const PointCloud& cloud, size_t i) {
  return {cloud.positions[3 * i], cloud.positions[3 * i + 1], cloud.positions[3 * i + 2]};
}

TEST(SynthScene, PresetsAndJsonRoundTrip) {
  for (const char* name : {"room", "tower", "vault"}) {
    SCOPED_TRACE(name);
    const SynthScene scene = Preset(name);
    EXPECT_EQ(scene.preset, name);
    EXPECT_FALSE(scene.openings.empty());
    Expected<SynthScene> back = SynthSceneFromJson(ToJson(scene));
    ASSERT_TRUE(back.ok()) << back.status().message();
    EXPECT_EQ(ToJson(back.value()), ToJson(scene));
  }
  const SynthScene room = Preset("room");
  EXPECT_EQ(room.width_m, 6.0);
  EXPECT_EQ(room.depth_m, 4.5);
  EXPECT_EQ(room.height_m, 3.2);
  EXPECT_EQ(room.openings.size(), 3u);  // a door and two windows
  EXPECT_EQ(Preset("tower").width_m, 6.0);
  EXPECT_EQ(Preset("tower").height_m, 6.0);

  Expected<SynthScene> small = MakeSynthScene("room", 1, Vec3{3.0, 2.5, 2.4});
  ASSERT_TRUE(small.ok()) << small.status().message();
  EXPECT_EQ(small->width_m, 3.0);
  EXPECT_EQ(small->height_m, 2.4);
}

TEST(SynthScene, RejectsBadDescriptions) {
  EXPECT_THAT(MakeSynthScene("castle", 1).status().message(), HasSubstr("unknown synthetic scene preset 'castle'"));
  EXPECT_THAT(MakeSynthScene("tower", 1, Vec3{6, 5, 6}).status().message(), HasSubstr("must be equal"));
  nlohmann::json j = ToJson(Preset("room"));
  j["openings"][1]["width_m"] = -1;
  EXPECT_THAT(SynthSceneFromJson(j).status().message(), HasSubstr("openings[1].width_m: must be > 0"));
  j = ToJson(Preset("room"));
  j["openings"][0]["center_u_m"] = 5.9;
  EXPECT_THAT(SynthSceneFromJson(j).status().message(), HasSubstr("openings[0].center_u_m: the opening leaves"));
  j = ToJson(Preset("room"));
  j["version"] = 7;
  EXPECT_THAT(SynthSceneFromJson(j).status().message(), HasSubstr("version: expected 1"));
  j = ToJson(Preset("room"));
  j.erase("size_m");
  EXPECT_THAT(SynthSceneFromJson(j).status().message(), HasSubstr("size_m: expected [width, depth, height]"));
}

TEST(SynthScene, IntersectHitsTheTrueSurfaceAndPassesOpenings) {
  const SynthScene room = Preset("room");
  const Vec3 center = {0, 0, 1.5};
  // Straight at wall 1 (x = +3), away from its openings (wall 1 has none).
  std::optional<SynthHit> hit = Intersect(room, center, {1, 0, 0});
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->surface, SynthSurface::kWall);
  EXPECT_EQ(hit->wall, 1);
  EXPECT_NEAR(hit->t, 3.0, 1e-12);
  // Mortar is recessed: behind the brick faces, away from the room.
  EXPECT_GE(hit->point[0], 3.0);
  EXPECT_LE(hit->point[0], 3.0 + room.brick.joint_depth_m + 1e-12);
  EXPECT_NEAR(SampleSurface(room, hit->point).distance_m, 0, 1e-9);
  // Floor and ceiling.
  hit = Intersect(room, center, {0, 0, -1});
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->surface, SynthSurface::kFloor);
  EXPECT_LE(std::abs(hit->point[2]), 0.013);
  hit = Intersect(room, center, {0, 0, 1});
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->surface, SynthSurface::kCeiling);
  EXPECT_NEAR(hit->point[2], 3.2, 1e-12);
  // Through the middle of every opening: nothing.
  for (const SynthOpening& o : room.openings) {
    const double u = o.center_u_m, v = o.sill_m + o.height_m / 2;
    const Vec3 target = o.wall == 0 ? Vec3{-3 + u, -2.25, v} : Vec3{3 - u, 2.25, v};  // walls 0 and 2
    Vec3 dir = {target[0] - center[0], target[1] - center[1], target[2] - center[2]};
    const double length = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    for (double& c : dir) c /= length;
    EXPECT_FALSE(Intersect(room, center, dir).has_value()) << o.kind << " on wall " << o.wall;
  }
  // Vault crown and tower wall.
  const SynthScene vault = Preset("vault");
  hit = Intersect(vault, {0, 0, 1.5}, {0, 0, 1});
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->surface, SynthSurface::kVault);
  EXPECT_NEAR(hit->point[2], 4.85, 1e-9);
  hit = Intersect(vault, {0, 0, 1.5}, {0, std::sqrt(0.5), std::sqrt(0.5)});
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->surface, SynthSurface::kVault);
  EXPECT_NEAR(SampleSurface(vault, hit->point).distance_m, 0, 1e-9);
  const SynthScene tower = Preset("tower");
  hit = Intersect(tower, {0, 0, 1.5}, {std::sqrt(0.5), std::sqrt(0.5), 0});
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->surface, SynthSurface::kWall);
  EXPECT_NEAR(hit->t, 3.0, 1e-9);
}

TEST(SynthScene, AlbedoShowsBricksMortarAndStones) {
  const SynthScene room = Preset("room");
  // Wall 1 at u = 0.1 (x = 3, y = -2.15): a mortar bed joint at v = 0.075 * 10 + 0.004.
  const SurfaceSample mortar = SampleSurface(room, {3.0 + 0.004, -2.15, 0.754});
  EXPECT_NEAR(mortar.albedo[0], mortar.albedo[2], 0.12);  // gray
  EXPECT_NEAR(mortar.distance_m, 0, 1e-9);
  const SurfaceSample brick = SampleSurface(room, {3.0, -2.15, 0.79});
  EXPECT_GT(brick.albedo[0], brick.albedo[2] + 0.1);  // red-brown
  EXPECT_NEAR(brick.normal[0], -1, 1e-9);
  // Different bricks differ.
  double spread = 0;
  for (int k = 0; k < 20; ++k) {
    const SurfaceSample a = SampleSurface(room, {3.0, -2.0 + 0.225 * k, 0.79});
    spread = std::max(spread, std::abs(a.albedo[0] - brick.albedo[0]));
  }
  EXPECT_GT(spread, 0.05);
  // Floor relief within +-1.3 cm, plaster ceiling off-white.
  for (int k = 0; k < 100; ++k) {
    const SurfaceSample floor = SampleSurface(room, {-2.9 + 0.057 * k, -2.0 + 0.041 * k, 0});
    EXPECT_EQ(floor.surface, SynthSurface::kFloor);
    EXPECT_LE(std::abs(floor.distance_m), 0.013);
  }
  const SurfaceSample ceiling = SampleSurface(room, {0.5, 0.5, 3.2});
  EXPECT_GT(ceiling.albedo[2], 0.75);
  // A point in a window.
  const SynthOpening& window = room.openings[1];
  EXPECT_TRUE(SampleSurface(room, {3 - window.center_u_m, 2.25, window.sill_m + 0.5}).in_opening);
}

TEST(SynthScan, RoomScanMatchesTruth) {
  const SynthScene room = Preset("room");
  const SynthScanResult result = Scan(room, 100000);
  const PointCloud& cloud = result.cloud;
  ASSERT_TRUE(Validate(cloud).ok());
  EXPECT_NEAR(static_cast<double>(cloud.size()), 100000, 10000);
  ASSERT_EQ(cloud.stations.size(), 3u);
  ASSERT_EQ(cloud.station_ids.size(), cloud.size());
  ASSERT_TRUE(cloud.has_colors());
  int seen[3] = {0, 0, 0};
  for (uint16_t id : cloud.station_ids) {
    ASSERT_LT(id, 3);
    ++seen[id];
  }
  for (int count : seen) EXPECT_GT(count, 20000);
  for (const Vec3& s : cloud.stations) {
    EXPECT_NEAR(s[2], 1.5, 0.06);
    EXPECT_LT(std::abs(s[0]), 3.0);
    EXPECT_LT(std::abs(s[1]), 2.25);
  }
  Vec3 lo, hi;
  SceneBounds(room, &lo, &hi);
  const double sigma = 0.002, slack = 5 * sigma;
  double color_error = 0;
  size_t far = 0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Vec3 p = PointAt(cloud, i);
    for (int a = 0; a < 3; ++a) {
      ASSERT_GE(p[a], lo[a] - slack) << i;
      ASSERT_LE(p[a], hi[a] + slack) << i;
    }
    const SurfaceSample truth = SampleSurface(room, p);
    if (std::abs(truth.distance_m) > 5 * sigma) ++far;
    EXPECT_FALSE(truth.in_opening && std::abs(truth.distance_m) < 1e-3) << i;
    for (int c = 0; c < 3; ++c) color_error += std::abs(cloud.colors[3 * i + c] / 255.0 - truth.albedo[c]);
  }
  // 5 sigma is exceeded by 6e-7 of a Gaussian; a few points near the brick
  // edges (relief steps) may project onto the neighboring relief.
  EXPECT_LE(far, cloud.size() / 10000) << far;
  color_error /= 3.0 * static_cast<double>(cloud.size());
  EXPECT_LT(color_error, 0.03);
  // Windows: no point on the wall plane inside a window rectangle.
  for (const SynthOpening& o : room.openings) {
    if (o.kind != "window") continue;
    ASSERT_EQ(o.wall, 2);
    size_t inside = 0;
    for (size_t i = 0; i < cloud.size(); ++i) {
      const Vec3 p = PointAt(cloud, i);
      const double u = 3 - p[0];
      if (p[1] > 2.25 - 0.02 && std::abs(u - o.center_u_m) < o.width_m / 2 - 0.01 &&
          p[2] > o.sill_m + 0.01 && p[2] < o.sill_m + o.height_m - 0.01) {
        ++inside;
      }
    }
    EXPECT_EQ(inside, 0u);
  }
  EXPECT_GT(result.median_spacing_m, 0.003);
  EXPECT_LT(result.median_spacing_m, 0.05);
}

TEST(SynthScan, DeterministicBySeed) {
  const SynthScene room = Preset("room");
  const SynthScanResult a = Scan(room, 20000, 7);
  const SynthScanResult b = Scan(room, 20000, 7);
  const SynthScanResult c = Scan(room, 20000, 8);
  EXPECT_EQ(a.cloud.positions, b.cloud.positions);
  EXPECT_EQ(a.cloud.colors, b.cloud.colors);
  EXPECT_EQ(a.cloud.station_ids, b.cloud.station_ids);
  ASSERT_EQ(a.cloud.size(), c.cloud.size());  // same rays, different noise
  EXPECT_NE(a.cloud.positions, c.cloud.positions);
  EXPECT_NE(a.cloud.colors, c.cloud.colors);
}

TEST(SynthScan, IndependentOfThreadCount) {
  const SynthScene tower = Preset("tower");
  SynthScanResult one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = Scan(tower, 50000);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = Scan(tower, 50000);
  }
  EXPECT_EQ(one.cloud.positions, two.cloud.positions);
  EXPECT_EQ(one.cloud.colors, two.cloud.colors);
  EXPECT_EQ(one.cloud.station_ids, two.cloud.station_ids);
  EXPECT_EQ(one.median_spacing_m, two.median_spacing_m);
}

TEST(SynthScan, TowerAndVaultPointsLieOnTheSurface) {
  for (const char* name : {"tower", "vault"}) {
    SCOPED_TRACE(name);
    const SynthScene scene = Preset(name);
    const SynthScanResult result = Scan(scene, 30000, 3, 2);
    EXPECT_NEAR(static_cast<double>(result.cloud.size()), 30000, 3000);
    size_t far = 0;
    for (size_t i = 0; i < result.cloud.size(); ++i) {
      if (std::abs(SampleSurface(scene, PointAt(result.cloud, i)).distance_m) > 0.01) ++far;
    }
    EXPECT_LE(far, 3u);
  }
}

TEST(SynthScan, HitsTargetCountAcrossSizesAndRejectsBadOptions) {
  const SynthScene room = Preset("room");
  for (uint64_t target : {1000u, 5000u, 200000u}) {
    const SynthScanResult result = Scan(room, target, 1, 1);
    EXPECT_NEAR(static_cast<double>(result.cloud.size()), static_cast<double>(target), 0.1 * target);
  }
  SynthScanOptions options;
  options.target_points = 10;
  EXPECT_THAT(SimulateScan(room, options).status().message(), HasSubstr("points: must be >= 1000"));
  options.target_points = 5000;
  options.stations = 17;
  EXPECT_THAT(SimulateScan(room, options).status().message(), HasSubstr("stations: must be 1..16"));
}

TEST(SynthScene, TruthMeshCoversTheSurfaceWithColors) {
  const SynthScene room = Preset("room");
  const Mesh mesh = SynthTruthMesh(room, 0.05);
  ASSERT_TRUE(Validate(mesh).ok());
  ASSERT_TRUE(mesh.has_colors());
  ASSERT_TRUE(mesh.has_normals());
  // Total area: walls minus openings, floor and ceiling (~120 m^2).
  double area = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < 3; ++a) p[k][a] = mesh.positions[3 * mesh.indices[3 * f + k] + a];
    }
    const Vec3 e1 = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
    const Vec3 e2 = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    const Vec3 n = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    area += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    // Faces point into the room: toward the center.
    const Vec3 to_center = {0 - p[0][0], 0 - p[0][1], 1.6 - p[0][2]};
    ASSERT_GT(n[0] * to_center[0] + n[1] * to_center[1] + n[2] * to_center[2], 0) << f;
  }
  double openings = 0;
  for (const SynthOpening& o : room.openings) openings += o.width_m * o.height_m;
  const double expected = 2 * (6 + 4.5) * 3.2 + 2 * 6 * 4.5 - openings;
  EXPECT_NEAR(area, expected, 0.01 * expected);
  for (size_t v = 0; v < mesh.vertex_count(); v += 97) {
    const Vec3 p = {mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
    // Near an edge of the room the nearest surface is ambiguous.
    if (std::abs(p[0]) > 2.97 || std::abs(p[1]) > 2.22 || p[2] < 0.03 || p[2] > 3.17) continue;
    EXPECT_NEAR(SampleSurface(room, p).distance_m, 0, 1e-5) << v;
  }
  for (const char* name : {"tower", "vault"}) {
    const Mesh other = SynthTruthMesh(Preset(name), 0.05);
    EXPECT_TRUE(Validate(other).ok());
    EXPECT_GT(other.face_count(), 50000u) << name;
  }
}

}  // namespace
}  // namespace pb
