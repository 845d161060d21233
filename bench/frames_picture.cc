// frames_picture: one viewpoint of a finished campaign's scene as a picture
// for docs/ (docs/images/frames-room.png in docs/metrics.md): top row the
// ground truth and each named run's frame, bottom row each run's FLIP map
// against the ground truth (black under the truth). Frames are halved by a
// 2x2 box filter.
//
//   build/bench/frames_picture OUT.png CAMPAIGN_DIR SCENE VIEW RUN...
//   build/bench/frames_picture docs/images/frames-room.png out/demo synthetic-room door lpm point_transfer
//
// RUN is a folder name under CAMPAIGN_DIR/runs/SCENE/ (as `pointbake
// campaign` writes them). Prints the mean FLIP of each run's view.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "stages/geometry/io/frames.h"
#include "stages/geometry/core/image.h"

namespace {

using pb::Expected;
using pb::Image;

Expected<Image> FrameOf(const std::string& frames_dir, const std::string& view) {
  PB_ASSIGN_OR_RETURN(pb::FrameSet set, pb::ReadFrames(frames_dir + "/frames.json"));
  const pb::Frame* frame = set.find(view);
  if (!frame) return pb::Status::NotFound(frames_dir + ": no frame named '" + view + "'");
  return frame->image;
}

// RGB, halved by a 2x2 box filter (rounded).
Image Half(const Image& in) {
  Image out = Image::Make(in.width / 2, in.height / 2, 3, Image::PixelType::kU8);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < 3; ++c) {
        int sum = 0;
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) sum += in.u8()[in.sample_index(2 * x + dx, 2 * y + dy, c)];
        out.u8()[out.sample_index(x, y, c)] = static_cast<uint8_t>((sum + 2) / 4);
      }
  return out;
}

void Paste(Image& canvas, const Image& tile, int x0, int y0) {
  for (int y = 0; y < tile.height; ++y)
    for (int x = 0; x < tile.width; ++x)
      for (int c = 0; c < 3; ++c)
        canvas.u8()[canvas.sample_index(x0 + x, y0 + y, c)] = tile.u8()[tile.sample_index(x, y, c)];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 6) {
    std::fprintf(stderr, "usage: %s OUT.png CAMPAIGN_DIR SCENE VIEW RUN...\n", argv[0]);
    return 2;
  }
  const std::string out = argv[1], campaign = argv[2], scene = argv[3], view = argv[4];
  std::vector<std::string> runs(argv + 5, argv + argc);
  const std::string scene_dir = campaign + "/runs/" + scene + "/";
  Expected<Image> truth = FrameOf(scene_dir + runs[0] + "/truth_frames", view);
  if (!truth.ok()) {
    std::fprintf(stderr, "%s\n", truth.status().message().c_str());
    return 1;
  }
  std::vector<Image> top{Half(*truth)}, bottom{Image::Make(top[0].width, top[0].height, 3, Image::PixelType::kU8)};
  for (const std::string& run : runs) {
    Expected<Image> frame = FrameOf(scene_dir + run + "/frames", view);
    Expected<Image> flip = FrameOf(scene_dir + run + "/flip_truth", view);
    if (!frame.ok() || !flip.ok()) {
      std::fprintf(stderr, "%s\n", (!frame.ok() ? frame : flip).status().message().c_str());
      return 1;
    }
    top.push_back(Half(*frame));
    bottom.push_back(Half(*flip));
  }
  const int tile_w = top[0].width, tile_h = top[0].height, gap = 4;
  const int columns = static_cast<int>(top.size());
  Image canvas = Image::Make(columns * tile_w + (columns - 1) * gap, 2 * tile_h + gap, 3,
                             Image::PixelType::kU8);
  std::fill(canvas.data.begin(), canvas.data.end(), uint8_t{255});
  for (int i = 0; i < columns; ++i) {
    Paste(canvas, top[i], i * (tile_w + gap), 0);
    Paste(canvas, bottom[i], i * (tile_w + gap), tile_h + gap);
  }
  const pb::Status st = pb::WritePng(out, canvas, pb::PngEncoding::kSmall);
  if (!st.ok()) {
    std::fprintf(stderr, "%s\n", st.message().c_str());
    return 1;
  }
  std::printf("wrote %s (%dx%d): ground truth", out.c_str(), canvas.width, canvas.height);
  for (const std::string& run : runs) std::printf(" | %s", run.c_str());
  std::printf("; bottom row: FLIP against the ground truth\n");
  return 0;
}
