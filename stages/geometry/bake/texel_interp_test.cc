#include "stages/geometry/bake/texel_interp.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

namespace pb {
namespace {

using Vec3 = std::array<float, 3>;
constexpr TexelInterpolation kAllModes[] = {TexelInterpolation::kDelaunay, TexelInterpolation::kNearest,
                                           TexelInterpolation::kIdw, TexelInterpolation::kSplat};

TexelSample Sample(float s, float t, Vec3 color, Vec3 normal = {0, 0, 1}) {
  TexelSample sample;
  sample.s = s, sample.t = t, sample.color = color, sample.normal = normal;
  return sample;
}

// Barycentric coordinates of (s, t) in the corners' triangle.
std::array<float, 3> Bary(const std::array<TexelSample, 3>& c, double s, double t) {
  double det = (c[1].t - c[2].t) * (c[0].s - c[2].s) + (c[2].s - c[1].s) * (c[0].t - c[2].t);
  double w0 = ((c[1].t - c[2].t) * (s - c[2].s) + (c[2].s - c[1].s) * (t - c[2].t)) / det;
  double w1 = ((c[2].t - c[0].t) * (s - c[2].s) + (c[0].s - c[2].s) * (t - c[2].t)) / det;
  return {float(w0), float(w1), float(1 - w0 - w1)};
}

// The texels whose centres lie inside or on the corners' triangle, row-major,
// as BakeRaster::TexelsOf gives them.
std::vector<BakeTexel> TexelsInside(const std::array<TexelSample, 3>& c) {
  std::vector<BakeTexel> texels;
  int x0 = int(std::floor(std::min({c[0].s, c[1].s, c[2].s})));
  int x1 = int(std::ceil(std::max({c[0].s, c[1].s, c[2].s})));
  int y0 = int(std::floor(std::min({c[0].t, c[1].t, c[2].t})));
  int y1 = int(std::ceil(std::max({c[0].t, c[1].t, c[2].t})));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      BakeTexel texel;
      texel.x = x, texel.y = y, texel.s = x + 0.5f, texel.t = y + 0.5f;
      texel.bary = Bary(c, texel.s, texel.t);
      if (texel.bary[0] < -1e-6f || texel.bary[1] < -1e-6f || texel.bary[2] < -1e-6f) continue;
      texels.push_back(texel);
    }
  }
  return texels;
}

const BakeTexel& TexelAt(const std::vector<BakeTexel>& texels, int x, int y, size_t* index) {
  for (size_t i = 0; i < texels.size(); ++i) {
    if (texels[i].x == x && texels[i].y == y) {
      *index = i;
      return texels[i];
    }
  }
  ADD_FAILURE() << "no texel " << x << "," << y;
  *index = 0;
  return texels[0];
}

// A right triangle of legs 16 texels with corner A on a texel centre.
std::array<TexelSample, 3> RightTriangle() {
  return {Sample(0.5f, 0.5f, {100, 0, 0}, {0, 0, 1}),
          Sample(16.5f, 0.5f, {0, 100, 0}, {0, 1, 0}),
          Sample(0.5f, 16.5f, {0, 0, 100}, {1, 0, 0})};
}

struct Output {
  std::vector<Vec3> colors, normals;
};

Output Interp(FaceInterpolator& interpolator, const std::array<TexelSample, 3>& corners,
           const std::vector<TexelSample>& points, const std::vector<BakeTexel>& texels,
           TexelInterpolationOptions options) {
  Output out;
  interpolator.Interpolate(corners, points, texels, options, out.colors, out.normals);
  EXPECT_EQ(out.colors.size(), texels.size());
  EXPECT_EQ(out.normals.size(), texels.size());
  return out;
}

Output Interp(const std::array<TexelSample, 3>& corners, const std::vector<TexelSample>& points,
           const std::vector<BakeTexel>& texels, TexelInterpolation mode) {
  FaceInterpolator interpolator;
  TexelInterpolationOptions options;
  options.mode = mode;
  return Interp(interpolator, corners, points, texels, options);
}

float Length(const Vec3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

TEST(TexelInterpTest, NoPointsGivesCornerInterpolationInEveryMode) {
  auto corners = RightTriangle();
  auto texels = TexelsInside(corners);
  ASSERT_EQ(texels.size(), 153u);  // centres with x + y <= 16: 17 * 18 / 2
  for (TexelInterpolation mode : kAllModes) {
    Output out = Interp(corners, {}, texels, mode);
    for (size_t i = 0; i < texels.size(); ++i) {
      const auto& b = texels[i].bary;
      for (int k = 0; k < 3; ++k) {
        double color = b[0] * double(corners[0].color[k]) + b[1] * double(corners[1].color[k]) +
                       b[2] * double(corners[2].color[k]);
        EXPECT_FLOAT_EQ(out.colors[i][k], float(color)) << int(mode) << " texel " << i;
      }
      // Corner normals are the axes: the blend is (b2, b1, b0), normalized.
      double length = std::sqrt(double(b[0]) * b[0] + double(b[1]) * b[1] + double(b[2]) * b[2]);
      EXPECT_NEAR(out.normals[i][0], b[2] / length, 1e-6);
      EXPECT_NEAR(out.normals[i][1], b[1] / length, 1e-6);
      EXPECT_NEAR(out.normals[i][2], b[0] / length, 1e-6);
    }
  }
}

TEST(TexelInterpTest, DelaunayIsExactAtAPointAndLinearAlongItsEdges) {
  auto corners = RightTriangle();
  auto texels = TexelsInside(corners);
  std::vector<TexelSample> points = {Sample(4.5f, 4.5f, {200, 40, 60}, {0, 0, 1})};
  Output out = Interp(corners, points, texels, TexelInterpolation::kDelaunay);
  size_t i = 0;
  TexelAt(texels, 4, 4, &i);
  EXPECT_EQ(out.colors[i], (Vec3{200, 40, 60}));
  // (2.5, 2.5) is halfway along the Delaunay edge from A = (0.5, 0.5),
  // color (100, 0, 0), to the point: (150, 20, 30).
  TexelAt(texels, 2, 2, &i);
  EXPECT_NEAR(out.colors[i][0], 150, 1e-4);
  EXPECT_NEAR(out.colors[i][1], 20, 1e-4);
  EXPECT_NEAR(out.colors[i][2], 30, 1e-4);
  // A quarter of the way: 0.75 A + 0.25 P = (125, 10, 15).
  TexelAt(texels, 1, 1, &i);
  EXPECT_NEAR(out.colors[i][0], 125, 1e-4);
  EXPECT_NEAR(out.colors[i][1], 10, 1e-4);
  EXPECT_NEAR(out.colors[i][2], 15, 1e-4);
  // A's texel is A's color.
  TexelAt(texels, 0, 0, &i);
  EXPECT_EQ(out.colors[i], (Vec3{100, 0, 0}));
}

Vec3 Ramp(double s, double t) {
  return {float(10 + 3 * s + 2 * t), float(100 - 2 * s + t), float(50 + s - t)};
}

TEST(TexelInterpTest, LinearRampIsReproducedExactlyByDelaunayApproximatelyByOthers) {
  auto corners = RightTriangle();
  for (auto& c : corners) c.color = Ramp(c.s, c.t);
  auto texels = TexelsInside(corners);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<TexelSample> points;
  while (points.size() < 150) {
    float a = u(rng), b = u(rng);
    if (a + b > 1) continue;
    float s = 0.5f + 16 * a, t = 0.5f + 16 * b;
    points.push_back(Sample(s, t, Ramp(s, t)));
  }
  auto mean_error = [&](TexelInterpolation mode, double* max_error) {
    TexelInterpolationOptions options;
    options.mode = mode;
    options.splat_sigma_texels = 1.0f;
    FaceInterpolator interpolator;
    Output out = Interp(interpolator, corners, points, texels, options);
    double sum = 0;
    *max_error = 0;
    for (size_t i = 0; i < texels.size(); ++i) {
      Vec3 truth = Ramp(texels[i].s, texels[i].t);
      for (int k = 0; k < 3; ++k) {
        double e = std::abs(double(out.colors[i][k]) - truth[k]);
        sum += e;
        *max_error = std::max(*max_error, e);
      }
    }
    return sum / (3 * texels.size());
  };
  double max_delaunay = 0, max_nearest = 0, max_idw = 0, max_splat = 0;
  mean_error(TexelInterpolation::kDelaunay, &max_delaunay);
  double nearest = mean_error(TexelInterpolation::kNearest, &max_nearest);
  double idw = mean_error(TexelInterpolation::kIdw, &max_idw);
  double splat = mean_error(TexelInterpolation::kSplat, &max_splat);
  EXPECT_LT(max_delaunay, 1e-3);  // linear precision, up to float rounding
  EXPECT_GT(nearest, 0.3);        // the test can tell exact from approximate
  EXPECT_LT(idw, 1.5);
  EXPECT_LT(max_idw, 6);
  EXPECT_LT(splat, 1.5);
  EXPECT_LT(max_splat, 6);
}

TEST(TexelInterpTest, NearestPicksTheNearestAndTiesGoToTheLowerIndex) {
  auto corners = RightTriangle();
  auto texels = TexelsInside(corners);
  size_t at44 = 0, at00 = 0, at76 = 0;
  TexelAt(texels, 4, 4, &at44);
  TexelAt(texels, 0, 0, &at00);
  TexelAt(texels, 7, 6, &at76);
  // (3.5, 4.5) and (5.5, 4.5) are both 1 texel from (4.5, 4.5).
  std::vector<TexelSample> points = {Sample(3.5f, 4.5f, {1, 1, 1}), Sample(5.5f, 4.5f, {2, 2, 2}),
                                     Sample(7.4f, 6.6f, {3, 3, 3}), Sample(0.5f, 1.5f, {4, 4, 4})};
  Output out = Interp(corners, points, texels, TexelInterpolation::kNearest);
  EXPECT_EQ(out.colors[at44], (Vec3{1, 1, 1}));
  EXPECT_EQ(out.colors[at76], (Vec3{3, 3, 3}));
  EXPECT_EQ(out.colors[at00], (Vec3{100, 0, 0}));  // corner A itself
  std::swap(points[0], points[1]);
  out = Interp(corners, points, texels, TexelInterpolation::kNearest);
  EXPECT_EQ(out.colors[at44], (Vec3{2, 2, 2}));
  // A point on corner A ties with the corner, which comes first.
  points.push_back(Sample(0.5f, 0.5f, {5, 5, 5}));
  out = Interp(corners, points, texels, TexelInterpolation::kNearest);
  EXPECT_EQ(out.colors[at00], (Vec3{100, 0, 0}));
}

TEST(TexelInterpTest, IdwWeightsByInverseDistanceAndIsExactOnASample) {
  auto corners = RightTriangle();
  auto texels = TexelsInside(corners);
  std::vector<TexelSample> points = {Sample(3.5f, 4.5f, {100, 100, 100}),
                                     Sample(6.5f, 4.5f, {200, 200, 200})};
  TexelInterpolationOptions options;
  options.mode = TexelInterpolation::kIdw;
  options.idw_neighbors = 2;
  options.idw_power = 2;
  FaceInterpolator interpolator;
  Output out = Interp(interpolator, corners, points, texels, options);
  size_t i = 0;
  // Distances 1 and 2, weights 1 and 1/4: (100 + 200 / 4) / 1.25 = 120.
  TexelAt(texels, 4, 4, &i);
  EXPECT_NEAR(out.colors[i][0], 120, 1e-4);
  TexelAt(texels, 3, 4, &i);
  EXPECT_EQ(out.colors[i], (Vec3{100, 100, 100}));
}

TEST(TexelInterpTest, SplatFillsUncoveredTexelsByPullPush) {
  auto corners = RightTriangle();
  for (auto& c : corners) c.color = {150, 150, 150};
  auto texels = TexelsInside(corners);
  std::vector<TexelSample> points = {Sample(2.5f, 2.5f, {100, 100, 100}, {0, 0, 1}),
                                     Sample(10.5f, 2.5f, {200, 200, 200}, {1, 0, 0})};
  TexelInterpolationOptions options;
  options.mode = TexelInterpolation::kSplat;
  options.splat_sigma_texels = 0.5f;  // footprint radius 1 texel
  FaceInterpolator interpolator;
  Output out = Interp(interpolator, corners, points, texels, options);
  size_t i = 0;
  TexelAt(texels, 2, 2, &i);  // covered by the first point only
  EXPECT_EQ(out.colors[i], (Vec3{100, 100, 100}));
  TexelAt(texels, 10, 2, &i);
  EXPECT_EQ(out.colors[i], (Vec3{200, 200, 200}));
  TexelAt(texels, 3, 2, &i);  // at exactly 2 sigma: still covered
  EXPECT_EQ(out.colors[i], (Vec3{100, 100, 100}));
  TexelAt(texels, 6, 2, &i);  // no footprint: pull-push
  EXPECT_GT(out.colors[i][0], 100.5f);
  EXPECT_LT(out.colors[i][0], 199.5f);
  size_t uncovered = 0;
  for (size_t j = 0; j < texels.size(); ++j) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(out.colors[j][k], 100 - 1e-3f);
      EXPECT_LE(out.colors[j][k], 200 + 1e-3f);
    }
    EXPECT_NEAR(Length(out.normals[j]), 1, 1e-5);
    uncovered += (out.colors[j][0] != 100 && out.colors[j][0] != 200);
  }
  EXPECT_GT(uncovered, 100u);
}

std::vector<TexelSample> RandomPoints(const std::array<TexelSample, 3>& c, size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1), v(-1, 1);
  std::vector<TexelSample> points;
  while (points.size() < n) {
    float a = u(rng), b = u(rng);
    if (a + b > 1) continue;
    float s = c[0].s + a * (c[1].s - c[0].s) + b * (c[2].s - c[0].s);
    float t = c[0].t + a * (c[1].t - c[0].t) + b * (c[2].t - c[0].t);
    Vec3 n3 = {v(rng), v(rng), v(rng)};
    float length = Length(n3);
    if (length < 0.1f) continue;
    points.push_back(Sample(s, t, {255 * u(rng), 255 * u(rng), 255 * u(rng)},
                            {n3[0] / length, n3[1] / length, n3[2] / length}));
  }
  return points;
}

TEST(TexelInterpTest, NormalsAreUnitLength) {
  auto corners = RightTriangle();
  auto texels = TexelsInside(corners);
  auto points = RandomPoints(corners, 80, 3);
  // Two opposite normals at one position average to zero: the corners'
  // normal is used instead.
  points.push_back(Sample(8.5f, 4.5f, {0, 0, 0}, {0, 0, 1}));
  points.push_back(Sample(8.5f, 4.5f, {0, 0, 0}, {0, 0, -1}));
  for (TexelInterpolation mode : kAllModes) {
    Output out = Interp(corners, points, texels, mode);
    for (size_t i = 0; i < texels.size(); ++i) {
      EXPECT_NEAR(Length(out.normals[i]), 1, 1e-5) << int(mode) << " texel " << i;
    }
  }
}

TEST(TexelInterpTest, DuplicatesCornersEdgesAndOutsideSamplesAreHandled) {
  auto corners = RightTriangle();
  auto texels = TexelsInside(corners);
  std::vector<TexelSample> points = {
      Sample(4.5f, 4.5f, {10, 10, 10}), Sample(4.5f, 4.5f, {30, 30, 30}),   // duplicates
      Sample(0.5f, 0.5f, {200, 0, 0}),                                      // on corner A
      Sample(8.5f, 0.5f, {0, 0, 0}),                                        // on edge AB
      Sample(4.5f, 12.5f, {50, 50, 50}),                                    // on edge BC
      Sample(std::nanf(""), 3.0f, {9, 9, 9})};                             // ignored
  // A texel whose sample a rounding put just outside the face.
  BakeTexel outside = texels[0];
  outside.s = 0.4999f, outside.t = 3.5f;
  outside.bary = Bary(corners, 0.5, 3.5);
  texels.push_back(outside);
  Output out = Interp(corners, points, texels, TexelInterpolation::kDelaunay);
  size_t i = 0;
  TexelAt(texels, 4, 4, &i);
  EXPECT_EQ(out.colors[i], (Vec3{20, 20, 20}));  // duplicates averaged
  TexelAt(texels, 0, 0, &i);
  EXPECT_EQ(out.colors[i], (Vec3{150, 0, 0}));  // corner and point averaged
  TexelAt(texels, 8, 0, &i);
  EXPECT_EQ(out.colors[i], (Vec3{0, 0, 0}));
  // Halfway between the averaged A (150, 0, 0) and the edge point.
  TexelAt(texels, 4, 0, &i);
  EXPECT_NEAR(out.colors[i][0], 75, 1e-4);
  // The outside texel: on edge CA, between A's (150,0,0) and C's (0,0,100).
  Vec3 last = out.colors.back();
  EXPECT_GE(last[0], 0);
  EXPECT_LE(last[0], 150);
  EXPECT_GE(last[2], 0);
  EXPECT_LE(last[2], 100);
  for (TexelInterpolation mode : kAllModes) {
    Output first = Interp(corners, points, texels, mode);
    Output second = Interp(corners, points, texels, mode);
    EXPECT_EQ(first.colors, second.colors);
    EXPECT_EQ(first.normals, second.normals);
    for (const Vec3& c : first.colors) {
      for (float x : c) EXPECT_TRUE(std::isfinite(x)) << int(mode);
    }
  }
}

TEST(TexelInterpTest, CollinearFaceFallsBackToTheNearestSample) {
  std::array<TexelSample, 3> corners = {Sample(0.5f, 0.5f, {10, 0, 0}), Sample(4.5f, 4.5f, {20, 0, 0}),
                                        Sample(8.5f, 8.5f, {30, 0, 0})};
  std::vector<BakeTexel> texels;
  for (int k = 0; k <= 8; ++k) {
    BakeTexel texel;
    texel.x = k, texel.y = k, texel.s = k + 0.5f, texel.t = k + 0.5f;
    texel.bary = {1 - k / 8.0f, 0, k / 8.0f};
    texels.push_back(texel);
  }
  std::vector<TexelSample> points = {Sample(2.5f, 2.5f, {40, 0, 0}), Sample(6.5f, 6.5f, {50, 0, 0})};
  for (TexelInterpolation mode : kAllModes) {
    Output out = Interp(corners, points, texels, mode);
    for (const Vec3& c : out.colors) EXPECT_TRUE(std::isfinite(c[0])) << int(mode);
  }
  Output out = Interp(corners, points, texels, TexelInterpolation::kDelaunay);
  const float expected[] = {10, 10, 40, 20, 20, 20, 50, 30, 30};  // ties: lower index
  for (int k = 0; k <= 8; ++k) EXPECT_EQ(out.colors[k][0], expected[k]) << k;
}

TEST(TexelInterpTest, SameInputsGiveIdenticalOutputsAcrossReuseAndMoves) {
  auto corners = RightTriangle();
  auto texels = TexelsInside(corners);
  auto points_a = RandomPoints(corners, 120, 11);
  auto points_b = RandomPoints(corners, 300, 12);
  for (TexelInterpolation mode : kAllModes) {
    TexelInterpolationOptions options;
    options.mode = mode;
    FaceInterpolator interpolator;
    Output a1 = Interp(interpolator, corners, points_a, texels, options);
    Output b = Interp(interpolator, corners, points_b, texels, options);
    Output a2 = Interp(interpolator, corners, points_a, texels, options);
    EXPECT_EQ(a1.colors, a2.colors) << int(mode);
    EXPECT_EQ(a1.normals, a2.normals) << int(mode);
    EXPECT_NE(a1.colors, b.colors) << int(mode);
    FaceInterpolator moved = std::move(interpolator);
    Output a3 = Interp(moved, corners, points_a, texels, options);
    Output a4 = Interp(interpolator, corners, points_a, texels, options);  // moved-from
    EXPECT_EQ(a1.colors, a3.colors) << int(mode);
    EXPECT_EQ(a1.colors, a4.colors) << int(mode);
    FaceInterpolator assigned;
    assigned = std::move(moved);
    Output a5 = Interp(assigned, corners, points_a, texels, options);
    EXPECT_EQ(a1.normals, a5.normals) << int(mode);
  }
}

// An independent check of the triangulation: at every texel the output must
// be the linear interpolation in some triangle of samples that contains the
// texel's sample point and whose circumcircle holds no other sample (brute
// force over all triples).
TEST(TexelInterpTest, DelaunayMatchesABruteForceEmptyCircumcircleTriangle) {
  std::array<TexelSample, 3> corners = {Sample(0.5f, 0.5f, {100, 0, 0}),
                                        Sample(14.5f, 2.5f, {0, 100, 0}),
                                        Sample(3.5f, 13.5f, {0, 0, 100})};
  auto texels = TexelsInside(corners);
  for (uint32_t seed = 0; seed < 5; ++seed) {
    auto points = RandomPoints(corners, 14, 100 + seed);
    std::vector<TexelSample> all(corners.begin(), corners.end());
    all.insert(all.end(), points.begin(), points.end());
    Output out = Interp(corners, points, texels, TexelInterpolation::kDelaunay);
    const size_t n = all.size();
    for (size_t i = 0; i < texels.size(); ++i) {
      double qs = texels[i].s, qt = texels[i].t;
      bool found = false;
      for (size_t a = 0; a < n && !found; ++a) {
        for (size_t b = a + 1; b < n && !found; ++b) {
          for (size_t c = b + 1; c < n && !found; ++c) {
            const TexelSample &A = all[a], &B = all[b], &C = all[c];
            double as = A.s, at = A.t, bs = B.s, bt = B.t, cs = C.s, ct = C.t;
            double det = (bt - ct) * (as - cs) + (cs - bs) * (at - ct);
            if (std::abs(det) < 1e-9) continue;
            double w0 = ((bt - ct) * (qs - cs) + (cs - bs) * (qt - ct)) / det;
            double w1 = ((ct - at) * (qs - cs) + (as - cs) * (qt - ct)) / det;
            double w2 = 1 - w0 - w1;
            // Texels on the hull edges have a weight ~0 up to rounding.
            if (w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9) continue;
            // Circumcircle empty: the in-circle determinant of every other
            // sample, oriented by the triangle, is not positive beyond its
            // rounding error.
            auto strictly_inside = [&](const TexelSample& d) {
              double ax = as - d.s, ay = at - d.t, bx = bs - d.s, by = bt - d.t;
              double cx = cs - d.s, cy = ct - d.t;
              double t0 = (ax * ax + ay * ay) * (bx * cy - cx * by);
              double t1 = -(bx * bx + by * by) * (ax * cy - cx * ay);
              double t2 = (cx * cx + cy * cy) * (ax * by - bx * ay);
              double v = det > 0 ? t0 + t1 + t2 : -(t0 + t1 + t2);
              return v > 1e-9 * (std::abs(t0) + std::abs(t1) + std::abs(t2));
            };
            bool empty = true;
            for (size_t d = 0; d < n && empty; ++d) {
              if (d != a && d != b && d != c && strictly_inside(all[d])) empty = false;
            }
            if (!empty) continue;
            bool match = true;
            for (int k = 0; k < 3; ++k) {
              double expected = w0 * A.color[k] + w1 * B.color[k] + w2 * C.color[k];
              match = match && std::abs(expected - out.colors[i][k]) < 1e-3;
            }
            found = match;
          }
        }
      }
      EXPECT_TRUE(found) << "seed " << seed << " texel " << texels[i].x << "," << texels[i].y;
    }
  }
}

// Many points and texels (the bucket grids' ring searches over many cells),
// and a long thin diagonal face whose texel bounding box is far larger than
// its texel count (pull-push on a coarsened grid).
TEST(TexelInterpTest, LargeAndSliverFacesStayWithinTheSampleRange) {
  auto big = RightTriangle();
  for (auto& c : big) c.s = 0.5f + (c.s - 0.5f) * 8, c.t = 0.5f + (c.t - 0.5f) * 8;  // legs 128
  auto big_texels = TexelsInside(big);
  auto big_points = RandomPoints(big, 5000, 21);
  std::array<TexelSample, 3> sliver = {Sample(0.5f, 0.5f, {10, 10, 10}),
                                       Sample(3000.5f, 3000.5f, {20, 20, 20}),
                                       Sample(3000.5f, 3001.5f, {30, 30, 30})};
  std::vector<BakeTexel> sliver_texels;
  for (int k = 0; k <= 3000; ++k) {
    BakeTexel texel;
    texel.x = k, texel.y = k, texel.s = k + 0.5f, texel.t = k + 0.5f;
    texel.bary = Bary(sliver, texel.s, texel.t);
    sliver_texels.push_back(texel);
  }
  std::vector<TexelSample> sliver_points = {Sample(1000.5f, 1000.7f, {40, 40, 40}),
                                            Sample(2000.5f, 2000.9f, {50, 50, 50})};
  for (TexelInterpolation mode : kAllModes) {
    TexelInterpolationOptions options;
    options.mode = mode;
    options.splat_sigma_texels = 0.4f;  // leaves most texels uncovered
    FaceInterpolator interpolator;
    Output out = Interp(interpolator, big, big_points, big_texels, options);
    for (size_t i = 0; i < big_texels.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        EXPECT_GE(out.colors[i][k], -1e-3f) << int(mode);
        EXPECT_LE(out.colors[i][k], 255 + 1e-3f) << int(mode);
      }
      EXPECT_NEAR(Length(out.normals[i]), 1, 1e-5);
    }
    out = Interp(interpolator, sliver, sliver_points, sliver_texels, options);
    for (size_t i = 0; i < sliver_texels.size(); ++i) {
      EXPECT_GE(out.colors[i][0], 10 - 1e-3f) << int(mode) << " texel " << i;
      EXPECT_LE(out.colors[i][0], 50 + 1e-3f) << int(mode) << " texel " << i;
    }
  }
}

TEST(TexelInterpTest, WithoutCornerSamplesThePointsAloneFillTheFace) {
  auto corners = RightTriangle();  // corner colors red, green, blue at 100
  auto texels = TexelsInside(corners);
  const Vec3 gray{200, 200, 200};
  // Three points in the middle of the face, gray: no texel may show a
  // corner's color, in any mode, inside or outside the points' hull.
  const std::vector<TexelSample> three = {Sample(3.5f, 3.5f, gray), Sample(9.5f, 3.5f, gray),
                                          Sample(3.5f, 9.5f, gray)};
  for (TexelInterpolation mode : kAllModes) {
    FaceInterpolator interpolator;
    TexelInterpolationOptions options;
    options.mode = mode;
    options.corner_samples = false;
    Output out = Interp(interpolator, corners, three, texels, options);
    for (size_t i = 0; i < texels.size(); ++i) {
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(out.colors[i][c], 200, 1e-3) << int(mode) << " texel " << i;
    }
    // The default keeps the corners: the texel on corner A is red's.
    options.corner_samples = true;
    out = Interp(interpolator, corners, three, texels, options);
    size_t a = 0;
    TexelAt(texels, 0, 0, &a);
    EXPECT_NEAR(out.colors[a][0], 100, 1e-3) << int(mode);
  }
  // Fewer than three points, or three on one line: the corners are samples
  // again (Delaunay), so the texel on corner A is red's.
  const std::vector<TexelSample> two = {Sample(3.5f, 3.5f, gray), Sample(9.5f, 3.5f, gray)};
  const std::vector<TexelSample> line = {Sample(3.5f, 3.5f, gray), Sample(6.5f, 3.5f, gray),
                                         Sample(9.5f, 3.5f, gray)};
  for (const auto* points : {&two, &line}) {
    FaceInterpolator interpolator;
    TexelInterpolationOptions options;
    options.corner_samples = false;
    Output out = Interp(interpolator, corners, *points, texels, options);
    size_t a = 0;
    TexelAt(texels, 0, 0, &a);
    EXPECT_EQ(out.colors[a], (Vec3{100, 0, 0})) << points->size() << " points";
  }
}

}  // namespace
}  // namespace pb
