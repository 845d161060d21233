// Campaign report, images: per scene and view, the frames of every run side
// by side as thumbnails, a zoomed crop where point transfer and LPM differ
// most (the crop-location rule, docs/report.md), and the FLIP maps; each
// written to images/ and kept as a base64 data: URI for report.html.
#include <algorithm>
#include <array>
#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "base/env.h"
#include "stages/geometry/io/frames.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/metrics/image_metrics.h"
#include "cli/report/report_internal.h"

namespace pb::report_internal {
namespace {

// A file-name-safe form of a scene, run or view name.
std::string Slug(const std::string& s) {
  std::string out;
  for (char ch : s) out += (std::isalnum(static_cast<unsigned char>(ch)) || ch == '-') ? ch : '_';
  return out;
}

// 8-bit RGB copy (alpha dropped: metrics.image measures all pixels too).
Image ToRgb8(const Image& in) {
  Image out = Image::Make(in.width, in.height, 3, Image::PixelType::kU8);
  for (int y = 0; y < in.height; ++y)
    for (int x = 0; x < in.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const int src = in.channels >= 3 ? c : 0;
        uint8_t v = 0;
        if (in.type == Image::PixelType::kU8)
          v = in.at_u8(x, y, src);
        else if (in.type == Image::PixelType::kU16)
          v = uint8_t(in.at_u16(x, y, src) >> 8);
        else
          v = uint8_t(std::clamp(in.at_f32(x, y, src), 0.0f, 1.0f) * 255.0f + 0.5f);
        out.at_u8(x, y, c) = v;
      }
  return out;
}

// `in` made smaller so its longest side is `max_side` (unchanged when it is
// already): each output pixel is `pick(x0, x1, y0, y1)` of the source box
// [x0, x1) x [y0, y1) it stands for (integer bounds, so every source pixel
// belongs to one box).
template <typename Pick>
Image DownscaleByBoxes(const Image& in, int max_side, Pick pick) {
  const int longest = std::max(in.width, in.height);
  if (longest <= max_side || max_side <= 0) return in;
  const int w = std::max(1, int(int64_t(in.width) * max_side / longest));
  const int h = std::max(1, int(int64_t(in.height) * max_side / longest));
  Image out = Image::Make(w, h, 3, Image::PixelType::kU8);
  for (int y = 0; y < h; ++y) {
    const int y0 = int(int64_t(y) * in.height / h),
              y1 = std::max(y0 + 1, int(int64_t(y + 1) * in.height / h));
    for (int x = 0; x < w; ++x) {
      const int x0 = int(int64_t(x) * in.width / w),
                x1 = std::max(x0 + 1, int(int64_t(x + 1) * in.width / w));
      const std::array<uint8_t, 3> rgb = pick(x0, x1, y0, y1);
      for (int c = 0; c < 3; ++c) out.at_u8(x, y, c) = rgb[size_t(c)];
    }
  }
  return out;
}

// Box filter: each output pixel is the rounded mean of the source pixels it
// covers.
Image BoxDownscale(const Image& in, int max_side) {
  return DownscaleByBoxes(in, max_side, [&](int x0, int x1, int y0, int y1) {
    std::array<uint32_t, 3> sum{};
    for (int sy = y0; sy < y1; ++sy)
      for (int sx = x0; sx < x1; ++sx)
        for (int c = 0; c < 3; ++c) sum[size_t(c)] += in.at_u8(sx, sy, c);
    const uint32_t n = uint32_t((y1 - y0) * (x1 - x0));
    std::array<uint8_t, 3> mean{};
    for (int c = 0; c < 3; ++c) mean[size_t(c)] = uint8_t((sum[size_t(c)] + n / 2) / n);
    return mean;
  });
}

// A coverage map (image_metrics.h) made smaller. A box with a defect in it
// (a hole, surface in front of or behind the scan) takes the most telling
// one (kCoverageMapRanked), so that a single hole pixel stays in sight where
// averaging would wash it out. Any other box takes what most of its pixels
// show (ties in this order): the model, as the mean of its grays; model
// only; splat disks only; neither. So the one-pixel gaps between a sparse
// scan's splats do not speckle a wall blue, and what a box shows is what
// most of it is.
Image RankedDownscale(const Image& in, int max_side) {
  constexpr size_t kDefects = 5;  // kCoverageMapRanked's holes, in front, behind
  static_assert(kCoverageMapRanked[kDefects] == kCoverageMapTestOnly &&
                kCoverageMapRanked[kDefects + 1] == kCoverageMapReferenceOnly);
  return DownscaleByBoxes(in, max_side, [&](int x0, int x1, int y0, int y1) {
    size_t defect = kDefects;
    std::array<uint32_t, 4> count{};  // the model, model only, disks only, neither
    uint32_t gray_sum = 0;
    for (int sy = y0; sy < y1; ++sy)
      for (int sx = x0; sx < x1; ++sx) {
        const std::array<uint8_t, 3> c = {in.at_u8(sx, sy, 0), in.at_u8(sx, sy, 1), in.at_u8(sx, sy, 2)};
        size_t k = 0;
        while (k < kDefects && c != kCoverageMapRanked[k]) ++k;
        if (k < kDefects) {
          defect = std::min(defect, k);
        } else if (c == kCoverageMapTestOnly) {
          ++count[1];
        } else if (c == kCoverageMapReferenceOnly) {
          ++count[2];
        } else if (c == kCoverageMapNeither) {
          ++count[3];
        } else {  // a gray of the model
          ++count[0];
          gray_sum += c[0];
        }
      }
    if (defect < kDefects) return kCoverageMapRanked[defect];
    switch (std::max_element(count.begin(), count.end()) - count.begin()) {
      case 0: {
        const uint8_t gray = uint8_t((gray_sum + count[0] / 2) / count[0]);
        return std::array<uint8_t, 3>{gray, gray, gray};
      }
      case 1: return kCoverageMapTestOnly;
      case 2: return kCoverageMapReferenceOnly;
      default: return kCoverageMapNeither;
    }
  });
}

// The crop_px window where frames `a` and `b` differ most (sum of absolute
// RGB differences; candidates on a grid of step size/8, the first maximum in
// row-major order wins). Without both frames: the centred window.
CropWindow ChooseCrop(const Image* a, const Image* b, int width, int height, int crop_px) {
  CropWindow w;
  w.size = std::max(1, std::min({crop_px, width, height}));
  w.x = (width - w.size) / 2;
  w.y = (height - w.size) / 2;
  if (!a || !b || a->width != b->width || a->height != b->height || a->width != width ||
      a->height != height)
    return w;
  // Integral image of the per-pixel difference.
  std::vector<uint64_t> integral(size_t(width + 1) * size_t(height + 1), 0);
  auto at = [&](int x, int y) -> uint64_t& {
    return integral[size_t(y) * size_t(width + 1) + size_t(x)];
  };
  for (int y = 0; y < height; ++y) {
    uint64_t row = 0;
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < 3; ++c)
        row += uint64_t(std::abs(int(a->at_u8(x, y, c)) - int(b->at_u8(x, y, c))));
      at(x + 1, y + 1) = at(x + 1, y) + row;
    }
  }
  const int step = std::max(1, w.size / 8);
  uint64_t best = 0;
  for (int y = 0; y + w.size <= height; y += step)
    for (int x = 0; x + w.size <= width; x += step) {
      const uint64_t s =
          at(x + w.size, y + w.size) - at(x, y + w.size) - at(x + w.size, y) + at(x, y);
      if (s > best) {
        best = s;
        w.x = x;
        w.y = y;
      }
    }
  return w;
}

// The window cut out and enlarged `scale` times (nearest neighbor).
Image CropEnlarge(const Image& in, const CropWindow& w, int scale) {
  Image out = Image::Make(w.size * scale, w.size * scale, 3, Image::PixelType::kU8);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < 3; ++c)
        out.at_u8(x, y, c) = in.at_u8(w.x + x / scale, w.y + y / scale, c);
  return out;
}

// A 2-pixel yellow outline of the crop window, in thumbnail coordinates.
void MarkWindow(Image& thumb, const CropWindow& w, int full_width, int full_height) {
  const int x0 = w.x * thumb.width / full_width,
            x1 = std::min(thumb.width - 1, (w.x + w.size) * thumb.width / full_width);
  const int y0 = w.y * thumb.height / full_height,
            y1 = std::min(thumb.height - 1, (w.y + w.size) * thumb.height / full_height);
  auto put = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= thumb.width || y >= thumb.height) return;
    thumb.at_u8(x, y, 0) = 255, thumb.at_u8(x, y, 1) = 221, thumb.at_u8(x, y, 2) = 0;
  };
  for (int t = 0; t < 2; ++t) {
    for (int x = x0; x <= x1; ++x) put(x, y0 + t), put(x, y1 - t);
    for (int y = y0; y <= y1; ++y) put(x0 + t, y), put(x1 - t, y);
  }
}

std::string Base64(const std::vector<uint8_t>& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const uint32_t n = uint32_t(bytes[i]) << 16 |
                       (i + 1 < bytes.size() ? uint32_t(bytes[i + 1]) << 8 : 0) |
                       (i + 2 < bytes.size() ? uint32_t(bytes[i + 2]) : 0);
    out += table[(n >> 18) & 63];
    out += table[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? table[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? table[n & 63] : '=';
  }
  return out;
}

Expected<ReportImage> SaveImage(const std::string& report_dir, const std::string& name,
                                const Image& image) {
  // Kept pictures: the smaller encoding (photographic frames compress ~2x better).
  PB_ASSIGN_OR_RETURN(std::vector<uint8_t> png, EncodePng(image, PngEncoding::kSmall));
  ReportImage out{"images/" + name + ".png", "data:image/png;base64," + Base64(png), image.width,
                  image.height};
  PB_RETURN_IF_ERROR(Env::Default()->WriteFileAtomic(
      JoinPath(report_dir, out.file),
      std::string_view(reinterpret_cast<const char*>(png.data()), png.size())));
  return out;
}

// Reads <dir>/frames.json if it exists; nullopt when absent.
Expected<std::optional<FrameSet>> MaybeReadFrames(const std::string& dir) {
  const std::string index = JoinPath(dir, kFramesIndexFile);
  if (!Env::Default()->Exists(index)) return std::optional<FrameSet>();
  PB_ASSIGN_OR_RETURN(FrameSet set, ReadFrames(index));
  return std::optional<FrameSet>(std::move(set));
}

}  // namespace

Expected<SceneImages> BuildSceneImages(const Campaign& c, const std::string& scene,
                                       const std::string& report_dir,
                                       const ReportOptions& options) {
  struct Column {
    std::string title, note, flip_title;
    std::optional<FrameSet> frames, flip, coverage;
    const Row* row = nullptr;
  };
  std::vector<Column> columns;
  std::optional<FrameSet> truth;
  for (const Row& r : c.rows) {
    if (r.scene != scene || !r.ok() || truth) continue;
    PB_ASSIGN_OR_RETURN(truth, MaybeReadFrames(JoinPath(r.run_dir, "truth_frames")));
  }
  if (truth) columns.push_back({"Ground truth", "", "", std::move(truth), std::nullopt, std::nullopt, nullptr});
  const bool has_truth = !columns.empty();
  // The scan itself as splats (render.splats, the same in every run).
  std::optional<FrameSet> scan;
  for (const Row& r : c.rows) {
    if (r.scene != scene || !r.ok() || scan) continue;
    PB_ASSIGN_OR_RETURN(scan, MaybeReadFrames(JoinPath(r.run_dir, "scan_frames")));
  }
  if (scan) columns.push_back({"Scan (splats)", "", "", std::move(scan), std::nullopt, std::nullopt, nullptr});
  for (const Row& r : c.rows) {
    if (r.scene != scene) continue;
    Column col{DisplayName(r), "", "", std::nullopt, std::nullopt, std::nullopt, &r};
    if (!r.ok()) {
      col.note = "run failed";
    } else {
      PB_ASSIGN_OR_RETURN(col.frames, MaybeReadFrames(JoinPath(r.run_dir, "frames")));
      if (!col.frames) col.note = "no frames";
      PB_ASSIGN_OR_RETURN(col.coverage, MaybeReadFrames(JoinPath(r.run_dir, "coverage_scan")));
      if (has_truth) {
        PB_ASSIGN_OR_RETURN(col.flip, MaybeReadFrames(JoinPath(r.run_dir, "flip_truth")));
        col.flip_title = "FLIP vs ground truth";
      } else {
        // Without ground truth the scan is the reference: its covered-pixel
        // map (unlit), else HPM's.
        PB_ASSIGN_OR_RETURN(col.flip, MaybeReadFrames(JoinPath(r.run_dir, "flip_scan")));
        col.flip_title = "FLIP vs scan (covered pixels, unlit)";
        if (!col.flip) {
          PB_ASSIGN_OR_RETURN(col.flip, MaybeReadFrames(JoinPath(r.run_dir, "flip_hpm")));
          col.flip_title = "FLIP vs HPM";
        }
      }
    }
    columns.push_back(std::move(col));
  }
  SceneImages out{scene, {}};
  const FrameSet* first = nullptr;
  for (const Column& col : columns)
    if (col.frames && !first) first = &*col.frames;
  if (!first) return out;
  // The crop compares point transfer with LPM (the no-variant rows).
  const Row* pt = PointTransferRow(c, scene);
  const FrameSet *pt_frames = nullptr, *lpm_frames = nullptr;
  for (const Column& col : columns) {
    if (!col.row || !col.frames) continue;
    if (col.row == pt) pt_frames = &*col.frames;
    if (col.row->workflow == "lpm" && !lpm_frames && col.row->variant.empty())
      lpm_frames = &*col.frames;
  }
  const int view_count =
      std::min<int>(std::max(0, options.max_viewpoints), int(first->frames.size()));
  for (int v = 0; v < view_count; ++v) {
    const std::string view = first->frames[size_t(v)].entry.name;
    ViewSection section{view, {}, {}};
    auto rgb_of = [&](const FrameSet* set) -> std::optional<Image> {
      const Frame* f = set ? set->find(view) : nullptr;
      return f ? std::optional<Image>(ToRgb8(f->image)) : std::nullopt;
    };
    const std::optional<Image> pt_rgb = rgb_of(pt_frames), lpm_rgb = rgb_of(lpm_frames);
    section.window = ChooseCrop(pt_rgb ? &*pt_rgb : nullptr, lpm_rgb ? &*lpm_rgb : nullptr,
                                first->width, first->height, options.crop_px);
    const int scale = std::max(1, options.thumbnail_px / section.window.size);
    for (size_t k = 0; k < columns.size(); ++k) {
      const Column& col = columns[k];
      FrameCell cell{col.title, col.note, std::nullopt, std::nullopt, std::nullopt, col.flip_title, std::nullopt};
      const std::string base =
          Slug(scene) + "__" + Slug(col.row ? col.row->name : k == 0 && has_truth ? "truth" : "scan") + "__" +
          Slug(view);
      std::optional<Image> rgb = rgb_of(col.frames ? &*col.frames : nullptr);
      if (col.frames && !rgb) cell.note = "no frame \"" + view + "\"";
      if (rgb) {
        const CropWindow w =
            ChooseCrop(nullptr, nullptr, rgb->width, rgb->height, section.window.size);
        const CropWindow use =
            rgb->width == first->width && rgb->height == first->height ? section.window : w;
        Image thumb = BoxDownscale(*rgb, options.thumbnail_px);
        MarkWindow(thumb, use, rgb->width, rgb->height);
        PB_ASSIGN_OR_RETURN(cell.thumb, SaveImage(report_dir, base + "_frame", thumb));
        PB_ASSIGN_OR_RETURN(cell.crop,
                            SaveImage(report_dir, base + "_crop", CropEnlarge(*rgb, use, scale)));
      }
      if (std::optional<Image> flip = rgb_of(col.flip ? &*col.flip : nullptr)) {
        PB_ASSIGN_OR_RETURN(cell.flip, SaveImage(report_dir, base + "_flip",
                                                 BoxDownscale(*flip, options.thumbnail_px)));
      }
      if (std::optional<Image> coverage = rgb_of(col.coverage ? &*col.coverage : nullptr)) {
        PB_ASSIGN_OR_RETURN(cell.coverage, SaveImage(report_dir, base + "_coverage",
                                                     RankedDownscale(*coverage, options.thumbnail_px)));
      }
      section.cells.push_back(std::move(cell));
    }
    out.views.push_back(std::move(section));
  }
  return out;
}

}  // namespace pb::report_internal
