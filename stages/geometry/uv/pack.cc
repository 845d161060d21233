// Skyline bottom-left rectangle packing (Jylänki 2010, SKYLINE-BL, with
// quarter turns) and a bisection on the uniform chart scale.
#include "stages/geometry/uv/pack.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

namespace pb {
namespace {

struct Segment {
  int64_t x, y, width;
};

class Skyline {
 public:
  explicit Skyline(int64_t limit) : limit_(limit) { segments_.push_back({0, 0, limit}); }

  // Places a width x height box, or a height x width one (*turned), at the
  // lowest top edge (ties: leftmost, then unturned); false if it fits
  // nowhere.
  bool Insert(int64_t width, int64_t height, int64_t* x_out, int64_t* y_out, bool* turned) {
    int64_t best_top = limit_ + 1, best_x = 0, best_y = 0;
    size_t best_index = segments_.size();
    bool best_turned = false;
    for (int turn = 0; turn < 2; ++turn) {
      const int64_t w = turn ? height : width, h = turn ? width : height;
      for (size_t i = 0; i < segments_.size(); ++i) {
        const int64_t x = segments_[i].x;
        if (x + w > limit_) break;
        int64_t y = 0;
        for (size_t j = i; j < segments_.size() && segments_[j].x < x + w; ++j) {
          y = std::max(y, segments_[j].y);
          if (y + h > best_top) break;  // cannot beat the best any more
        }
        const int64_t top = y + h;
        if (top <= limit_ && (top < best_top || (top == best_top && x < best_x))) {
          best_top = top;
          best_x = x;
          best_y = y;
          best_index = i;
          best_turned = turn == 1;
        }
      }
      if (width == height) break;
    }
    if (best_index == segments_.size()) return false;
    Place(best_index, best_x, best_top, best_turned ? height : width);
    *x_out = best_x;
    *y_out = best_y;
    *turned = best_turned;
    return true;
  }

 private:
  void Place(size_t index, int64_t x, int64_t top, int64_t width) {
    segments_.insert(segments_.begin() + static_cast<std::ptrdiff_t>(index), {x, top, width});
    const int64_t end = x + width;
    size_t j = index + 1;
    while (j < segments_.size() && segments_[j].x < end) {
      Segment& s = segments_[j];
      const int64_t s_end = s.x + s.width;
      if (s_end <= end) {
        segments_.erase(segments_.begin() + static_cast<std::ptrdiff_t>(j));
      } else {
        s.width = s_end - end;
        s.x = end;
        break;
      }
    }
    // Merge equal-height neighbours (linear, like the search itself).
    size_t out = 0;
    for (size_t k = 1; k < segments_.size(); ++k) {
      if (segments_[k].y == segments_[out].y) {
        segments_[out].width += segments_[k].width;
      } else {
        segments_[++out] = segments_[k];
      }
    }
    segments_.resize(out + 1);
  }

  int64_t limit_;
  std::vector<Segment> segments_;
};

int64_t BoxSize(double extent_m, double scale, int gutter) {
  return std::max<int64_t>(1, static_cast<int64_t>(std::ceil(extent_m * scale))) + gutter;
}

// Packs in `order` at `scale`; false as soon as one box does not fit.
bool TryPack(const std::vector<ChartExtent>& charts, const std::vector<uint32_t>& order,
             double scale, int size, int gutter, std::vector<int64_t>* xs, std::vector<int64_t>* ys,
             std::vector<char>* turned) {
  // Boxes carry their gutter on the right and top; the skyline starts one
  // gutter in from the left and bottom border and ends at the atlas edge.
  Skyline skyline(static_cast<int64_t>(size) - gutter);
  for (uint32_t i : order) {
    int64_t x = 0, y = 0;
    bool turn = false;
    if (!skyline.Insert(BoxSize(charts[i].width, scale, gutter),
                        BoxSize(charts[i].height, scale, gutter), &x, &y, &turn)) {
      return false;
    }
    (*turned)[i] = turn;
    (*xs)[i] = x + gutter;
    (*ys)[i] = y + gutter;
  }
  return true;
}

}  // namespace

Expected<PackResult> PackCharts(const std::vector<ChartExtent>& charts, int size_texels,
                                int gutter_texels) {
  if (size_texels < 1 || gutter_texels < 0 || 2 * gutter_texels >= size_texels) {
    return Status::Invalid("uv packing: atlas of " + std::to_string(size_texels) +
                           " texels cannot hold a gutter of " + std::to_string(gutter_texels));
  }
  PackResult result;
  result.x_texels.assign(charts.size(), 0);
  result.y_texels.assign(charts.size(), 0);
  result.turned.assign(charts.size(), 0);
  if (charts.empty()) return result;

  // Tallest first (ties: wider, then lower index): the skyline's best case.
  std::vector<uint32_t> order(charts.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    if (charts[a].height != charts[b].height) return charts[a].height > charts[b].height;
    if (charts[a].width != charts[b].width) return charts[a].width > charts[b].width;
    return a < b;
  });

  double area_m2 = 0;
  for (const ChartExtent& c : charts) area_m2 += c.width * c.height;
  const double usable = static_cast<double>(size_texels - 2 * gutter_texels);
  // No packing beats the charts' total area filling the whole atlas.
  double hi = area_m2 > 0 ? usable / std::sqrt(area_m2) : usable;
  for (const ChartExtent& c : charts)
    hi = std::min(hi, usable / std::max({c.width, c.height, 1e-30}));
  std::vector<int64_t> xs(charts.size()), ys(charts.size());
  std::vector<char> turned(charts.size(), 0);

  // Step down from the area bound until a packing fits, then bisect.
  double lo = 0;
  double scale = hi;
  for (int step = 0; step < 60; ++step) {
    ++result.attempts;
    if (TryPack(charts, order, scale, size_texels, gutter_texels, &xs, &ys, &turned)) {
      lo = scale;
      result.x_texels = xs;
      result.y_texels = ys;
      result.turned = turned;
      break;
    }
    hi = scale;
    scale *= step < 4 ? 0.95 : 0.8;
  }
  if (lo == 0) {
    return Status::Invalid("uv packing: " + std::to_string(charts.size()) +
                           " charts with a gutter of " + std::to_string(gutter_texels) +
                           " texels do not fit in a " + std::to_string(size_texels) +
                           "-texel atlas; raise `size` or lower `gutter`");
  }
  while (hi > lo * (1.0 + 1.0 / 256.0)) {
    const double mid = 0.5 * (lo + hi);
    ++result.attempts;
    if (TryPack(charts, order, mid, size_texels, gutter_texels, &xs, &ys, &turned)) {
      lo = mid;
      result.x_texels = xs;
      result.y_texels = ys;
      result.turned = turned;
    } else {
      hi = mid;
    }
  }
  result.texels_per_meter = lo;
  return result;
}

}  // namespace pb
