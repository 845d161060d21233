// Point-to-face assignment for the paper's point-based detail transfer
// (paper, "Detail Transfer Algorithm", lines 5-10 and 20-28 of its
// pseudo-code): every scan point goes to the face of the low mesh it lies on,
// keeping its barycentric coordinates, and so to a position in the face's UV
// triangle (texel space, bake_raster.h).
//
// "The face it lies on": the nearest face (Euclidean distance from the point
// to the closest point of the triangle) among those within max_distance_m
// whose face normal is within max_angle_deg of the point's normal; the
// point's position on the face is that closest point. Points with no such
// face are dropped. A spatial grid over the faces keeps this O(N log M)-ish
// (each point tests the faces registered in its cell), not a per-face scan.
// Faces of zero area are never chosen. A point whose normal is zero or not
// finite skips the angle test; a point with a non-finite position is dropped
// and counted in AssignReport::non_finite.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/mesh.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

struct AssignOptions {
  double max_distance_m = 0.01;  // > 0
  // Angle between the point's normal and the face normal; 180 (or a cloud
  // without normals) disables the test. Orientation matters: 120 accepts a
  // point whose normal is 100 degrees off, 45 only nearly parallel ones.
  double max_angle_deg = 90;
  int size = 4096;               // texel space of a size x size map
  int threads = 0;               // 0 = all; never changes the output
  std::function<void(double)> progress;
};

struct AssignReport {
  size_t points = 0;
  size_t assigned = 0;
  size_t too_far = 0;       // no face within max_distance_m
  size_t wrong_angle = 0;   // faces within reach, none within max_angle_deg
  size_t non_finite = 0;    // NaN or infinite position (dropped)
  // points == assigned + too_far + wrong_angle + non_finite
  double mean_distance_m = 0;  // over assigned points
  size_t faces_with_points = 0;
};

// The assigned points grouped by face: the points of face f are
// [face_begin[f], face_begin[f + 1]); within a face sorted by (s, t, color,
// normal), so the grouping does not depend on the thread count.
struct MappedPoints {
  std::vector<uint64_t> face_begin;  // face_count + 1 offsets
  std::vector<float> st;             // 2 per point: texel-space position
  std::vector<uint8_t> colors;       // 3 per point, sRGB (empty if the cloud had none)
  std::vector<float> normals;        // 3 per point, the cloud's normal as given (empty if none)

  size_t size() const { return st.size() / 2; }
};

// Consumes `cloud` and reuses its arrays, so peak memory stays near the
// cloud's own size plus O(faces + grid): ~120 bytes per face, 4 per face and
// thread, the grid (~11 bytes per face-cell registration, ~10 registrations
// a face at the default cell size; 29 MB for 2.5e5 faces). Positions become
// st in place, the points are bucket-sorted by face in place, and the memory
// of the dropped points and of the third st float is returned to the system
// (the vectors keep their capacity; the pages past size() are released).
// Measured: 3e7 points onto 2.5e5 faces add 63 MB to the RSS
// (docs/bench-point-assign.md). The mesh needs uvs, finite positions and
// uvs, and must fail no Validate; the cloud's origin may differ from the
// mesh's (the work is done in the mesh's frame, the offset in double).
// Status::Invalid for bad options (max_distance_m <= 0 or not finite,
// max_angle_deg outside [0, 180], size < 1) or input (also 2^32 - 1 points
// or more).
Expected<MappedPoints> AssignPointsToFaces(const Mesh& mesh, PointCloud&& cloud,
                                           const AssignOptions& options,
                                           AssignReport* report = nullptr);

}  // namespace pb
