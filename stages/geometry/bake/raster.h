// The machinery every texture bake shares (bake.vertex_colors,
// bake.from_mesh, bake.from_points): UV-space rasterization of the target
// mesh, the surface frame at a texel, the two maps being baked, and the
// gutter.
//
// Texel coordinates. A map is `size` x `size` texels; texel (x, y) is column
// x, row y, row 0 at the top of the image (v = 1, as PNG stores it). Texel
// space (s, t) = (u * size, (1 - v) * size), so texel (x, y) covers
// [x, x+1) x [y, y+1) and its centre is (x + 0.5, y + 0.5).
//
// Ownership (BakeRaster). Every texel belongs to at most one face, so faces
// can be baked in parallel and the result does not depend on the order:
//   - a texel whose centre lies inside or on the boundary of some faces
//     belongs to the lowest-numbered of them and samples at its centre;
//   - otherwise a texel whose square the face touches (conservative
//     rasterization: edges pushed out by half a texel in each axis) belongs
//     to the lowest-numbered such face and samples at the point of that face
//     nearest to its centre, so bilinear filtering at chart borders reads
//     values continued from the face, not the gutter.
// Faces with zero UV area own no texels.
//
// Frames. Normal maps are in tangent space with the mesh's per-vertex frames
// (tangents.h): at a texel the interpolated normal n, tangent t
// (Gram-Schmidt against n) and bitangent b = w * cross(n, t); a world normal
// N is stored as (N.t, N.b, N.n), which is what glTF viewers and our renderer
// undo per pixel. Encoded in 8 bits as round((c + 1) / 2 * 255) per channel.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/core/mesh.h"

namespace pb {

// Vertex v's position in texel space: (u * size, (1 - v) * size).
inline std::array<double, 2> TexelPosition(const Mesh& mesh, size_t v, int size) {
  return {double(mesh.uvs[2 * v]) * size, (1.0 - double(mesh.uvs[2 * v + 1])) * size};
}

// A texel to bake and where on its face it samples.
struct BakeTexel {
  int32_t x = 0;  // column
  int32_t y = 0;  // row, 0 = top
  float s = 0;    // sample point in texel space: the centre, or for an edge
  float t = 0;    //   texel the nearest point of the face to the centre
  std::array<float, 3> bary{};  // barycentric coordinates of (s, t) in the
                                // face (each >= 0, sum 1)
};

class BakeRaster {
 public:
  static constexpr uint32_t kNoFace = 0xffffffffu;

  // Rasterizes every face of `mesh` into a size x size grid. The mesh needs
  // uvs (Status::Invalid otherwise, and for size outside [1, 32768]). Uses
  // `threads` threads (0 = all); the result does not depend on the count.
  // Memory: 4 bytes per texel.
  static Expected<BakeRaster> Build(const Mesh& mesh, int size, int threads = 0);

  int size() const { return size_; }
  // The face owning texel (x, y), or kNoFace.
  uint32_t owner(int x, int y) const;
  // Whether the owner samples at the centre (false for conservative edge
  // texels and for empty texels).
  bool centre_inside(int x, int y) const;
  size_t covered_texels() const { return covered_; }
  size_t edge_texels() const { return edge_; }

  // The texels `face` owns, row-major, in `out` (cleared first).
  void TexelsOf(const Mesh& mesh, uint32_t face, std::vector<BakeTexel>& out) const;

 private:
  int size_ = 0;
  // Per texel: bit 31 set for a conservative edge texel, low 31 bits the
  // face; 0xffffffff empty. The smallest value wins during rasterization.
  std::vector<uint32_t> cells_;
  size_t covered_ = 0;
  size_t edge_ = 0;
};

// Calls bake_face(face, texels) once for every face that owns texels, on
// `threads` threads (0 = all), so bake_face must be thread-safe; each call
// may write exactly the texels it is given. progress(fraction) is called from
// the calling thread now and then when set.
void ForEachBakeFace(const Mesh& mesh, const BakeRaster& raster, int threads,
                     const std::function<void(uint32_t face, std::span<const BakeTexel>)>& bake_face,
                     const std::function<void(double)>& progress = {});

// The surface frame at a texel of the target mesh.
struct TexelFrame {
  std::array<float, 3> position{};   // meters, relative to the mesh's origin
  std::array<float, 3> normal{};     // unit, interpolated vertex normal
  std::array<float, 3> tangent{};    // unit, orthogonal to normal
  std::array<float, 3> bitangent{};  // w * cross(normal, tangent)
};
// Precondition: the mesh has normals and tangents (PrepareBakeMesh).
TexelFrame FrameAt(const Mesh& mesh, uint32_t face, const std::array<float, 3>& bary);
// A world-space direction in the texel's tangent frame, normalized; a zero
// vector gives (0, 0, 1).
std::array<float, 3> ToTangentSpace(const TexelFrame& frame, const std::array<float, 3>& world);

// The mesh a bake writes out: `mesh` with vertex normals (computed,
// area-weighted, when it has none) and tangent frames (ComputeTangents).
// Status::Invalid when it has no uvs or fails Validate.
Expected<Mesh> PrepareBakeMesh(Mesh mesh);

// The two maps being baked. Color: kU8 RGB, sRGB as stored in the inputs.
// Normal: kU8 RGB encoded as above, or kF32 RGB in [-1, 1] when float
// normals were asked for (to write OpenEXR). Texels nothing writes stay
// black / flat (0, 0, 1).
struct BakeMaps {
  Image color;
  Image normal;

  static BakeMaps Make(int size, bool float_normals);
  // srgb in [0, 255] (clamped, rounded to nearest).
  void SetColor(int x, int y, const std::array<float, 3>& srgb);
  // A tangent-space unit vector (clamped to [-1, 1]).
  void SetNormal(int x, int y, const std::array<float, 3>& tangent_space);
};

// The gutter: `passes` rings of texels around the covered ones. In each pass
// every empty texel with a filled 8-neighbour (filled before the pass) takes
// the mean of those neighbours, color and normal (re-normalized); a pass
// sees only the previous passes' results, so the output does not depend on
// the thread count. Returns the number of texels filled. The authors' 25x25
// dilation is 12 passes.
size_t DilateBakeMaps(BakeMaps& maps, const BakeRaster& raster, int passes, int threads = 0);

}  // namespace pb
