// Filling one face's texels from the scan points mapped onto it (the paper's
// point-based detail transfer, lines 11-17 of its pseudo-code) and the
// variants the campaign compares:
//   kDelaunay (the paper): 2-D Delaunay triangulation (CGAL) of the face's
//     three corners plus the mapped points, linear interpolation inside the
//     triangle that contains the texel's sample point;
//   kNearest: the value of the nearest sample (corners included);
//   kIdw: inverse-distance weighting of the k nearest samples;
//   kSplat: Gaussian-weighted mean of the samples whose footprint covers the
//     texel, pull-push filling of texels no footprint covers.
// Colors (sRGB values as stored) and world normals are interpolated alike;
// normals are re-normalized. Positions are in texel space (bake_raster.h).
#pragma once

#include <array>
#include <memory>
#include <span>
#include <vector>

#include "stages/geometry/bake_raster.h"

namespace pb {

enum class TexelInterpolation { kDelaunay, kNearest, kIdw, kSplat };

struct TexelSample {
  float s = 0, t = 0;              // texel space
  std::array<float, 3> color{};    // sRGB, 0..255
  std::array<float, 3> normal{};   // world, unit
};

struct TexelInterpolationOptions {
  TexelInterpolation mode = TexelInterpolation::kDelaunay;
  int idw_neighbors = 4;           // kIdw: k
  float idw_power = 2;             // kIdw: weight = 1 / distance^power
  // kSplat: Gaussian sigma of a point's footprint, in texels (the caller
  // converts the scan's point spacing with the face's texel density); the
  // footprint is cut at 2 sigma.
  float splat_sigma_texels = 1;
};

// One per thread: keeps scratch buffers between faces.
class FaceInterpolator {
 public:
  FaceInterpolator();
  ~FaceInterpolator();
  FaceInterpolator(FaceInterpolator&&) noexcept;
  FaceInterpolator& operator=(FaceInterpolator&&) noexcept;

  // corners: the face's three vertices as samples (UV corners in texel
  // space, vertex colors, vertex normals); points: the samples mapped into
  // the face. Writes colors[i] and normals[i] for texels[i] (resized to
  // texels.size()). Deterministic for the same arguments.
  void Interpolate(const std::array<TexelSample, 3>& corners, std::span<const TexelSample> points,
                   std::span<const BakeTexel> texels, const TexelInterpolationOptions& options,
                   std::vector<std::array<float, 3>>& colors,
                   std::vector<std::array<float, 3>>& normals);

 private:
  struct Scratch;
  std::unique_ptr<Scratch> scratch_;
};

}  // namespace pb
