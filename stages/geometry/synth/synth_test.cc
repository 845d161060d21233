// Tests of the synthetic scene (synth_scene.h) and the simulated scanner
// (synth_scanner.h).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numbers>

#include "stages/geometry/core/image.h"
#include "stages/geometry/synth/objects.h"
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

// --- open scenes (objects.h) ---

double Distance3(const Vec3& a, const Vec3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

TEST(SynthOpenScene, PresetsRoundTripThroughJson) {
  for (const char* name : {"facade", "sculpture"}) {
    SCOPED_TRACE(name);
    const SynthScene scene = Preset(name);
    EXPECT_EQ(scene.shape, SynthShape::kObjects);
    ASSERT_NE(scene.objects, nullptr);
    const nlohmann::json json = ToJson(scene);
    EXPECT_EQ(json["shape"], "objects");
    Expected<SynthScene> back = SynthSceneFromJson(json);
    ASSERT_TRUE(back.ok()) << back.status().message();
    EXPECT_EQ(ToJson(back.value()), json);
    nlohmann::json edited = json;
    edited["objects"]["patches"][0]["length_u_m"] = 99.0;
    EXPECT_THAT(SynthSceneFromJson(edited).status().message(), HasSubstr("objects: differ from preset"));
  }
  EXPECT_THAT(MakeSynthScene("facade", 1, Vec3{3, 3, 3}).status().message(), HasSubstr("has a fixed size"));
  SynthScanOptions options;
  options.target_points = 5000;
  options.stations = 6;
  EXPECT_THAT(SimulateScan(Preset("facade"), options).status().message(),
              HasSubstr("at most 5 stations, got 6"));
}

// Distances and normals of the sculpture are those of the implicit surface:
// a hit is on the ray and on the surface, and moving off the surface along
// the normal by d gives distance d.
TEST(SynthOpenScene, SculptureDistanceIsExactNearTheSurface) {
  const SynthScene scene = Preset("sculpture");
  const Vec3 eye = {2.0, -1.6, 1.8};
  int blob_hits = 0;
  for (int i = 0; i < 40; ++i) {
    for (int j = 0; j < 40; ++j) {
      const Vec3 target = {-0.45 + 0.9 * i / 39, 0.0, 0.9 + 1.2 * j / 39};
      Vec3 d = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
      const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      for (double& x : d) x /= n;
      const std::optional<SynthHit> hit = Intersect(scene, eye, d);
      if (!hit || hit->surface != SynthSurface::kObject || hit->point[2] < 0.96) continue;
      ++blob_hits;
      const Vec3 on_ray = {eye[0] + hit->t * d[0], eye[1] + hit->t * d[1], eye[2] + hit->t * d[2]};
      ASSERT_LT(Distance3(on_ray, hit->point), 1e-9);
      const SurfaceSample at = SampleSurface(scene, hit->point);
      ASSERT_LT(std::abs(at.distance_m), 1e-8);
      // Facing the eye.
      ASSERT_LT(at.normal[0] * d[0] + at.normal[1] * d[1] + at.normal[2] * d[2], 0);
      // Within the radius of curvature (> 2 mm: grooves 3.5 cm deep), exact.
      for (double offset : {-0.002, -0.001, 0.001, 0.002}) {
        const Vec3 p = {hit->point[0] + offset * at.normal[0], hit->point[1] + offset * at.normal[1],
                        hit->point[2] + offset * at.normal[2]};
        EXPECT_NEAR(SampleSurface(scene, p).distance_m, offset, 2e-6) << i << " " << j << " " << offset;
      }
      // Farther out, another part of a groove may be nearer, and the search
      // may end in a local closest point (objects.h): within 10 %.
      const Vec3 out = {hit->point[0] + 0.01 * at.normal[0], hit->point[1] + 0.01 * at.normal[1],
                        hit->point[2] + 0.01 * at.normal[2]};
      const double d_out = SampleSurface(scene, out).distance_m;
      EXPECT_LE(d_out, 0.011);
      EXPECT_GT(d_out, 0.002);
    }
  }
  EXPECT_GT(blob_hits, 500);
  // Far from every surface, the distance is still a distance (membranes of a
  // reconstruction are measured there): above the blob's top.
  const SurfaceSample above = SampleSurface(scene, {0, 0, 2.6});
  EXPECT_GT(above.distance_m, 0.4);
  EXPECT_LT(above.distance_m, 0.7);
}

// Rays march the blob with per-direction Lipschitz bounds: no ray may step
// over a crossing. A brute-force walk (0.5 mm steps, 1.4 m around the blob,
// ObjectsInside)
// finds no point inside the surface before the reported hit, and a hit
// where the walk finds one (grazing rays at the silhouette included).
TEST(SynthOpenScene, SculptureRaysStopAtTheFirstCrossing) {
  const SynthScene scene = Preset("sculpture");
  const Vec3 center = {0, 0, 1.47};
  size_t rays = 0, hits = 0, skipped = 0, missed = 0;
  for (const Vec3& eye : {Vec3{1.9, 0.0, 1.75}, Vec3{-1.2, -1.4, 2.3}}) {
    for (int i = 0; i < 24; ++i) {
      for (int j = 0; j < 12; ++j) {
        // Targets on a disk around the blob's axis: many pass near the silhouette.
        const double a = 2 * std::numbers::pi * i / 24, r = 0.2 + 0.2 * j / 11;
        const Vec3 target = {r * std::cos(a), r * std::sin(a), 1.0 + 0.9 * j / 11};
        Vec3 d = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
        const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (double& x : d) x /= n;
        const std::optional<SynthHit> hit = Intersect(scene, eye, d);
        ++rays;
        const double t_end = hit ? hit->t : 6.0;
        if (hit) ++hits;
        double first_inside = -1;
        for (double t = 0.3; t < t_end - 1e-6; t += 0.0005) {
          const Vec3 p = {eye[0] + t * d[0], eye[1] + t * d[1], eye[2] + t * d[2]};
          if (Distance3(p, center) > 0.7 || p[2] < 0.96) continue;  // the blob only
          if (ObjectsInside(scene, p)) {
            first_inside = t;
            break;
          }
        }
        if (first_inside >= 0) (hit ? ++skipped : ++missed);
      }
    }
  }
  EXPECT_GT(hits, rays / 3);
  EXPECT_EQ(skipped, 0u);
  EXPECT_EQ(missed, 0u);
}

// One station in front: every point is on the true surface, seen from that
// station (the true normal faces it and nothing lies between), colored by
// the albedo; the wall behind the pump and the space around are not scanned.
TEST(SynthOpenScene, FacadeFromOneStationSeesOnlyWhatFacesIt) {
  const SynthScene scene = Preset("facade");
  const SynthScanResult result = Scan(scene, 100000, 3, /*stations=*/1);
  const PointCloud& cloud = result.cloud;
  EXPECT_NEAR(static_cast<double>(cloud.size()), 100000, 10000);
  ASSERT_EQ(cloud.stations.size(), 1u);
  const Vec3 station = cloud.stations[0];
  EXPECT_NEAR(station[0], 0.6, 1e-9);
  EXPECT_NEAR(station[1], -2.8, 1e-9);
  size_t far = 0, back_facing = 0, occluded = 0, behind_pump = 0, checked = 0;
  double color_error = 0, sum_sq = 0;
  std::array<size_t, 5> by_surface{};
  for (size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_EQ(cloud.station_ids[i], 0);
    const Vec3 p = PointAt(cloud, i);
    if (p[1] > 1.95 && p[0] > -1.0 && p[0] < -0.6 && p[2] > 0.1 && p[2] < 0.9) ++behind_pump;
    if (i % 20 != 0) continue;
    ++checked;
    const SurfaceSample truth = SampleSurface(scene, p);
    by_surface[static_cast<int>(truth.surface)]++;
    sum_sq += truth.distance_m * truth.distance_m;
    if (std::abs(truth.distance_m) > 0.01) ++far;
    const Vec3 to_station = {station[0] - p[0], station[1] - p[1], station[2] - p[2]};
    const double range = std::sqrt(to_station[0] * to_station[0] + to_station[1] * to_station[1] +
                                   to_station[2] * to_station[2]);
    if (truth.normal[0] * to_station[0] + truth.normal[1] * to_station[1] + truth.normal[2] * to_station[2] <
        -0.01 * range) {
      ++back_facing;
    }
    const Vec3 dir = {-to_station[0] / range, -to_station[1] / range, -to_station[2] / range};
    // Occluded: the ray stops well before the point (at grazing incidence the
    // relief convention, scene.h, moves the hit a few cm along the ray).
    const std::optional<SynthHit> hit = Intersect(scene, station, dir);
    if (!hit || (hit->t < range - 0.02 && Distance3(hit->point, p) > 0.1)) ++occluded;
    for (int c = 0; c < 3; ++c) color_error += std::abs(cloud.colors[3 * i + c] - 255 * truth.albedo[c]);
  }
  EXPECT_LE(far, checked / 1000);
  // The 2 mm range noise along the ray, seen along the normal.
  EXPECT_GT(std::sqrt(sum_sq / checked), 0.0008);
  EXPECT_LT(std::sqrt(sum_sq / checked), 0.0022);
  // Brick bevels slope up to 63 degrees: at grazing incidence a few normals
  // face away though the base surface faces the station.
  EXPECT_LE(back_facing, checked / 200);
  EXPECT_LE(occluded, checked / 1000);
  EXPECT_EQ(behind_pump, 0u);
  // Color noise sigma 0.02 (5.1 / 255): mean absolute error ~ 0.8 sigma, plus
  // albedo detail finer than the noise's displacement.
  EXPECT_LT(color_error / (3 * checked), 8.0);
  EXPECT_GT(by_surface[static_cast<int>(SynthSurface::kWall)], checked / 5);
  EXPECT_GT(by_surface[static_cast<int>(SynthSurface::kFloor)], checked / 5);
  EXPECT_GT(by_surface[static_cast<int>(SynthSurface::kObject)], checked / 50);
}

TEST(SynthOpenScene, SculpturePointsLieOnTheCurvedSurface) {
  const SynthScene scene = Preset("sculpture");
  const SynthScanResult result = Scan(scene, 60000, 5, /*stations=*/4);
  const PointCloud& cloud = result.cloud;
  ASSERT_EQ(cloud.stations.size(), 4u);
  size_t far = 0, on_blob = 0;
  double sum_sq = 0, color_error = 0;
  for (size_t i = 0; i < cloud.size(); i += 5) {
    const Vec3 p = PointAt(cloud, i);
    const SurfaceSample truth = SampleSurface(scene, p);
    if (std::abs(truth.distance_m) > 0.01) ++far;
    sum_sq += truth.distance_m * truth.distance_m;
    if (truth.surface == SynthSurface::kObject && p[2] > 0.96) ++on_blob;
    for (int c = 0; c < 3; ++c) color_error += std::abs(cloud.colors[3 * i + c] - 255 * truth.albedo[c]);
  }
  const size_t checked = (cloud.size() + 4) / 5;
  EXPECT_LE(far, checked / 1000);
  EXPECT_GT(std::sqrt(sum_sq / checked), 0.0008);
  EXPECT_LT(std::sqrt(sum_sq / checked), 0.0022);
  EXPECT_GT(on_blob, checked / 20);
  EXPECT_LT(color_error / (3 * checked), 8.0);
  EXPECT_GT(result.median_spacing_m, 0.003);
  EXPECT_LT(result.median_spacing_m, 0.05);
}

TEST(SynthOpenScene, TruthMeshLiesOnTheSurfaceWithoutHiddenParts) {
  for (const char* name : {"facade", "sculpture"}) {
    SCOPED_TRACE(name);
    const SynthScene scene = Preset(name);
    const Mesh mesh = SynthTruthMesh(scene, 0.02);
    ASSERT_TRUE(Validate(mesh).ok());
    ASSERT_TRUE(mesh.has_colors() && mesh.has_normals());
    EXPECT_GT(mesh.face_count(), 100000u);
    // Vertices on the surface (the flutes' and relief's too), triangle
    // centroids within the chord error of a 2 cm grid, faces wound to face
    // along the true normal, no face inside an element (hidden).
    double max_vertex = 0, centroid_sum = 0;
    size_t faces = 0, wrong_side = 0, hidden = 0, vertices = 0, off = 0;
    for (size_t v = 0; v < mesh.vertex_count(); v += 7) {
      const Vec3 p = {mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
      const double d = std::abs(SampleSurface(scene, p).distance_m);
      max_vertex = std::max(max_vertex, d);
      ++vertices;
      if (d > 2e-4) ++off;
    }
    for (size_t f = 0; f < mesh.face_count(); f += 13) {
      Vec3 q[3];
      for (int k = 0; k < 3; ++k) {
        for (int a = 0; a < 3; ++a) q[k][a] = mesh.positions[3 * mesh.indices[3 * f + k] + a];
      }
      const Vec3 c = {(q[0][0] + q[1][0] + q[2][0]) / 3, (q[0][1] + q[1][1] + q[2][1]) / 3,
                      (q[0][2] + q[1][2] + q[2][2]) / 3};
      const SurfaceSample truth = SampleSurface(scene, c);
      centroid_sum += std::abs(truth.distance_m);
      ++faces;
      const Vec3 e1 = {q[1][0] - q[0][0], q[1][1] - q[0][1], q[1][2] - q[0][2]};
      const Vec3 e2 = {q[2][0] - q[0][0], q[2][1] - q[0][1], q[2][2] - q[0][2]};
      const Vec3 n = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
      if (n[0] * truth.normal[0] + n[1] * truth.normal[1] + n[2] * truth.normal[2] < 0) ++wrong_side;
      if (truth.distance_m < -0.01) ++hidden;  // deep inside an element: a hidden face
    }
    // float32 positions; off only at joints between elements, where a cell
    // straddles the junction (a leg on the uneven ground, the blob's foot on
    // the plinth): within a cell.
    EXPECT_LE(off, vertices / 100);
    EXPECT_LT(max_vertex, 0.02);
    EXPECT_LT(centroid_sum / faces, 1e-3);
    EXPECT_LE(wrong_side, faces / 200);  // sharp relief edges where the sampled normal flips
    EXPECT_EQ(hidden, 0u);
  }
  // The ground under the plinth and the blob inside it are left out: the
  // sculpture's truth has no vertex inside the plinth.
  const SynthScene sculpture = Preset("sculpture");
  const Mesh mesh = SynthTruthMesh(sculpture, 0.02);
  size_t inside_plinth = 0;
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    const float* p = &mesh.positions[3 * v];
    if (std::abs(p[0]) < 0.30 && std::abs(p[1]) < 0.30 && p[2] > 0.02 && p[2] < 0.93) ++inside_plinth;
  }
  EXPECT_EQ(inside_plinth, 0u);
}

TEST(SynthOpenScene, ScansAreDeterministicForAnyThreadCount) {
  for (const char* name : {"facade", "sculpture"}) {
    SCOPED_TRACE(name);
    const SynthScene scene = Preset(name);
    SynthScanResult one, two, again;
    {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
      one = Scan(scene, 30000, 9, 2);
    }
    {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
      two = Scan(scene, 30000, 9, 2);
      again = Scan(scene, 30000, 9, 2);
    }
    EXPECT_EQ(one.cloud.positions, two.cloud.positions);
    EXPECT_EQ(one.cloud.colors, two.cloud.colors);
    EXPECT_EQ(one.cloud.station_ids, two.cloud.station_ids);
    EXPECT_EQ(two.cloud.positions, again.cloud.positions);
    EXPECT_EQ(one.median_spacing_m, two.median_spacing_m);
    const Mesh a = SynthTruthMesh(scene, 0.05), b = SynthTruthMesh(scene, 0.05);
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.indices, b.indices);
  }
}

}  // namespace
}  // namespace pb
