#include "stages/geometry/bake/bake.h"

#include <utility>

namespace pb {

Expected<BakeResult> BakeVertexColors(Mesh mesh, const BakeOptions& options) {
  if (!mesh.has_colors()) {
    return Status::Invalid(
        "bake.vertex_colors: the mesh has no vertex colors (its scan had none: io.read_points "
        "paints such scans grey unless `uncolored: none`)");
  }
  BakeResult result;
  PB_ASSIGN_OR_RETURN(result.mesh, PrepareBakeMesh(std::move(mesh)));
  PB_ASSIGN_OR_RETURN(const BakeRaster raster,
                      BakeRaster::Build(result.mesh, options.size, options.threads));
  result.maps = BakeMaps::Make(options.size, options.float_normals);
  const Mesh& target = result.mesh;
  BakeMaps& maps = result.maps;
  // The normal map stays flat: the maps start flat and only colors are set.
  ForEachBakeFace(target, raster, options.threads,
                  [&](uint32_t face, std::span<const BakeTexel> texels) {
    const uint32_t* corner = &target.indices[3 * size_t(face)];
    for (const BakeTexel& texel : texels) {
      std::array<float, 3> color{};
      for (int k = 0; k < 3; ++k) {
        for (int c = 0; c < 3; ++c) color[c] += texel.bary[k] * target.colors[3 * size_t(corner[k]) + c];
      }
      maps.SetColor(texel.x, texel.y, color);
    }
  }, options.progress);
  result.covered_texels = raster.covered_texels();
  result.edge_texels = raster.edge_texels();
  result.gutter_texels = DilateBakeMaps(maps, raster, options.gutter, options.threads);
  return result;
}

}  // namespace pb
