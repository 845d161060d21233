// Wavefront OBJ + MTL + PNG writing and reading: the `model` artifact's
// model.obj, model.mtl, color.png, normal.png, for MeshLab and Blender.
//
// What WriteObj writes next to `obj_path` (same folder, fixed names):
//   model.obj (the stem of obj_path)
//     # pointbake obj 1                    <- signature + version (kObjVersion)
//     # origin X Y Z                       <- the mesh's double origin, meters
//     # coordinates absolute               <- or "relative" (see below)
//     mtllib model.mtl
//     o NAME
//     v X Y Z [R G B]                      <- ABSOLUTE coordinates, meters:
//                                             origin + position in double,
//                                             shortest round-trip digits (OBJ
//                                             has no node transform); with
//                                             options.absolute_coordinates
//                                             false, the float positions
//                                             relative to the origin (viewers
//                                             that store float32, Blender and
//                                             MeshLab, round absolute
//                                             coordinates of 5e6 m to 0.5 m);
//                                             colors
//                                             in [0,1] (sRGB, the MeshLab /
//                                             Blender extension) when the mesh
//                                             has colors and options.vertex_colors
//     vt U V                               <- when the mesh has uvs; v up, as
//                                             OBJ (no flip)
//     vn X Y Z                             <- unit normals (ComputeVertexNormals
//                                             when the mesh has none)
//     usemtl NAME
//     f a/a/a b/b/b c/c/c                  <- 1-based; a//a without uvs
//   model.mtl
//     newmtl NAME, Ka 0 0 0, Kd 1 1 1, Ks 0 0 0, d 1, illum 1,
//     map_Kd color.png                     <- when a base color PNG is given
//     map_Bump normal.png, norm normal.png <- when a normal PNG is given:
//                                             tangent space, +Y up (Blender
//                                             reads map_Bump as a normal map)
//   color.png, normal.png                  <- the given PNG bytes, unchanged
// Frames stay in the mesh's (z-up) coordinates. OBJ has no tangents: viewers
// derive them from uvs and normals (MikkTSpace in Blender).
// The files are written as one durable set (WriteFilesAtomic, base/env.h):
// all are synced before any is renamed, the .obj last, so a write that fails
// (full disk, I/O error) leaves the earlier files as they were.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "base/env.h"
#include "base/status.h"
#include "stages/geometry/core/mesh.h"

namespace pb {

inline constexpr int kObjVersion = 1;

struct ObjWriteOptions {
  std::string name = "model";           // object and material name
  std::vector<uint8_t> base_color_png;  // PNG file bytes (sRGB); empty: none
  std::vector<uint8_t> normal_png;      // PNG file bytes (tangent space); empty: none
  bool vertex_colors = true;            // colors on the v lines
  bool absolute_coordinates = true;     // v = origin + position (else position)
};

struct ObjWriteReport {
  uint64_t bytes = 0;               // all files together
  std::vector<std::string> files;   // paths written: obj, mtl, then textures
  bool computed_normals = false;
};

// Status::Invalid for a mesh that fails Validate, has no triangles, has
// textures but no uvs, or a texture that is not a PNG; Status::Io naming
// the file when one cannot be written.
Status WriteObj(const std::string& obj_path, const Mesh& mesh, const ObjWriteOptions& options,
                ObjWriteReport* report = nullptr, Env* env = Env::Default());

struct ObjModel {
  Mesh mesh;                            // origin from "# origin" (else the
                                        // bounding-box center rounded to 1 m);
                                        // "# coordinates relative" keeps v as is
  std::string material;                 // the first usemtl's name
  std::vector<uint8_t> base_color_png;  // the map_Kd file's bytes, empty if none
  std::vector<uint8_t> normal_png;      // norm / map_Bump / bump file's bytes
};

// Reads v (with optional colors), vt, vn, f (v, v/t, v//n, v/t/n; negative
// indices; polygons fan-triangulated), mtllib and the first material's
// map_Kd and norm/map_Bump/bump (options before the file name skipped).
// When every corner uses the same index for v, vt and vn the vertex order is
// kept; otherwise a vertex is made per distinct (v, vt, vn). Errors name the
// file and line: "model.obj:12: face index 9 out of range (8 vertices)".
Expected<ObjModel> ReadObj(const std::string& obj_path);

}  // namespace pb
