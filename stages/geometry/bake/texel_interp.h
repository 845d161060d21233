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
// normals are re-normalized (a zero result takes the corners' interpolated
// normal, then (0, 0, 1)). Positions are in texel space (bake_raster.h).
// Samples are indexed corners 0-2, then the points in the order given;
// "ties to the lower index" refers to that. Decisions the paper leaves open
// (docs/bake-interpolation.md): kDelaunay averages samples at the same
// position into one vertex, and a face with collinear UV corners takes the
// nearest sample; points with a non-finite position are ignored; a face with
// no points, in every mode, gets the barycentric interpolation of its corners
// at BakeTexel::bary (what bake.vertex_colors writes).
#pragma once

#include <array>
#include <memory>
#include <span>
#include <vector>

#include "stages/geometry/bake/raster.h"

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
  // footprint is cut at 2 sigma. Texels no footprint covers are filled by
  // pull-push over the face's texel bounding box, the corners included.
  float splat_sigma_texels = 1;
  // false: the corners are samples only for a face with fewer than three
  // points, or whose points all lie on one line. For callers that pass the
  // points of the neighbouring faces too (bake.from_points' `neighbors`),
  // whose samples surround the face: the corners' values (a mesh's smooth
  // vertex colors) would otherwise draw slivers of their own color around
  // each corner, between it and the first points. Texels outside the
  // points' hull take the nearest hull triangle's clamped interpolation
  // (kDelaunay) or the nearest samples (the others).
  bool corner_samples = true;
};

// One per thread: keeps scratch buffers between faces (CGAL's triangulation
// frees and reallocates its few blocks per face). A moved-from interpolator
// may be used again.
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
