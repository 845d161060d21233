// VTK XML PolyData (.vtp) writing: a triangle mesh with per-vertex arrays,
// for ParaView and every program built on VTK. Our own writer (the format is
// VTK's documented XML file format, "VTK File Formats", VTK User's Guide,
// section 19.3, XML PolyData): it streams through Env::NewAtomicFile like the
// PLY writer, so a failed write leaves the earlier file, and pointbake does
// not link VTK; the tests read the files back with VTK 9's
// vtkXMLPolyDataReader (docs/export.md says why not vtkXMLPolyDataWriter).
//
// What WriteVtp writes:
//
//   <?xml version="1.0"?>
//   <!-- pointbake vtp 1 -->                 <- signature + kVtpVersion
//   <VTKFile type="PolyData" version="1.0" byte_order="LittleEndian"
//            header_type="UInt64">
//     <PolyData>
//       <FieldData>                          <- strings, format="ascii" (the
//         <Array type="String" Name=...>        character codes, 0-ended, as
//       </FieldData>                            VTK writes them)
//       <Piece NumberOfPoints=N NumberOfPolys=M ...>
//         <PointData Scalars=.. Normals="Normals" TCoords="TCoords">
//           Normals   Float32 x3             <- when the mesh has normals
//           TCoords   Float32 x2             <- uvs (u right, v up), if any
//           Colors    UInt8 x3               <- sRGB 0..255, if any
//           Tangents  Float32 x4             <- xyz + handedness w, if any
//                                               (a plain array: VTK's
//                                               Tangents attribute is x3)
//           then options.point_arrays in order (Float32 or UInt8)
//         </PointData>
//         <Points> Float64 x3                <- ABSOLUTE coordinates, meters
//                                               (origin + position)
//         <Polys> connectivity, offsets      <- Int64; 3 corners per cell,
//                                               counter-clockwise = front
//       </Piece>
//     </PolyData>
//     <AppendedData encoding="raw">_ then, per numeric array in the order
//       above: a UInt64 byte count and the little-endian values
//   </VTKFile>
//
// Points are doubles so that georeferenced scans keep millimeters at
// millions of meters (the PLY stores floats relative to its origin).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "base/env.h"
#include "base/status.h"
#include "stages/geometry/core/mesh.h"

namespace pb {

inline constexpr int kVtpVersion = 1;  // "<!-- pointbake vtp 1 -->"

// One per-vertex array: exactly one of float32 / uint8 is set, with
// components x vertex-count values (vertex-major).
struct VtpPointArray {
  std::string name;
  int components = 1;
  std::span<const float> float32;
  std::span<const uint8_t> uint8;
};

struct VtpStringField {
  std::string name;
  std::string value;
};

// A file written beside the .vtp as one durable set with it (a texture the
// field data names): every file is synced before any is renamed, the .vtp
// renamed last.
struct VtpCompanionFile {
  std::string path;
  std::span<const uint8_t> bytes;
};

struct VtpWriteOptions {
  std::vector<VtpPointArray> point_arrays;
  std::string active_scalars;  // a point array's name, or empty: none
  std::vector<VtpStringField> field_data;
  std::vector<VtpCompanionFile> companions;
};

// Writes `mesh` and the arrays to `path` (and the companions), durably.
// Status::Invalid for a mesh failing Validate, an array whose size is not
// components x vertices or with both or neither type set, a duplicate or
// empty array name, or active_scalars naming no array; the env's error
// naming the file when a write fails. `bytes` (optional): the .vtp's size.
Status WriteVtp(const std::string& path, const Mesh& mesh, const VtpWriteOptions& options,
                uint64_t* bytes = nullptr, Env* env = Env::Default());

}  // namespace pb
