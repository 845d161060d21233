// Voxel-grid downsampling of a point cloud: one output point per occupied
// cubic voxel, the mean of the points inside it.
//
// The grid is aligned to absolute coordinates (cell = floor((origin + p) /
// voxel_m)), so clouds that share a scene but not an origin downsample onto
// the same grid. Per voxel the output has
//   position: the mean position (accumulated in double),
//   color:    the mean of each channel, rounded to nearest,
//   normal:   the mean normal renormalized to unit length; if the normals
//             cancel out (length < 1e-12) the first input point's normal,
// and output points are sorted by voxel (x, then y, then z cell index), so
// the result does not depend on the input order of voxels. Cost: O(N log N)
// time, 16 bytes per input point of scratch memory.
#pragma once

#include "base/status.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

struct VoxelDownsampleOptions {
  double voxel_m = 0.01;  // voxel edge length, meters, > 0
};

// Status::Invalid if voxel_m <= 0 (or not finite), or if the cloud spans more
// than 2^21 voxels along an axis (choose a larger voxel).
Expected<PointCloud> VoxelDownsample(const PointCloud& cloud, const VoxelDownsampleOptions& options = {});

}  // namespace pb
