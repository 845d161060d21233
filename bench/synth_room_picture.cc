// synth_room_picture: docs/images/synthetic-room-points.png, an oblique
// orthographic cut-away view of a 10^6-point scan of the synthetic room,
// colored by the points' colors (ceiling and the walls facing the camera
// left out).
//
//   synth_room_picture [OUT=docs/images/synthetic-room-points.png]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "stages/geometry/core/image.h"
#include "stages/geometry/synth/scanner.h"
#include "stages/geometry/synth/scene.h"

int main(int argc, char** argv) {
  using namespace pb;
  const std::string out = argc > 1 ? argv[1] : "docs/images/synthetic-room-points.png";
  Expected<SynthScene> room = MakeSynthScene("room", 1);
  if (!room.ok()) return std::fprintf(stderr, "%s\n", room.status().message().c_str()), 1;
  SynthScanOptions options;
  options.target_points = 1000000;
  Expected<SynthScanResult> result = SimulateScan(*room, options);
  if (!result.ok()) return std::fprintf(stderr, "%s\n", result.status().message().c_str()), 1;
  const double azimuth = -2.2, elevation = 0.75;  // camera direction, radians
  const Vec3 forward = {-std::cos(elevation) * std::cos(azimuth),
                        -std::cos(elevation) * std::sin(azimuth), -std::sin(elevation)};
  const Vec3 right = {-std::sin(azimuth), std::cos(azimuth), 0};
  const Vec3 up = {right[1] * forward[2] - right[2] * forward[1],
                   right[2] * forward[0] - right[0] * forward[2],
                   right[0] * forward[1] - right[1] * forward[0]};
  const int width = 600, height = 440;
  const double scale = 72;  // pixels per meter
  Image image = Image::Make(width, height, 3, Image::PixelType::kU8);
  std::fill(image.data.begin(), image.data.end(), uint8_t{40});
  std::vector<double> depth(size_t(width) * height, 1e9);
  const PointCloud& cloud = result->cloud;
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Vec3 p = {cloud.positions[3 * i], cloud.positions[3 * i + 1], cloud.positions[3 * i + 2]};
    const SurfaceSample truth = SampleSurface(*room, p);
    if (truth.surface == SynthSurface::kCeiling) continue;
    // Cut away the walls between the camera and the room.
    if (truth.surface == SynthSurface::kWall &&
        truth.normal[0] * forward[0] + truth.normal[1] * forward[1] > 0) {
      continue;
    }
    const double d = p[0] * forward[0] + p[1] * forward[1] + (p[2] - 1.6) * forward[2];
    const int x = static_cast<int>(width / 2 + scale * (p[0] * right[0] + p[1] * right[1]));
    const int y = static_cast<int>(height / 2 - scale * (p[0] * up[0] + p[1] * up[1] +
                                                         (p[2] - 1.6) * up[2]));
    if (x < 0 || y < 0 || x >= width || y >= height || d >= depth[size_t(y) * width + x]) continue;
    depth[size_t(y) * width + x] = d;
    // 5 bits per channel keep the PNG small (< 300 KB) for the docs.
    for (int c = 0; c < 3; ++c) image.at_u8(x, y, c) = cloud.colors[3 * i + c] & 0xF8;
  }
  const Status written = WritePng(out, image);
  if (!written.ok()) return std::fprintf(stderr, "%s\n", written.message().c_str()), 1;
  std::printf("wrote %s\n", out.c_str());
  return 0;
}
