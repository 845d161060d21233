// Texture bakes of a mesh with UVs into a color map and a tangent-space
// normal map (bake_raster.h has the conventions): the options and result
// every bake shares, and the simplest bake, from the mesh's own vertex
// colors (the paper's HPM and LPM workflows). The others:
// bake_from_mesh.h (Remeshing), bake_from_points.h (the paper's transfer).
#pragma once

#include <cstddef>
#include <functional>

#include "base/status.h"
#include "stages/geometry/bake/raster.h"
#include "stages/geometry/core/mesh.h"

namespace pb {

struct BakeOptions {
  int size = 4096;              // texels, width = height
  int gutter = 12;              // dilation passes (the authors' 25x25 = 12)
  bool float_normals = false;   // normal map as kF32 (for OpenEXR) not kU8
  int threads = 0;              // 0 = all; never changes the output
  std::function<void(double)> progress;  // fraction done, optional
};

struct BakeResult {
  Mesh mesh;      // the target with normals and tangents (PrepareBakeMesh)
  BakeMaps maps;
  size_t covered_texels = 0;  // texels some face owns
  size_t edge_texels = 0;     // of which conservative edge texels
  size_t gutter_texels = 0;   // filled by dilation
};

// Interpolates the mesh's vertex colors (as stored, sRGB) at every texel;
// the normal map is flat (0, 0, 1) everywhere: a mesh carries no detail
// finer than its vertices. Status::Invalid without uvs or vertex colors.
Expected<BakeResult> BakeVertexColors(Mesh mesh, const BakeOptions& options);

}  // namespace pb
