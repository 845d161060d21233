// Points another station saw through (seen_through.h): two stations scan a
// wall, a floor and a pillar; a person stands in front of the wall while the
// first scans and is gone when the second does.
#include "stages/geometry/points/seen_through.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

#include "stages/geometry/points/spacing.h"
#include "stages/geometry/points/strays.h"

namespace pb {
namespace {

struct Box {
  std::array<double, 3> lo, hi;
};

// What part of the scene a sample fell on.
enum Part : uint8_t { kWall, kFloor, kPillar, kPerson };

constexpr Box kPillarBox{{-0.2, 1.8, 0.0}, {0.2, 2.2, 2.0}};
constexpr Box kPersonBox{{0.8, 2.5, 0.0}, {1.2, 2.8, 1.7}};

// Distance along the unit ray from `o` in `d` to the box, if it meets it.
std::optional<double> HitBox(const std::array<double, 3>& o, const std::array<double, 3>& d, const Box& box) {
  double near = 0, far = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) {
      if (o[a] < box.lo[a] || o[a] > box.hi[a]) return std::nullopt;
      continue;
    }
    double t0 = (box.lo[a] - o[a]) / d[a], t1 = (box.hi[a] - o[a]) / d[a];
    if (t0 > t1) std::swap(t0, t1);
    near = std::max(near, t0);
    far = std::min(far, t1);
  }
  if (near > far || near <= 0) return std::nullopt;
  return near;
}

struct Scan {
  PointCloud cloud;
  std::vector<uint8_t> part;
};

// Each station casts rays every `step` radians over the half space towards
// +y (latitudes -60..60 degrees) onto the wall y = 4, the floor z = 0 (up to
// the wall), the pillar and, for the stations in `sees_person`, the person.
// `shift`: added to the samples of station 1 (a registration error).
Scan ScanRoom(const std::vector<std::array<double, 3>>& stations, const std::vector<bool>& sees_person,
              double step = 0.008, std::array<double, 3> shift = {0, 0, 0}) {
  Scan scan;
  scan.cloud.origin = {0, 0, 0};
  for (size_t s = 0; s < stations.size(); ++s) {
    const std::array<double, 3>& o = stations[s];
    scan.cloud.stations.push_back(o);
    for (double lon = 0.35; lon < std::numbers::pi - 0.35; lon += step)
      for (double lat = -1.05; lat < 1.05; lat += step) {
        const std::array<double, 3> d = {std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
        double t = (4.0 - o[1]) / d[1];
        uint8_t part = kWall;
        if (d[2] < 0) {
          const double floor = -o[2] / d[2];
          if (floor < t) t = floor, part = kFloor;
        }
        if (const auto hit = HitBox(o, d, kPillarBox); hit && *hit < t) t = *hit, part = kPillar;
        if (sees_person[s])
          if (const auto hit = HitBox(o, d, kPersonBox); hit && *hit < t) t = *hit, part = kPerson;
        const std::array<double, 3> p = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
        if (std::abs(p[0]) > 3 || p[2] > 3) continue;  // the room is 6 m wide and 3 m high
        for (int a = 0; a < 3; ++a) scan.cloud.positions.push_back(float(p[a] + (s == 1 ? shift[a] : 0.0)));
        scan.cloud.station_ids.push_back(uint16_t(s));
        scan.part.push_back(part);
      }
  }
  return scan;
}

struct Counts {
  size_t seen[4] = {0, 0, 0, 0};
  size_t total[4] = {0, 0, 0, 0};
  size_t person_above = 0, seen_person_above = 0;
  SeenThroughReport report;
};

Counts SeenThrough(const Scan& scan, const SeenThroughOptions& options = {}) {
  Counts counts;
  Expected<std::vector<float>> spacing = LocalSpacing(scan.cloud, 8);
  EXPECT_TRUE(spacing.ok()) << spacing.status().message();
  Expected<std::vector<uint8_t>> seen = SeenThroughPoints(scan.cloud, *spacing, options, &counts.report);
  EXPECT_TRUE(seen.ok()) << seen.status().message();
  if (!seen.ok()) return counts;
  for (size_t i = 0; i < scan.part.size(); ++i) {
    // A person's sample whose ball reaches near the floor in front of it
    // stays (the feet): count those above 0.3 m apart.
    if (scan.part[i] == kPerson && scan.cloud.positions[i * 3 + 2] > 0.3f) {
      ++counts.person_above;
      counts.seen_person_above += (*seen)[i];
    }
    ++counts.total[scan.part[i]];
    counts.seen[scan.part[i]] += (*seen)[i];
  }
  EXPECT_EQ(counts.report.seen_through,
            counts.seen[kWall] + counts.seen[kFloor] + counts.seen[kPillar] + counts.seen[kPerson]);
  return counts;
}

const std::vector<std::array<double, 3>> kStations = {{-1.0, 0.0, 1.5}, {1.2, 0.3, 1.4}};

TEST(SeenThroughTest, APersonOnlyOneStationSawIsSeenThroughTheRoomIsNot) {
  const Counts counts = SeenThrough(ScanRoom(kStations, {true, false}));
  ASSERT_GT(counts.total[kPerson], 1000u);
  EXPECT_EQ(counts.report.stations, 2u);
  // Every sample of the person higher than 0.3 m goes; below, a sample
  // whose ball (3 local spacings, 7-12 cm here) or the cells read around it
  // reach the floor in front of it stays: 115 of 1,069 with the feet.
  EXPECT_EQ(counts.seen_person_above, counts.person_above);
  EXPECT_GE(double(counts.seen[kPerson]), 0.85 * double(counts.total[kPerson]))
      << counts.seen[kPerson] << " of " << counts.total[kPerson];
  EXPECT_EQ(counts.seen[kWall], 0u);
  EXPECT_EQ(counts.seen[kFloor], 0u);
  EXPECT_EQ(counts.seen[kPillar], 0u) << "the pillar both stations saw";
  // Most points were decided: the wall and floor both stations saw.
  EXPECT_GT(double(counts.report.decided), 0.5 * double(counts.total[kWall] + counts.total[kFloor]));
}

TEST(SeenThroughTest, APersonBothStationsSawIsNotSeenThrough) {
  const Counts counts = SeenThrough(ScanRoom(kStations, {true, true}));
  ASSERT_GT(counts.total[kPerson], 1000u);
  EXPECT_EQ(counts.report.seen_through, 0u);
}

TEST(SeenThroughTest, ARegistrationErrorBetweenTheStationsSeesThroughNothing) {
  // 8 mm off, more than a careful registration leaves, and the ball holds it.
  const Counts counts = SeenThrough(ScanRoom(kStations, {true, true}, 0.008, {0.005, -0.006, 0.003}));
  EXPECT_EQ(counts.report.seen_through, 0u);
}

// Two rooms 50 m apart, two stations each, a person only the first saw in
// the first room: the stations of either room read only that room's points
// (the others lie outside their reach), and find the same points as when
// every station reads every point's cone.
TEST(SeenThroughTest, ReadingOnlyThePointsWithinReachFindsTheSamePoints) {
  Scan scan = ScanRoom(kStations, {true, false});
  const Scan other = ScanRoom(kStations, {false, false});
  for (size_t i = 0; i < other.cloud.size(); ++i) {
    scan.cloud.positions.push_back(other.cloud.positions[i * 3] + 50.0f);
    scan.cloud.positions.push_back(other.cloud.positions[i * 3 + 1]);
    scan.cloud.positions.push_back(other.cloud.positions[i * 3 + 2]);
    scan.cloud.station_ids.push_back(uint16_t(other.cloud.station_ids[i] + 2));
    scan.part.push_back(other.part[i]);
  }
  for (const auto& at : kStations) scan.cloud.stations.push_back({at[0] + 50, at[1], at[2]});
  const Counts counts = SeenThrough(scan);
  EXPECT_EQ(counts.report.stations, 4u);
  EXPECT_GT(counts.person_above, 800u);
  EXPECT_EQ(counts.seen_person_above, counts.person_above);
  EXPECT_EQ(counts.report.seen_through, counts.seen[kPerson]);

  Expected<std::vector<float>> spacing = LocalSpacing(scan.cloud, 8);
  ASSERT_TRUE(spacing.ok());
  SeenThroughOptions every_point;
  every_point.within_reach_only = false;
  SeenThroughReport culled, every;
  Expected<std::vector<uint8_t>> a = SeenThroughPoints(scan.cloud, *spacing, {}, &culled);
  Expected<std::vector<uint8_t>> b = SeenThroughPoints(scan.cloud, *spacing, every_point, &every);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_TRUE(*a == *b);
  EXPECT_EQ(culled.seen_through, every.seen_through);
  // A point past a station's reach whose cone it would have read full (of
  // nearer samples) is not counted as decided by it: 1 of 123,246 here.
  EXPECT_LE(culled.decided, every.decided);
  EXPECT_GT(double(culled.decided), 0.999 * double(every.decided));
  // Without the cut every station reads the other three's points; with it,
  // only the other station's of its room.
  EXPECT_LT(double(culled.cones_read), 0.4 * double(every.cones_read))
      << culled.cones_read << " of " << every.cones_read;
  EXPECT_GT(culled.cones_read, scan.cloud.size() / 2);
}

// Progress: after each station, and, through RemoveAirPoints, after each
// pass of the air too; never backwards, ending at 1.
TEST(SeenThroughTest, SaysHowFarItIs) {
  const Scan scan = ScanRoom(kStations, {true, false});
  Expected<std::vector<float>> spacing = LocalSpacing(scan.cloud, 8);
  ASSERT_TRUE(spacing.ok());
  std::vector<double> seen_steps;
  SeenThroughOptions options;
  options.progress = [&](double f) { seen_steps.push_back(f); };
  ASSERT_TRUE(SeenThroughPoints(scan.cloud, *spacing, options).ok());
  EXPECT_EQ(seen_steps, (std::vector<double>{0.5, 1.0}));

  std::vector<double> air_steps;
  AirOptions air;
  air.progress = [&](double f) { air_steps.push_back(f); };
  AirReport report;
  Expected<PointCloud> kept = RemoveAirPoints(scan.cloud, air, 0, &report);
  ASSERT_TRUE(kept.ok()) << kept.status().message();
  EXPECT_GT(report.seen_through, 800u);  // the person (963 of 1,069 with the air's spacings)
  ASSERT_GE(air_steps.size(), 3u);  // the passes, then the two stations
  EXPECT_TRUE(std::is_sorted(air_steps.begin(), air_steps.end()));
  EXPECT_GT(air_steps.front(), 0.0);
  EXPECT_LE(air_steps.front(), 0.5);
  EXPECT_EQ(air_steps.back(), 1.0);
  EXPECT_EQ(std::count(air_steps.begin(), air_steps.end(), 0.75), 1);  // the first station done
}

TEST(SeenThroughTest, OneStationOrNoneSeesThroughNothing) {
  Scan one = ScanRoom({kStations[0]}, {true});
  Expected<std::vector<float>> spacing = LocalSpacing(one.cloud, 8);
  ASSERT_TRUE(spacing.ok());
  SeenThroughReport report;
  Expected<std::vector<uint8_t>> seen = SeenThroughPoints(one.cloud, *spacing, {}, &report);
  ASSERT_TRUE(seen.ok());
  EXPECT_EQ(report.seen_through, 0u);
  EXPECT_EQ(report.stations, 0u);
  one.cloud.station_ids.clear();
  one.cloud.stations.clear();
  seen = SeenThroughPoints(one.cloud, *spacing);
  ASSERT_TRUE(seen.ok());
  EXPECT_EQ(seen->size(), one.cloud.size());
}

TEST(SeenThroughTest, TheStraysOfACloudWithStationsAreWhatAnotherStationSawThroughToo) {
  // What render.splats and metrics.geometry ask: the scan's render leaves the
  // person out as the meshes do.
  const Scan scan = ScanRoom(kStations, {true, false});
  Expected<KnnIndex> index = KnnIndex::Build(scan.cloud.positions);
  ASSERT_TRUE(index.ok());
  Expected<SpacingAndStrays> with = LocalSpacingAndStrays(*index, {}, &scan.cloud);
  ASSERT_TRUE(with.ok()) << with.status().message();
  // The same points as the air stage's: spacings over the air's k (16).
  Expected<std::vector<float>> air_spacing = LocalSpacing(*index, StrayOptions{}.air.k);
  ASSERT_TRUE(air_spacing.ok());
  Expected<std::vector<uint8_t>> seen = SeenThroughPoints(scan.cloud, *air_spacing);
  ASSERT_TRUE(seen.ok());
  size_t seen_count = 0;
  for (size_t i = 0; i < seen->size(); ++i) {
    seen_count += (*seen)[i];
    if ((*seen)[i]) {
      EXPECT_EQ(with->stray[i], 1) << "point " << i;
    }
  }
  EXPECT_GT(seen_count, 800u);
  EXPECT_EQ(with->seen_through, seen_count);
  EXPECT_GE(with->air, seen_count);
  // Without the cloud, or with seen_through off, the person is no stray.
  Expected<SpacingAndStrays> without = LocalSpacingAndStrays(*index, {});
  ASSERT_TRUE(without.ok());
  StrayOptions off;
  off.air.seen_through = false;
  Expected<SpacingAndStrays> switched_off = LocalSpacingAndStrays(*index, off, &scan.cloud);
  ASSERT_TRUE(switched_off.ok());
  for (const SpacingAndStrays* local : {&*without, &*switched_off}) {
    EXPECT_EQ(local->seen_through, 0u);
    size_t person_strays = 0;
    for (size_t i = 0; i < scan.part.size(); ++i) person_strays += scan.part[i] == kPerson && local->stray[i];
    EXPECT_EQ(person_strays, 0u);
  }
  // A cloud of another size than the index is refused.
  Scan other = ScanRoom(kStations, {true, false}, 0.05);
  EXPECT_FALSE(LocalSpacingAndStrays(*index, {}, &other.cloud).ok());
}

TEST(SeenThroughTest, BadInputIsRefused) {
  Scan scan = ScanRoom(kStations, {true, false}, 0.05);
  Expected<std::vector<float>> spacing = LocalSpacing(scan.cloud, 8);
  ASSERT_TRUE(spacing.ok());
  std::vector<float> short_spacing(spacing->begin(), spacing->end() - 1);
  EXPECT_FALSE(SeenThroughPoints(scan.cloud, short_spacing).ok());
  EXPECT_FALSE(SeenThroughPoints(scan.cloud, *spacing, {.margin_spacings = -1}).ok());
  EXPECT_FALSE(SeenThroughPoints(scan.cloud, *spacing, {.margin_range = std::nan("")}).ok());
  Scan bad_station = scan;
  bad_station.cloud.station_ids[3] = 7;
  Expected<std::vector<uint8_t>> refused = SeenThroughPoints(bad_station.cloud, *spacing);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("point 3 names station 7"), std::string::npos)
      << refused.status().message();
  Scan nan = scan;
  nan.cloud.positions[3 * 5 + 1] = std::nanf("");
  refused = SeenThroughPoints(nan.cloud, *spacing);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("point 5"), std::string::npos) << refused.status().message();
}

}  // namespace
}  // namespace pb
