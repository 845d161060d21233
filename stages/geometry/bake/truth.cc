#include "stages/geometry/bake/truth.h"

#include <cmath>
#include <vector>

namespace pb {

Expected<TruthColorError> ColorErrorAgainstTruth(const SynthScene& scene, const BakeResult& result,
                                                 double max_off_surface_m) {
  const Mesh& mesh = result.mesh;
  const Image& color = result.maps.color;
  PB_ASSIGN_OR_RETURN(const BakeRaster raster, BakeRaster::Build(mesh, color.width));
  double sum = 0;
  TruthColorError error;
  std::vector<BakeTexel> texels;
  for (uint32_t face = 0; face < mesh.face_count(); ++face) {
    raster.TexelsOf(mesh, face, texels);
    for (const BakeTexel& texel : texels) {
      if (!raster.centre_inside(texel.x, texel.y)) continue;
      const TexelFrame frame = FrameAt(mesh, face, texel.bary);
      const SurfaceSample truth =
          SampleSurface(scene, {mesh.origin[0] + frame.position[0], mesh.origin[1] + frame.position[1],
                                mesh.origin[2] + frame.position[2]});
      if (truth.in_opening || std::abs(truth.distance_m) > max_off_surface_m) continue;
      for (int c = 0; c < 3; ++c) {
        sum += std::abs(color.at_u8(texel.x, texel.y, c) - 255.0 * truth.albedo[c]) / 3;
      }
      ++error.texels;
    }
  }
  if (error.texels) error.mean_abs = sum / double(error.texels);
  return error;
}

}  // namespace pb
