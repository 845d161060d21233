#include "stages/geometry/points/scene_survey.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "stages/geometry/testing/clouds.h"

namespace pb {
namespace {

using Vec3 = std::array<double, 3>;

double Distance(const Vec3& a, const Vec3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

void AddPoint(PointCloud* cloud, double x, double y, double z) {
  cloud->positions.push_back(float(x));
  cloud->positions.push_back(float(y));
  cloud->positions.push_back(float(z));
}

// A wall 4 m wide and 3 m high, 3 m north (+y) of the origin, a 1 cm grid.
PointCloud Wall() {
  PointCloud cloud;
  for (int i = 0; i <= 400; ++i)
    for (int k = 0; k <= 300; ++k) AddPoint(&cloud, -2.0 + 0.01 * i, 3.0, -1.0 + 0.01 * k);
  return cloud;
}

// A sphere of radius 1 m, about 20,000 points (a Fibonacci lattice).
PointCloud Sphere() {
  PointCloud cloud;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1.0 - z * z);
    const double phi = i * M_PI * (3.0 - std::sqrt(5.0));
    AddPoint(&cloud, r * std::cos(phi), r * std::sin(phi), z);
  }
  return cloud;
}

TEST(SceneParamsTest, InTheShippedScenesProportions) {
  SceneSurvey pump;  // 155,201 points 4.6 mm apart over 3.9 m: configs/scenes/pump.yaml
  ChooseSceneParams(155201, 0.004635, 3.88, &pump);
  EXPECT_EQ(pump.depth_high, 10);
  EXPECT_EQ(pump.depth_low, 8);
  EXPECT_EQ(pump.faces_high, 62000);
  EXPECT_EQ(pump.faces_low, 6200);
  EXPECT_EQ(pump.texture, 2048);
  EXPECT_EQ(pump.frame_size, 1024);

  SceneSurvey site;  // 10^8 points 2 mm apart over 30 m: every clamp
  ChooseSceneParams(100000000, 0.002, 30.0, &site);
  EXPECT_EQ(site.depth_high, 11);
  EXPECT_EQ(site.depth_low, 9);
  EXPECT_EQ(site.faces_high, kMaxFacesHigh);
  EXPECT_EQ(site.faces_low, kMaxFacesLow);
  EXPECT_EQ(site.texture, 8192);
  EXPECT_EQ(site.frame_size, 1024);

  SceneSurvey small;  // 1,000 points 1 cm apart over 20 cm
  ChooseSceneParams(1000, 0.01, 0.2, &small);
  EXPECT_EQ(small.depth_high, 8);
  EXPECT_EQ(small.depth_low, 7);

  SceneSurvey office;  // 254,456 points 8.5 mm apart over 3.9 m: configs/scenes/office-wall.yaml
  ChooseSceneParams(254456, 0.0085, 3.85, &office);
  EXPECT_EQ(office.depth_high, 9);
  EXPECT_EQ(office.depth_low, 8);
  EXPECT_EQ(small.faces_high, kMinFacesHigh);
  EXPECT_EQ(small.faces_low, kMinFacesHigh / 10);
  EXPECT_EQ(small.texture, 1024);
  EXPECT_EQ(small.frame_size, 512);
}

TEST(SceneSurveyTest, StationLooksAtWhatItScannedAndTheObliqueViewTurnsAway) {
  PointCloud cloud = Wall();
  cloud.origin = {637000.0, 849000.0, 400.0};  // georeferenced: views are absolute
  cloud.stations = {{637000.0, 849000.0, 400.0}};
  cloud.station_ids.assign(cloud.size(), 0);
  Expected<SceneSurvey> survey = SurveyScene(cloud);
  ASSERT_TRUE(survey.ok()) << survey.status().message();
  EXPECT_EQ(survey->stations, 1u);
  EXPECT_NEAR(survey->spacing_m, 0.01, 1e-4);
  EXPECT_TRUE(survey->warnings.empty());
  ASSERT_EQ(survey->viewpoints.size(), 2u);
  const SurveyViewpoint& station = survey->viewpoints[0];
  EXPECT_EQ(station.name, "station1");
  // The eye is above the station, the target on the wall, near its middle.
  EXPECT_NEAR(station.eye[0], 637000.0, 1e-9);
  EXPECT_NEAR(station.eye[1], 849000.0, 1e-9);
  EXPECT_GT(station.eye[2], 400.0);
  EXPECT_LT(station.eye[2], 400.3);
  EXPECT_NEAR(station.target[1], 849003.0, 0.5);
  EXPECT_NEAR(station.target[0], 637000.0, 1.0);
  EXPECT_NEAR(station.target[2], 400.5, 0.5);
  const SurveyViewpoint& oblique = survey->viewpoints[1];
  EXPECT_EQ(oblique.name, "oblique");
  EXPECT_EQ(oblique.target, station.target);
  EXPECT_NEAR(Distance(oblique.eye, oblique.target), Distance(station.eye, station.target), 1e-6);
  EXPECT_GT(Distance(oblique.eye, station.eye), 1.0);
  EXPECT_GT(oblique.eye[2], station.eye[2]);
}

TEST(SceneSurveyTest, StationsThatSawMostComeFirst) {
  PointCloud cloud = Wall();
  cloud.stations = {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {-1.0, 0.0, 0.0}};
  cloud.station_ids.assign(cloud.size(), 2);
  for (size_t i = 0; i < cloud.size() / 4; ++i) cloud.station_ids[i] = 0;
  SceneSurveyOptions options;
  options.max_station_views = 1;
  Expected<SceneSurvey> survey = SurveyScene(cloud, options);
  ASSERT_TRUE(survey.ok()) << survey.status().message();
  EXPECT_EQ(survey->stations, 2u);  // station 1 saw nothing
  ASSERT_EQ(survey->viewpoints.size(), 2u);
  EXPECT_NEAR(survey->viewpoints[0].eye[0], -1.0, 1e-9);
}

TEST(SceneSurveyTest, AWrongUpIsFlagged) {
  PointCloud cloud = Wall();
  cloud.stations = {{0.0, 0.0, 0.0}};
  cloud.station_ids.assign(cloud.size(), 0);
  SceneSurveyOptions options;
  options.up = {0.0, -1.0, 0.0};  // the wall is then "below" the station
  Expected<SceneSurvey> survey = SurveyScene(cloud, options);
  ASSERT_TRUE(survey.ok()) << survey.status().message();
  ASSERT_EQ(survey->warnings.size(), 1u);
  EXPECT_NE(survey->warnings[0].find("below its horizon"), std::string::npos)
      << survey->warnings[0];
  EXPECT_NEAR(survey->viewpoints[0].target[1], 3.0, 0.5);  // still looking at it
}

// A ceiling straight above its station: the view looks along up, so its
// camera's up lies across it (a camera cannot roll about its up).
TEST(SceneSurveyTest, AStationLookingUpKeepsACameraUpAcrossTheView) {
  PointCloud ceiling;
  for (int i = 0; i <= 100; ++i)
    for (int k = 0; k <= 100; ++k) AddPoint(&ceiling, -0.5 + 0.01 * i, -0.5 + 0.01 * k, 3.0);
  ceiling.stations = {{0.0, 0.0, 0.0}};
  ceiling.station_ids.assign(ceiling.size(), 0);
  Expected<SceneSurvey> survey = SurveyScene(ceiling);
  ASSERT_TRUE(survey.ok()) << survey.status().message();
  ASSERT_EQ(survey->warnings.size(), 1u);  // mostly above its horizon
  const SurveyViewpoint& view = survey->viewpoints[0];
  const double dz = view.target[2] - view.eye[2];
  EXPECT_GT(dz, 2.0);
  EXPECT_NEAR(view.up[2], 0.0, 1e-9);
  EXPECT_NEAR(std::hypot(view.up[0], view.up[1]), 1.0, 1e-9);
}

// An ellipsoid 4 m wide (x), 3 m high (z), 1 m deep (y): the front view
// looks along y, face-on, and frames it; the side views turn about z.
TEST(SceneSurveyTest, WithoutStationsFaceOnAndTurnedEitherWay) {
  PointCloud cloud = Sphere();
  for (size_t i = 0; i < cloud.size(); ++i) {
    cloud.positions[3 * i] *= 2.0f;
    cloud.positions[3 * i + 1] *= 0.5f;
    cloud.positions[3 * i + 2] *= 1.5f;
  }
  cloud.origin = {10.0, 20.0, 5.0};
  Expected<SceneSurvey> survey = SurveyScene(cloud);
  ASSERT_TRUE(survey.ok()) << survey.status().message();
  EXPECT_EQ(survey->stations, 0u);
  ASSERT_EQ(survey->viewpoints.size(), 3u);
  const SurveyViewpoint& front = survey->viewpoints[0];
  EXPECT_EQ(front.name, "front");
  EXPECT_LT(Distance(front.target, {10.0, 20.0, 5.0}), 0.05);
  const Vec3 look = {front.target[0] - front.eye[0], front.target[1] - front.eye[1],
                     front.target[2] - front.eye[2]};
  const double d = Distance(front.eye, front.target);
  EXPECT_GT(std::abs(look[1]) / d, 0.999);  // along y, the least extent
  EXPECT_NEAR(front.up[2], 1.0, 1e-9);
  // Framed: the 2 m half-width within the 30° half field, not much more.
  const double half_width_seen = std::tan(M_PI / 6) * (d - 0.5);
  EXPECT_GT(half_width_seen, 1.9);
  EXPECT_LT(half_width_seen, 2.6);
  for (int k : {1, 2}) {
    const SurveyViewpoint& view = survey->viewpoints[k];
    EXPECT_LT(Distance(view.target, front.target), 1e-9) << view.name;
    EXPECT_GT(view.eye[2], front.eye[2]) << view.name;  // raised
  }
  EXPECT_EQ(survey->viewpoints[1].name, "left");
  EXPECT_EQ(survey->viewpoints[2].name, "right");
  // Symmetric, up to the framing distance's percentile of a discrete cloud.
  EXPECT_NEAR(survey->viewpoints[1].eye[1], survey->viewpoints[2].eye[1], 1e-3);
  EXPECT_NEAR(survey->viewpoints[1].eye[0] - 10.0, -(survey->viewpoints[2].eye[0] - 10.0), 1e-3);
  EXPECT_LT(survey->viewpoints[1].eye[0], 10.0 - 1.0);
}

// A room merged into one cloud (no stations): three level views from inside
// it, from one place away from the walls, looking about the room.
TEST(SceneSurveyTest, WithoutStationsARoomIsSeenFromInside) {
  PointCloud room = testing::RoomWithTable(6.0, 4.5, 1.0, 3);
  room.origin = {500000.0, 4000000.0, 120.0};
  Expected<SceneSurvey> survey = SurveyScene(room);
  ASSERT_TRUE(survey.ok()) << survey.status().message();
  EXPECT_GT(survey->enclosed_volume_m3, 8.0);
  ASSERT_EQ(survey->viewpoints.size(), 3u);
  const Vec3 eye = survey->viewpoints[0].eye;
  EXPECT_GT(eye[0] - room.origin[0], 1.0);
  EXPECT_LT(eye[0] - room.origin[0], 5.0);
  EXPECT_GT(eye[1] - room.origin[1], 1.0);
  EXPECT_LT(eye[1] - room.origin[1], 3.5);
  EXPECT_GT(eye[2] - room.origin[2], 1.0);
  EXPECT_LT(eye[2] - room.origin[2], 2.0);
  for (int k = 0; k < 3; ++k) {
    const SurveyViewpoint& view = survey->viewpoints[k];
    EXPECT_EQ(view.name, "inside" + std::to_string(k + 1));
    EXPECT_LT(Distance(view.eye, eye), 1e-9) << view.name;
    EXPECT_NEAR(view.up[2], 1.0, 1e-9);
    EXPECT_NEAR(view.target[2], eye[2], 1e-6) << view.name;  // level
    // Looking at a wall: the target about as far as the room's walls.
    EXPECT_GT(Distance(view.target, eye), 1.0) << view.name;
    EXPECT_LT(Distance(view.target, eye), 5.0) << view.name;
    for (int j = 0; j < k; ++j) {  // turned at least 120°, the third 90°
      const SurveyViewpoint& other = survey->viewpoints[j];
      const double a = std::atan2(view.target[1] - eye[1], view.target[0] - eye[0]);
      const double b = std::atan2(other.target[1] - eye[1], other.target[0] - eye[0]);
      EXPECT_GT(std::abs(std::remainder(a - b, 2 * M_PI)), (k < 2 ? 2 * M_PI / 3 : M_PI / 2) - 1e-6)
          << view.name;
    }
  }
  // The first view looks down the room's length (x, 6 m; y is 4.5 m).
  const SurveyViewpoint& first = survey->viewpoints[0];
  EXPECT_GT(std::abs(first.target[0] - eye[0]), std::abs(first.target[1] - eye[1]));
  // An object has no inside to stand in: the face-on views.
  survey = SurveyScene(Sphere());
  ASSERT_TRUE(survey.ok());
  EXPECT_EQ(survey->enclosed_volume_m3, 0.0);
  EXPECT_EQ(survey->viewpoints[0].name, "front");
}

// A corridor open at both ends (no stations): Find closes nothing in, but
// the space it nearly encloses is stood in (enclosure.h, FindOpen) and the
// first view looks down its length.
TEST(SceneSurveyTest, WithoutStationsACorridorIsSeenFromInside) {
  const PointCloud corridor = testing::OpenCorridor();
  const Expected<SceneSurvey> survey = SurveyScene(corridor);
  ASSERT_TRUE(survey.ok()) << survey.status().message();
  EXPECT_TRUE(survey->enclosure_open);
  EXPECT_GT(survey->enclosed_volume_m3, 8.0);
  ASSERT_EQ(survey->viewpoints.size(), 3u);
  const SurveyViewpoint& first = survey->viewpoints[0];
  EXPECT_EQ(first.name, "inside1");
  EXPECT_NE(first.why.find("nearly encloses"), std::string::npos) << first.why;
  EXPECT_GT(first.eye[1], 0.3);
  EXPECT_LT(first.eye[1], 1.5);
  EXPECT_GT(first.eye[2], 0.5);
  EXPECT_LT(first.eye[2], 2.1);
  EXPECT_GT(std::abs(first.target[0] - first.eye[0]), 3 * std::abs(first.target[1] - first.eye[1]));
}

TEST(SceneSurveyTest, WithoutStationsFromTheSideTheNormalsFace) {
  for (float facing : {-1.0f, 1.0f}) {
    PointCloud cloud = Wall();
    cloud.normals.resize(cloud.positions.size());
    for (size_t i = 0; i < cloud.size(); ++i) cloud.normals[3 * i + 1] = facing;
    Expected<SceneSurvey> survey = SurveyScene(cloud);
    ASSERT_TRUE(survey.ok()) << survey.status().message();
    ASSERT_EQ(survey->viewpoints.size(), 3u);
    for (const SurveyViewpoint& view : survey->viewpoints)
      EXPECT_GT(facing * (view.eye[1] - 3.0), 1.0) << view.name << " facing " << facing;
    EXPECT_NEAR(survey->viewpoints[0].eye[0], survey->viewpoints[0].target[0],
                1e-6);  // straight on
  }
}

// A floor seen from above: the view looks along up, so the camera's up is
// the floor's longest axis instead.
TEST(SceneSurveyTest, LookingAlongUpTakesTheLongestAxisAsTheCamerasUp) {
  PointCloud floor;
  for (int i = 0; i <= 300; ++i)
    for (int k = 0; k <= 100; ++k) AddPoint(&floor, 0.01 * i, 0.01 * k, 0.0);
  Expected<SceneSurvey> survey = SurveyScene(floor);
  ASSERT_TRUE(survey.ok()) << survey.status().message();
  const SurveyViewpoint& front = survey->viewpoints[0];
  EXPECT_GT(front.eye[2], 1.0);
  EXPECT_GT(std::abs(front.up[0]), 0.999);
  EXPECT_NEAR(front.up[2], 0.0, 1e-9);
  for (const SurveyViewpoint& view : survey->viewpoints)
    for (double c : view.eye) EXPECT_TRUE(std::isfinite(c)) << view.name;
}

// A statue on its paving, delivered without stations: the paving (5 x 4 m)
// holds most points, so the main plane is level, and face-on would look
// straight down onto the statue's top. The views look as a visitor does:
// 30 degrees down toward the broad side (along y, the paving's narrow
// axis), then turned 40 degrees either way about up, 45 degrees down.
TEST(SceneSurveyTest, AStatueOnItsGroundIsSeenFromTheSide) {
  PointCloud site;
  for (int i = 0; i <= 250; ++i)
    for (int k = 0; k <= 200; ++k) AddPoint(&site, -2.5 + 0.02 * i, -2.0 + 0.02 * k, 0.0);
  for (int k = 0; k <= 100; ++k)  // a 0.6 m square column 2 m tall
    for (int i = 0; i < 30; ++i) {
      const double t = -0.3 + 0.02 * i, z = 0.02 * k;
      AddPoint(&site, t, -0.3, z);
      AddPoint(&site, 0.3, t, z);
      AddPoint(&site, -t, 0.3, z);
      AddPoint(&site, -0.3, -t, z);
    }
  Expected<SceneSurvey> survey = SurveyScene(site);
  ASSERT_TRUE(survey.ok()) << survey.status().message();
  ASSERT_EQ(survey->viewpoints.size(), 3u);
  const double sines[3] = {0.5, std::sqrt(0.5), std::sqrt(0.5)};
  for (int k = 0; k < 3; ++k) {
    const SurveyViewpoint& view = survey->viewpoints[k];
    const Vec3 from = {view.eye[0] - view.target[0], view.eye[1] - view.target[1],
                       view.eye[2] - view.target[2]};
    const double d = Distance(view.eye, view.target);
    EXPECT_NEAR(from[2] / d, sines[k], 1e-6) << view.name;  // looking down, not straight down
    EXPECT_NEAR(view.up[2], 1.0, 1e-9) << view.name;
  }
  const SurveyViewpoint& front = survey->viewpoints[0];
  EXPECT_NE(front.why.find("main plane is level"), std::string::npos) << front.why;
  EXPECT_LT(std::abs(front.eye[0] - front.target[0]), 1e-6 * Distance(front.eye, front.target));
  EXPECT_NEAR(survey->viewpoints[1].eye[0] - front.target[0], -(survey->viewpoints[2].eye[0] - front.target[0]),
              1e-3);
  EXPECT_GT(std::abs(survey->viewpoints[1].eye[0] - front.target[0]), 1.0);
  // The same paving without the column is a floor: seen from above (the
  // test below), as before.
}

TEST(SceneSurveyTest, BadInputIsNamed) {
  PointCloud few;
  for (int i = 0; i < 5; ++i) AddPoint(&few, i, 0, 0);
  EXPECT_NE(SurveyScene(few).status().message().find("5 points"), std::string::npos);

  PointCloud nan = Sphere();
  nan.positions[3 * 7 + 1] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(SurveyScene(nan).status().message().find("point 7"), std::string::npos);

  PointCloud same;
  for (int i = 0; i < 20; ++i) AddPoint(&same, 1, 2, 3);
  EXPECT_FALSE(SurveyScene(same).ok());

  SceneSurveyOptions no_up;
  no_up.up = {0, 0, 0};
  EXPECT_NE(SurveyScene(Sphere(), no_up).status().message().find("up"), std::string::npos);
}

}  // namespace
}  // namespace pb
