// PLY (Stanford polygon file format) reading and writing: the on-disk form of
// the `points` and `mesh` artifacts.
//
// The writer produces binary little-endian PLY that MeshLab, CloudCompare and
// Blender open directly:
//
//   ply
//   format binary_little_endian 1.0
//   comment pointbake points 1          <- signature + format version; "mesh"
//                                          for meshes. Bump the version when
//                                          the layout below changes.
//   comment origin X Y Z                <- double origin, printf %.17g, meters;
//                                          absolute = origin + stored position
//   comment station I X Y Z             <- points, optional: scanner position I
//                                          (0, 1, ... in order), absolute meters
//   element vertex N
//   property float x                    <- meters, relative to origin
//   property float y
//   property float z
//   property float nx                   <- optional, all three or none
//   property float ny
//   property float nz
//   property uchar red                  <- optional, sRGB 0..255
//   property uchar green
//   property uchar blue
//   property float s                    <- optional (meshes), texture coords
//   property float t
//   property float tx                   <- optional (meshes), tangent xyz + w
//   property float ty                      (handedness ±1, glTF convention)
//   property float tz
//   property float tw
//   property float intensity            <- optional (points), [0, 1]
//   property ushort station             <- optional (points), index of the
//                                          station that saw the point
//   property float NAME                 <- optional (meshes), per-vertex
//                                          scalars (WritePlyMeshWithScalars),
//                                          e.g. `quality`, MeshLab's vertex
//                                          quality; CloudCompare 2.11 loads
//                                          `scalar_X` as scalar field X (not
//                                          other names, and none when the
//                                          file has tangents). The reader
//                                          skips them, so the version stays.
//   element face M                      <- meshes only
//   property list uchar uint vertex_indices
//   end_header
//   <N vertex records, packed, in the property order above>
//   <M face records: uchar 3, then 3 uint32 indices>
//
// The reader is general: `ascii`, `binary_little_endian` and
// `binary_big_endian`; every PLY scalar type (char uchar short ushort int uint
// float double and int8 uint8 int16 uint16 int32 uint32 float32 float64);
// list properties; unknown elements and properties are skipped. It recognizes
//   vertex: x y z (any scalar type; non-float32 coordinates, e.g. georeferenced
//           doubles, are re-centered on an origin = their bounding-box center
//           rounded to 1 m), nx ny nz, red green blue (or diffuse_red ...;
//           uchar as is, ushort scaled to 8 bit, float/double in [0,1]; alpha
//           ignored), s t | u v | texture_u texture_v, tx ty tz tw,
//           intensity (or scalar_intensity), station (with the comments),
//           row and col (or column, rowIndex / columnIndex, row_index /
//           column_index: a structured scan's grid cell; with no station in
//           the file, its scanner is taken at the frame's origin when the
//           grid was swept from there, grid_station.h, with a warning);
//   face:   vertex_indices or vertex_index (polygons are fan-triangulated).
// It streams the file through a 1 MiB buffer: memory is the decoded arrays,
// never a copy of the file. `comment origin` restores the origin.
//
// Errors name the file and the place: header problems as `scan.ply:3: ...`
// (1-based line), body problems with the element index and the byte offset
// (binary) or the line (ascii), e.g.
//   scan.ply: truncated: vertex 1203 of 35947 at byte 48211
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "base/env.h"
#include "base/status.h"
#include "stages/geometry/core/mesh.h"
#include "stages/geometry/core/point_cloud.h"

namespace pb {

inline constexpr int kPlyPointsVersion = 2;  // 2: intensity, station  // "comment pointbake points 1"
inline constexpr int kPlyMeshVersion = 1;    // "comment pointbake mesh 1"

struct PlyReadOptions {
  // Drop vertices with a NaN or infinite coordinate (counted in
  // PlyReadReport::dropped_points) instead of failing on the first one.
  bool drop_invalid_points = false;
  // Called with the fraction of the file read, in [0,1], about once per MiB.
  std::function<void(double fraction)> progress;
  // ScanReadOptions::infer_stations: false skips the grid test of a
  // structured scan without a station (its warning with it).
  bool infer_stations = true;
};

struct PlyReadReport {
  std::string format;           // "ascii", "binary_little_endian", "binary_big_endian"
  uint64_t vertices_in_file = 0;
  uint64_t faces_in_file = 0;
  uint64_t dropped_points = 0;     // non-finite coordinates (drop_invalid_points)
  uint64_t dropped_triangles = 0;  // polygons with < 3 corners, or touching a dropped point
  std::string pointbake_kind;      // "points" or "mesh" if written by pointbake, else ""
  int pointbake_version = 0;       // 0 if not written by pointbake
  std::vector<std::string> comments;  // header comment and obj_info lines, without keyword
  // For the user, e.g. where a structured scan's scanner was taken to stand.
  std::vector<std::string> warnings;
};

struct PlyPoints {
  PointCloud points;
  PlyReadReport report;
};

struct PlyMesh {
  Mesh mesh;
  PlyReadReport report;
};

// Reads the vertices of any PLY file (faces are checked for structure but not
// kept).
Expected<PlyPoints> ReadPlyPoints(const std::string& path, const PlyReadOptions& options = {});
// Reads vertices and faces; a file without a face element gives a mesh
// without triangles.
Expected<PlyMesh> ReadPlyMesh(const std::string& path, const PlyReadOptions& options = {});

// Write the binary layout above to `path`, durably (env->NewAtomicFile:
// streamed to a temporary, fsynced, renamed; on failure `path` keeps what it
// held). Status::Invalid if the attribute arrays disagree with the vertex
// count.
Status WritePlyPoints(const std::string& path, const PointCloud& cloud, Env* env = Env::Default());
Status WritePlyMesh(const std::string& path, const Mesh& mesh, Env* env = Env::Default());

// One float per vertex, written as `property float NAME` after the mesh's
// attributes. NAME: letters, digits and '_', not a name the layout above uses.
struct PlyVertexScalar {
  std::string name;
  std::span<const float> values;
};
// WritePlyMesh plus `scalars` in order. Status::Invalid for a bad or
// repeated name or a size other than the vertex count.
Status WritePlyMeshWithScalars(const std::string& path, const Mesh& mesh, std::span<const PlyVertexScalar> scalars,
                               Env* env = Env::Default());

}  // namespace pb
