#include "stages/geometry/points/enclosure.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "stages/geometry/testing/clouds.h"

namespace pb {
namespace {

using ::testing::HasSubstr;
using testing::AddBoxFaces;
using testing::AddSphere;
using testing::OpenCorridor;
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

// FindOpen: a room that Find cannot close in (open wider than 2 * gap_m,
// or too small) is found by what one sees from inside it.

TEST(EnclosureTest, CorridorOpenAtBothEndsIsNearlyEnclosed) {
  const PointCloud corridor = OpenCorridor();
  const Expected<EnclosedSpace> closed = EnclosedSpace::Find(corridor);
  ASSERT_TRUE(closed.ok());
  EXPECT_TRUE(closed->empty());  // the ends, 1.8 m wide, stay open
  const Expected<EnclosedSpace> space = EnclosedSpace::FindOpen(corridor);
  ASSERT_TRUE(space.ok()) << space.status().message();
  ASSERT_FALSE(space->empty());
  EXPECT_TRUE(space->open());
  EXPECT_FALSE(closed->open());
  // (10 - 0.75) x (1.8 - 0.75) x (2.6 - 0.75) m = 18 m3 less the ends,
  // from which the lines of sight along the corridor leave.
  EXPECT_GT(space->volume_m3(), 8.0);
  EXPECT_LT(space->volume_m3(), 18.5);
  EXPECT_TRUE(Contains(*space, 5.0, 0.9, 1.3));
  EXPECT_TRUE(Contains(*space, 5.0, 0.1, 1.3));  // beside a wall
  EXPECT_TRUE(Contains(*space, 2.0, 0.9, 0.1));  // on the floor
  EXPECT_FALSE(Contains(*space, 5.0, -0.4, 1.3));  // behind a wall
  EXPECT_FALSE(Contains(*space, 5.0, 0.9, 3.0));   // above the ceiling
  EXPECT_FALSE(Contains(*space, -1.0, 0.9, 1.3));  // out past an end
  const std::array<double, 3> deepest = space->Deepest();
  EXPECT_NEAR(deepest[1], 0.9, 0.3);
  EXPECT_GT(deepest[2], 0.6);
  EXPECT_LT(deepest[2], 2.0);
}

// A cell 2.2 x 2 x 2.5 m with a door: Find's gap fills it; FindOpen's not.
// And the room with a 2 m opening that Find leaves open.
TEST(EnclosureTest, SmallRoomAndWideOpeningAreNearlyEnclosed) {
  PointCloud cell;
  const double lo[3] = {0, 0, 0}, hi[3] = {2.2, 2.0, 2.5};
  AddBoxFaces(cell, lo, hi, 0.03, 0.002, 12, [](double x, double y, double z) {
    return y < 0.01 && z < 2.0 && x > 0.65 && x < 1.55;
  });
  const Expected<EnclosedSpace> closed = EnclosedSpace::Find(cell);
  ASSERT_TRUE(closed.ok());
  EXPECT_TRUE(closed->empty());
  const Expected<EnclosedSpace> space = EnclosedSpace::FindOpen(cell);
  ASSERT_TRUE(space.ok());
  EXPECT_FALSE(space->empty());
  EXPECT_TRUE(Contains(*space, 1.1, 1.0, 1.25));
  EXPECT_FALSE(Contains(*space, 1.1, -0.5, 1.0));  // out through the door

  const PointCloud room = RoomWithTable(6.0, 4.5, 2.0, 3);
  const Expected<EnclosedSpace> wide = EnclosedSpace::FindOpen(room);
  ASSERT_TRUE(wide.ok());
  EXPECT_GT(wide->volume_m3(), 8.0);
  EXPECT_TRUE(Contains(*wide, 4.5, 2.0, 1.5));
  EXPECT_FALSE(Contains(*wide, 2.4, 2.65, 0.4));  // inside the table
  EXPECT_FALSE(Contains(*wide, 3.0, -0.5, 1.0));  // out through the opening
}

// What FindOpen must not take for a room: objects (a 2 m ball closed all
// round; boxes standing on paving, not scanned underneath: a 1.6 m plinth,
// and a 3 m monument whose inside is large and surrounded but a cup, open
// below) and open scenes (two walls meeting in a corner on a yard, open
// to the sky; a statue in a niche of a wall, on the floor before it).
TEST(EnclosureTest, ObjectsAndOpenScenesAreNotNearlyEnclosed) {
  const double center[3] = {10.0, -3.0, 1.0};
  PointCloud ball;
  AddSphere(ball, center, 1.0, 60000, 0.001, 4);
  PointCloud plinth;  // a 1.6 x 1.6 x 2 m box on 6 x 6 m of paving
  const double plo[3] = {2.2, 2.2, 0}, phi[3] = {3.8, 3.8, 2.0};
  AddBoxFaces(plinth, plo, phi, 0.04, 0.002, 5, [](double, double, double z) { return z < 0.01; });
  const double glo[3] = {0, 0, -0.2}, ghi[3] = {6, 6, 0};
  AddBoxFaces(plinth, glo, ghi, 0.04, 0.002, 6, [&](double x, double y, double z) {
    return z < -0.01 || (x > plo[0] && x < phi[0] && y > plo[1] && y < phi[1]);
  });
  PointCloud monument;  // a 3 m cube on 9 x 9 m of paving
  const double mlo[3] = {3, 3, 0}, mhi[3] = {6, 6, 3}, mglo[3] = {0, 0, -0.2}, mghi[3] = {9, 9, 0};
  AddBoxFaces(monument, mlo, mhi, 0.05, 0.002, 10, [](double, double, double z) { return z < 0.01; });
  AddBoxFaces(monument, mglo, mghi, 0.05, 0.002, 11, [&](double x, double y, double z) {
    return z < -0.01 || (x > mlo[0] && x < mhi[0] && y > mlo[1] && y < mhi[1]);
  });
  PointCloud corner;  // walls 8 m long and 6 m tall on 8 x 8 m of yard
  const double wx[3] = {0, 0, 0}, wxh[3] = {8, 0.3, 6}, wy[3] = {0, 0, 0}, wyh[3] = {0.3, 8, 6};
  const double ylo[3] = {0, 0, -0.2}, yhi[3] = {8, 8, 0};
  auto inner = [](double, double, double) { return false; };
  AddBoxFaces(corner, wx, wxh, 0.05, 0.002, 7, inner);
  AddBoxFaces(corner, wy, wyh, 0.05, 0.002, 8, inner);
  AddBoxFaces(corner, ylo, yhi, 0.05, 0.002, 9, [](double, double, double z) { return z < -0.01; });
  // A statue in a niche 2 m wide, 1.2 m deep and 3.5 m tall in the front
  // of a wall 6 m wide and 5 m tall, on 6 x 6 m of floor before it: open to
  // the front and the sky.
  PointCloud niche;
  const double wlo[3] = {0, 0, 0}, whi[3] = {6, 1.5, 5}, nlo[3] = {2, 0, 0}, nhi[3] = {4, 1.2, 3.5};
  AddBoxFaces(niche, wlo, whi, 0.05, 0.002, 12, [&](double x, double y, double z) {
    return y > 0.01 || (x > nlo[0] && x < nhi[0] && z < nhi[2]);  // the wall's front, less the niche
  });
  AddBoxFaces(niche, nlo, nhi, 0.05, 0.002, 13, [](double, double y, double) { return y < 0.01; });
  const double flo[3] = {0, -6, -0.2}, fhi[3] = {6, 0, 0};
  AddBoxFaces(niche, flo, fhi, 0.05, 0.002, 14, [](double, double, double z) { return z < -0.01; });
  PointCloud figure;
  const double figure_center[3] = {3.0, 0.6, 0.9};
  AddSphere(figure, figure_center, 1.0, 30000, 0.001, 15);
  for (size_t i = 0; i < figure.size(); ++i) {  // 0.8 x 0.6 x 1.8 m, standing in the niche
    for (int a = 0; a < 3; ++a) {
      const double scale = a == 0 ? 0.4 : a == 1 ? 0.3 : 0.9;
      niche.positions.push_back(float(figure_center[a] + scale * (figure.positions[3 * i + a] - figure_center[a])));
    }
  }
  for (const auto& [name, cloud] : {std::pair<const char*, const PointCloud*>{"ball", &ball},
                                    {"plinth", &plinth}, {"monument", &monument}, {"corner", &corner},
                                    {"niche", &niche}}) {
    const Expected<EnclosedSpace> space = EnclosedSpace::FindOpen(*cloud);
    ASSERT_TRUE(space.ok()) << name;
    EXPECT_TRUE(space->empty()) << name << ": " << space->volume_m3() << " m3";
  }
}

TEST(EnclosureTest, BadInput) {
  PointCloud cloud;
  EXPECT_THAT(EnclosedSpace::Find(cloud).status().message(), HasSubstr("no points"));
  cloud.positions = {0, 0, 0, 1, std::nanf(""), 0};
  EXPECT_THAT(EnclosedSpace::Find(cloud).status().message(), HasSubstr("point 1"));
  cloud.positions = {0, 0, 0};
  EXPECT_FALSE(EnclosedSpace::Find(cloud, {.gap_m = 0}).ok());
  EXPECT_FALSE(EnclosedSpace::FindOpen(cloud, {.min_surrounded = 1.5}).ok());
  cloud.positions = {0, 0, 0, 1, std::nanf(""), 0};
  EXPECT_THAT(EnclosedSpace::FindOpen(cloud).status().message(), HasSubstr("point 1"));
}

}  // namespace
}  // namespace pb
