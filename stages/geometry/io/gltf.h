// Binary glTF 2.0 (.glb) writing and reading: the `model` artifact's
// model.glb, for Unity, Unreal, Blender and three.js.
//
// What WriteGlb writes (little-endian; the subset ReadGlb reads back):
//   12-byte header "glTF", version 2, total length; a JSON chunk (padded with
//   spaces to 4 bytes) and one BIN chunk (padded with zeros to 4 bytes);
//   every bufferView starts at a multiple of 4 in the BIN chunk.
//   asset: version "2.0", generator "pointbake",
//          extras.pointbake_glb_version = kGlbVersion (bump on layout change).
//   scene 0 -> node 0 named options.name: translation = mesh.origin in
//          glTF's y-up axes (x, z, -y), extras.pointbake_origin = the origin
//          as is (JSON numbers with 17 significant digits: the doubles
//          survive) -> node 1 "z_up_to_y_up": rotation -90° about x (our
//          frames are z up, glTF's y up), mesh 0. Positions stay relative to
//          the origin, so large coordinates keep float precision, and the
//          rotation sits below the translation so that engines composing
//          matrices in float32 do not scale its rounding by the origin.
//          With options.z_up_to_y_up false: one node, translation = origin,
//          mesh 0.
//   mesh 0, one triangle primitive (mode 4), one bufferView per attribute:
//     POSITION   float32 VEC3, with min/max (exact float bounds)
//     NORMAL     float32 VEC3, unit length (mesh normals renormalized, or
//                ComputeVertexNormals when the mesh has none)
//     TEXCOORD_0 float32 VEC2 = (u, 1 - v): glTF's v axis points down from
//                the image's top-left corner, ours up from its bottom-left
//     TANGENT    float32 VEC4 when the mesh has uvs: mesh.tangents
//                (renormalized; recomputed with ComputeTangents when absent
//                or not finite). w is written unchanged: glTF's bitangent
//                w * cross(n, t) is the direction of "up" in the normal map
//                (+Y up, the OpenGL/Blender convention), which in our v-up
//                uvs is +v; the v flip moves where texels are, not the frame.
//     COLOR_0    uint16 normalized VEC3 (byteStride 8), *linear* values
//                (glTF's COLOR_0 is linear; ours are sRGB bytes), only when
//                the mesh has colors, options.vertex_colors is true and no
//                base color texture is given: glTF multiplies COLOR_0 into
//                the base color texture, so both would darken the model.
//     indices    uint16 when the mesh has at most 65535 vertices (65535
//                itself is reserved for primitive restart), else uint32.
//   material 0: pbrMetallicRoughness {baseColorTexture (sRGB PNG),
//          metallicFactor 0, roughnessFactor 1}, normalTexture (PNG,
//          tangent-space, +Y up); each texture is an image in its own
//          bufferView with mimeType image/png, sampler linear/mipmapped,
//          clamp to edge. A mesh without textures gets the factors only.
//          A map given as KTX2 (Basis Universal) instead is an image with
//          mimeType image/ktx2 that its texture names through
//          extensions.KHR_texture_basisu.source (no PNG fallback: the
//          extension is in extensionsUsed and extensionsRequired).
// The file is written durably (env->NewAtomicFile: a temporary, fsync,
// rename): on failure `path` keeps what it held and no partial file is left.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "base/env.h"
#include "base/status.h"
#include "stages/geometry/core/mesh.h"
#include "stages/geometry/core/tangents.h"

namespace pb {

inline constexpr int kGlbVersion = 1;

struct GltfWriteOptions {
  std::string name = "model";           // node, mesh and material name
  std::vector<uint8_t> base_color_png;   // PNG file bytes (sRGB); empty: none
  std::vector<uint8_t> normal_png;       // PNG file bytes (tangent space); empty: none
  // KTX2 file bytes (KHR_texture_basisu) in place of the PNG of the same
  // map; a map may be given one way only.
  std::vector<uint8_t> base_color_ktx2;
  std::vector<uint8_t> normal_ktx2;
  bool vertex_colors = true;             // COLOR_0 (see above)
  bool z_up_to_y_up = true;              // the root rotation node
};

struct GltfWriteReport {
  uint64_t bytes = 0;             // size of the .glb
  bool wrote_colors = false;      // COLOR_0 present
  bool wrote_tangents = false;    // TANGENT present
  bool computed_normals = false;  // the mesh had none
  bool computed_tangents = false; // the mesh had uvs but no (valid) tangents
  TangentReport tangents;         // when computed_tangents
};

// Status::Invalid for a mesh that fails Validate, has no triangles, has
// textures but no uvs, or a texture that is not a PNG; Status::Io naming the
// file when it cannot be written.
Status WriteGlb(const std::string& path, const Mesh& mesh, const GltfWriteOptions& options,
                GltfWriteReport* report = nullptr, Env* env = Env::Default());

struct GlbModel {
  Mesh mesh;                            // origin from extras.pointbake_origin (else the
                                        // mesh node's translation), v flipped back,
                                        // colors back to sRGB
  std::string name;                     // the root node's name
  std::string generator;                // asset.generator
  std::vector<uint8_t> base_color_png;  // embedded image bytes, empty if none
  std::vector<uint8_t> normal_png;
  std::vector<uint8_t> base_color_ktx2;  // KHR_texture_basisu images, empty if none
  std::vector<uint8_t> normal_ktx2;
};

// Reads what WriteGlb writes (one mesh, one triangle primitive, the
// attributes above with any valid component layout and byteStride; images
// from bufferViews). Status::Corrupt naming the file and what is wrong for
// anything else or out-of-bounds data; Status::NotFound if missing.
Expected<GlbModel> ReadGlb(const std::string& path);

}  // namespace pb
