// bake.from_points: the paper's point-based detail transfer ("Detail
// Transfer Algorithm"): scan points are assigned to the low mesh's faces
// (point_assign.h), mapped into each face's UV triangle, and every texel of
// the face is filled from the face's corners plus its points
// (texel_interp.h). Faces no point reached are filled from their corners'
// vertex colors, as bake.vertex_colors would.
#pragma once

#include <cstddef>

#include "base/status.h"
#include "stages/geometry/bake/bake.h"
#include "stages/geometry/bake/point_assign.h"
#include "stages/geometry/core/point_cloud.h"
#include "stages/geometry/bake/texel_interp.h"

namespace pb {

struct FromPointsOptions {
  double max_distance_m = 0.01;
  double max_angle_deg = 90;
  TexelInterpolationOptions interpolation;
  // kSplat: a point's footprint sigma in meters (typically the scan's point
  // spacing); converted per face with its texel density.
  double splat_sigma_m = 0.002;
};

struct FromPointsReport {
  AssignReport assign;
  size_t faces_with_points = 0;
  size_t faces_from_corners = 0;  // faces owning texels but no points
};

// Consumes the cloud (see AssignPointsToFaces for memory). The cloud needs
// colors; normals are used for the angle test and the normal map (without
// them the normal map is flat).
Expected<BakeResult> BakeFromPoints(Mesh low, PointCloud&& cloud, const BakeOptions& options,
                                    const FromPointsOptions& from_points,
                                    FromPointsReport* report = nullptr);

}  // namespace pb
