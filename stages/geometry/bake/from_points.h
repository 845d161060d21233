// bake.from_points: the paper's point-based detail transfer ("Detail
// Transfer Algorithm"): scan points are assigned to the low mesh's faces
// (point_assign.h), mapped into each face's UV triangle, and every texel of
// the face is filled from the face's corners plus its points
// (texel_interp.h), optionally with the points of its neighbours near their
// shared edges (FromPointsOptions::neighbors). Faces no point reached are
// filled from their corners' vertex colors, as bake.vertex_colors would.
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
  // false (the paper): a face's texels come from its corners and its own
  // points. true: a face with points of its own also takes the points of
  // the faces across its edges that lie near the shared edge (a band two
  // point spacings wide), unfolded about that edge into the face's UV
  // plane, and, with three or more points of its own, leaves its corners
  // out. The paper's per-face triangulation ends at the face's edges, so
  // its outermost points join the corners in long slivers in the corners'
  // color (the mesh's smooth vertex colors): stars around every vertex and
  // streaks along every edge wherever the points are sparse against the
  // texels. A face with no point of its own keeps its corners' blend.
  // Faces are neighbours when their edge's end points have the same
  // position, so UV seams do not separate them; an edge of more than two
  // faces has none.
  bool neighbors = false;
};

struct FromPointsReport {
  AssignReport assign;
  size_t faces_with_points = 0;
  size_t faces_from_corners = 0;  // faces owning texels but no points
  size_t points_borrowed = 0;     // `neighbors`: points used by a face across an edge
};

// Consumes the cloud (see AssignPointsToFaces for memory). The cloud needs
// colors; normals are used for the angle test and the normal map (without
// them the normal map is flat).
Expected<BakeResult> BakeFromPoints(Mesh low, PointCloud&& cloud, const BakeOptions& options,
                                    const FromPointsOptions& from_points,
                                    FromPointsReport* report = nullptr);

}  // namespace pb
