#include "stages/geometry/points/enclosure.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "stages/geometry/testing/clouds.h"

namespace pb {
namespace {

using ::testing::HasSubstr;
using testing::AddSphere;
using testing::RoomWithTable;

bool Contains(const EnclosedSpace& space, double x, double y, double z) {
  const float p[3] = {float(x), float(y), float(z)};
  return space.Contains(p);
}

// A 6 x 4.5 x 3 m room with a 1 m door: the free space 0.75 m from its
// walls, (6 - 1.5) x (4.5 - 1.5) x (3 - 1.5) = 20 m3 less the table's
// surroundings (about 5 m3) and the voxels' rounding, reaching back to the
// walls and the table (to a voxel: 19 cm here), not into the table nor out
// through the door.
TEST(EnclosureTest, RoomWithADoorEnclosesItsFreeSpace) {
  const PointCloud room = RoomWithTable(6.0, 4.5, 1.0, 3);
  const Expected<EnclosedSpace> space = EnclosedSpace::Find(room);
  ASSERT_TRUE(space.ok()) << space.status().message();
  EXPECT_FALSE(space->empty());
  EXPECT_GT(space->volume_m3(), 8.0);
  EXPECT_LT(space->volume_m3(), 21.0);
  EXPECT_TRUE(Contains(*space, 4.5, 2.0, 1.5));   // the middle of the room
  EXPECT_TRUE(Contains(*space, 0.3, 2.0, 1.5));  // a voxel inside a wall
  EXPECT_TRUE(Contains(*space, 0.3, 2.0, 0.3));  // in the corner with the floor
  EXPECT_TRUE(Contains(*space, 5.7, 0.3, 2.7));  // beside the door's wall, under the ceiling
  EXPECT_TRUE(Contains(*space, 2.4, 3.6, 0.3));  // between the table and a wall
  EXPECT_FALSE(Contains(*space, 2.4, 2.65, 0.4));  // inside the table
  EXPECT_FALSE(Contains(*space, -0.4, 2.0, 1.5));  // outside the walls, two voxels
  EXPECT_FALSE(Contains(*space, 3.0, -0.3, 1.0));  // in front of the door
  EXPECT_FALSE(Contains(*space, 6.5, 2.0, 1.5));
  EXPECT_FALSE(Contains(*space, 100.0, 2.0, 1.5));  // off the grid
  // A place to stand: at mid-height, away from the walls.
  const std::array<double, 3> deepest = space->Deepest();
  EXPECT_NEAR(deepest[2], 1.5, 0.3);
  EXPECT_GT(deepest[0], 1.0);
  EXPECT_LT(deepest[0], 5.0);
  EXPECT_GT(deepest[1], 1.0);
  EXPECT_LT(deepest[1], 3.5);
}

// An opening wider than 2 * gap_m leaves the inside connected to the
// outside: no enclosed space (the documented limit; points.normals'
// `interior: yes` is for such rooms).
TEST(EnclosureTest, WideOpeningEnclosesNothing) {
  const PointCloud room = RoomWithTable(6.0, 4.5, 2.0, 3);
  const Expected<EnclosedSpace> space = EnclosedSpace::Find(room);
  ASSERT_TRUE(space.ok());
  EXPECT_TRUE(space->empty());
  EXPECT_EQ(space->volume_m3(), 0.0);
  EXPECT_FALSE(Contains(*space, 3.0, 2.0, 1.5));
}

// Objects scanned from outside: their surface, grown by gap_m, fills their
// inside. A 2 m ball, a 3 m tall statue-like ellipsoid, a small one.
TEST(EnclosureTest, ObjectsEncloseNothing) {
  const double center[3] = {10.0, -3.0, 1.0};
  for (const double radius : {0.1, 1.0}) {
    PointCloud ball;
    AddSphere(ball, center, radius, 40000, 0.001, 4);
    const Expected<EnclosedSpace> space = EnclosedSpace::Find(ball);
    ASSERT_TRUE(space.ok());
    EXPECT_TRUE(space->empty()) << "radius " << radius << ": " << space->volume_m3() << " m3";
  }
  PointCloud statue;
  AddSphere(statue, center, 1.0, 60000, 0.001, 5);
  for (size_t i = 0; i < statue.size(); ++i) {  // 1 x 0.7 x 3 m
    statue.positions[3 * i] = float(center[0] + 0.5 * (statue.positions[3 * i] - center[0]));
    statue.positions[3 * i + 1] = float(center[1] + 0.35 * (statue.positions[3 * i + 1] - center[1]));
    statue.positions[3 * i + 2] = float(center[2] + 1.5 * (statue.positions[3 * i + 2] - center[2]));
  }
  const Expected<EnclosedSpace> space = EnclosedSpace::Find(statue);
  ASSERT_TRUE(space.ok());
  EXPECT_TRUE(space->empty()) << space->volume_m3() << " m3";
}

TEST(EnclosureTest, BadInput) {
  PointCloud cloud;
  EXPECT_THAT(EnclosedSpace::Find(cloud).status().message(), HasSubstr("no points"));
  cloud.positions = {0, 0, 0, 1, std::nanf(""), 0};
  EXPECT_THAT(EnclosedSpace::Find(cloud).status().message(), HasSubstr("point 1"));
  cloud.positions = {0, 0, 0};
  EXPECT_FALSE(EnclosedSpace::Find(cloud, {.gap_m = 0}).ok());
}

}  // namespace
}  // namespace pb
