// Bitmap bottom-left packing of chart shapes; see raster_pack.h.
#include "stages/geometry/uv/raster_pack.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <utility>

#include "stages/geometry/uv/pack.h"

namespace pb {
namespace {

// Chart point (u, v) turned by `angle` and moved by -(min_u, min_v): the
// same arithmetic for the turned copies that are rasterized and for the
// placed UVs (PlacedTexel), so both touch the same texels.
std::array<double, 2> Turned(double angle, double min_u, double min_v, double u, double v) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * u - s * v - min_u, s * u + c * v - min_v};
}

// A bit mask, `w` x `h` texels, rows of `words` 64-bit words (bit x of a
// row is bit x % 64 of word x / 64), plus per row its longest run of set
// bits (used to prune candidate positions).
struct Mask {
  int w = 0, h = 0, words = 0;
  std::vector<uint64_t> bits;
  std::vector<int> run_lo, run_len;  // per row; run_len 0 for an empty row
  std::vector<int> first_word, last_word;
  std::vector<char> contiguous;  // per row: its set bits are one run

  void Reset(int width, int height) {
    w = width;
    h = height;
    words = (w + 63) / 64;
    bits.assign(size_t(words) * size_t(h), 0);
  }
  uint64_t* Row(int y) { return bits.data() + size_t(y) * size_t(words); }
  const uint64_t* Row(int y) const { return bits.data() + size_t(y) * size_t(words); }
  bool Get(int x, int y) const { return (Row(y)[x >> 6] >> (x & 63)) & 1u; }
  void Set(int x, int y) { Row(y)[x >> 6] |= uint64_t(1) << (x & 63); }
};

int NextBit(const uint64_t* row, int words, int limit, int from, bool set) {
  if (from >= limit) return limit;
  int w = from >> 6;
  uint64_t m = (set ? row[w] : ~row[w]) & (~uint64_t(0) << (from & 63));
  while (m == 0) {
    if (++w >= words) return limit;
    m = set ? row[w] : ~row[w];
  }
  return std::min(limit, w * 64 + __builtin_ctzll(m));
}

// The longest run of clear bits of a row of `words` words (the first of
// the longest): its start and length. Word by word: a clear word extends
// the current run, a set one ends it, and only the others are walked run
// by run (an atlas row is mostly whole words of either).
std::pair<int, int> LongestClearRun(const uint64_t* row, int words) {
  int best_lo = 0, best = 0, start = 0, length = 0;  // the current run
  for (int w = 0; w < words; ++w) {
    const uint64_t x = row[w];
    if (x == 0) {
      length += 64;
      continue;
    }
    int bit = 0;
    while (bit < 64) {
      const uint64_t clear_from_bit = x >> bit;
      if (clear_from_bit == 0) {  // clear to the word's end: the run goes on
        length += 64 - bit;
        break;
      }
      const int clear = __builtin_ctzll(clear_from_bit);
      length += clear;
      if (length > best) {
        best = length;
        best_lo = start;
      }
      bit += clear;
      const uint64_t set_from_bit = ~x >> bit;
      bit += set_from_bit == 0 ? 64 - bit : __builtin_ctzll(set_from_bit);
      start = w * 64 + bit;
      length = 0;
    }
  }
  if (length > best) {
    best = length;
    best_lo = start;
  }
  return {best_lo, best};
}

void ComputeRuns(Mask* mask) {
  mask->run_lo.assign(mask->h, 0);
  mask->run_len.assign(mask->h, 0);
  mask->first_word.assign(mask->h, 0);
  mask->last_word.assign(mask->h, -1);
  mask->contiguous.assign(mask->h, 1);
  for (int y = 0; y < mask->h; ++y) {
    const uint64_t* row = mask->Row(y);
    int runs = 0;
    for (int x = 0; x < mask->w;) {
      const int s = NextBit(row, mask->words, mask->w, x, true);
      if (s >= mask->w) break;
      const int e = NextBit(row, mask->words, mask->w, s, false);
      ++runs;
      if (e - s > mask->run_len[y]) {
        mask->run_lo[y] = s;
        mask->run_len[y] = e - s;
      }
      x = e;
    }
    mask->contiguous[y] = runs <= 1;
    int first = mask->words, last = -1;
    for (int i = 0; i < mask->words; ++i) {
      if (row[i] != 0) {
        first = std::min(first, i);
        last = i;
      }
    }
    mask->first_word[y] = first;
    mask->last_word[y] = last;
  }
}

// Sets bits a..b (inclusive) of a row.
void FillRun(uint64_t* row, int a, int b) {
  const int first = a >> 6, last = b >> 6;
  const uint64_t head = ~uint64_t(0) << (a & 63), tail = ~uint64_t(0) >> (63 - (b & 63));
  if (first == last) {
    row[first] |= head & tail;
    return;
  }
  row[first] |= head;
  for (int w = first + 1; w < last; ++w) row[w] = ~uint64_t(0);
  row[last] |= tail;
}

uint64_t ReverseBits(uint64_t x) {
  x = ((x >> 1) & 0x5555555555555555ull) | ((x & 0x5555555555555555ull) << 1);
  x = ((x >> 2) & 0x3333333333333333ull) | ((x & 0x3333333333333333ull) << 2);
  x = ((x >> 4) & 0x0F0F0F0F0F0F0F0Full) | ((x & 0x0F0F0F0F0F0F0F0Full) << 4);
  return __builtin_bswap64(x);
}

// The mask turned by half a turn: texel (i, j) -> (w - 1 - i, h - 1 - j),
// as PlacedTexel turns a chart by two quarter turns.
Mask HalfTurn(const Mask& in) {
  Mask out;
  out.Reset(in.w, in.h);
  const int pad = in.words * 64 - in.w;  // unused high bits of a row
  std::vector<uint64_t> reversed(in.words + 1, 0);
  for (int j = 0; j < in.h; ++j) {
    const uint64_t* row = in.Row(j);
    // Bit i goes to words * 64 - 1 - i, then down by `pad` to w - 1 - i.
    for (int k = 0; k < in.words; ++k) reversed[in.words - 1 - k] = ReverseBits(row[k]);
    uint64_t* dst = out.Row(in.h - 1 - j);
    const int word_shift = pad >> 6, bit_shift = pad & 63;
    for (int k = 0; k < in.words; ++k) {
      const int src = k + word_shift;
      uint64_t v = src < in.words ? reversed[src] >> bit_shift : 0;
      if (bit_shift != 0 && src + 1 < in.words) v |= reversed[src + 1] << (64 - bit_shift);
      dst[k] = v;
    }
  }
  return out;
}

// A chart's boundary: the directed edges (corner k to k + 1 of a face,
// local vertex ids) whose reverse is no edge of the chart. Found once per
// chart, whatever the scale. `closed` is false when some directed edge
// belongs to two faces (a fold or a non-manifold fan) or some face is not
// counter-clockwise: then the union of the faces may not be what the
// boundary encloses, and the chart is rasterized face by face.
struct Outline {
  std::vector<std::array<uint32_t, 2>> edges;
  bool closed = true;
};

Outline MakeOutline(const FlatChart& chart) {
  Outline outline;
  if (chart.isolated) return outline;
  // A face turned clockwise (flipped, or flat) folds over its neighbours:
  // the boundary no longer encloses the union of the faces.
  for (size_t f = 0; f < chart.faces.size(); ++f) {
    const double* a = &chart.uv_m[2 * chart.corners[3 * f]];
    const double* b = &chart.uv_m[2 * chart.corners[3 * f + 1]];
    const double* c = &chart.uv_m[2 * chart.corners[3 * f + 2]];
    if (!((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]) > 0)) {
      outline.closed = false;
      return outline;
    }
  }
  // Each vertex's outgoing edges (their heads), in face order.
  const size_t n = chart.vertices.size(), corners = chart.corners.size();
  std::vector<uint32_t> first(n + 1, 0), heads(corners);
  for (size_t i = 0; i < corners; ++i) ++first[chart.corners[i] + 1];
  for (size_t v = 0; v < n; ++v) first[v + 1] += first[v];
  std::vector<uint32_t> next(first.begin(), first.end() - 1);
  auto head = [&](size_t i) { return chart.corners[i % 3 == 2 ? i - 2 : i + 1]; };
  for (size_t i = 0; i < corners; ++i) heads[next[chart.corners[i]]++] = head(i);
  auto has_edge = [&](uint32_t a, uint32_t b) {
    return std::find(heads.begin() + first[a], heads.begin() + first[a + 1], b) !=
           heads.begin() + first[a + 1];
  };
  for (size_t v = 0; v < n; ++v) {
    for (uint32_t i = first[v]; i < first[v + 1]; ++i) {
      if (std::find(heads.begin() + i + 1, heads.begin() + first[v + 1], heads[i]) !=
          heads.begin() + first[v + 1]) {
        outline.closed = false;  // an edge of two faces the same way round
        return outline;
      }
    }
  }
  for (size_t i = 0; i < corners; ++i) {  // face order: deterministic
    const uint32_t a = chart.corners[i], b = head(i);
    if (!has_edge(b, a)) outline.edges.push_back({a, b});
  }
  return outline;
}

// Texels grown by a hair: float UVs may move a vertex by ~1e-4 texel.
constexpr double kEps = 0.01;

// Sets, in rows y0..y1 of `mask`, every texel (grown by kEps) that the
// segment (or triangle, n = 3) through the points x, y touches: per row,
// the extent of the points inside the row's band and of the edges'
// crossings of its two lines.
void FillPolygonRows(const double* x, const double* y, int n, Mask* mask) {
  const int w = mask->w, h = mask->h;
  double lo_y = y[0], hi_y = y[0];
  for (int k = 1; k < n; ++k) {
    lo_y = std::min(lo_y, y[k]);
    hi_y = std::max(hi_y, y[k]);
  }
  const int y0 = std::clamp(int(std::floor(lo_y - kEps)), 0, h - 1);
  const int y1 = std::clamp(int(std::floor(hi_y + kEps)), 0, h - 1);
  const int edges = n == 2 ? 1 : n;
  for (int ty = y0; ty <= y1; ++ty) {
    const double band_lo = ty - kEps, band_hi = ty + 1 + kEps;
    double min_x = std::numeric_limits<double>::infinity(), max_x = -min_x;
    for (int k = 0; k < n; ++k) {
      if (y[k] >= band_lo && y[k] <= band_hi) {
        min_x = std::min(min_x, x[k]);
        max_x = std::max(max_x, x[k]);
      }
    }
    for (int k = 0; k < edges; ++k) {
      const int m = (k + 1) % n;
      if (y[k] == y[m]) continue;
      for (double line : {band_lo, band_hi}) {
        if ((line - y[k]) * (line - y[m]) > 0) continue;
        const double t = (line - y[k]) / (y[m] - y[k]);
        const double xi = x[k] + t * (x[m] - x[k]);
        min_x = std::min(min_x, xi);
        max_x = std::max(max_x, xi);
      }
    }
    if (!(min_x <= max_x)) continue;
    const int tx0 = std::clamp(int(std::floor(min_x - kEps)), 0, w - 1);
    const int tx1 = std::clamp(int(std::floor(max_x + kEps)), 0, w - 1);
    FillRun(mask->Row(ty), tx0, tx1);
  }
}

// The chart's integer box at scale s, turned `quarter_turns` times
// counter-clockwise (the mapping of PlacedTexel), and its conservative
// raster: every texel (grown by kEps) that a face touches. Each turn is
// rasterized from the turned chart: cheaper than turning a large mask bit
// by bit, and exactly the texels the placed UVs touch.
//
// A texel touches the union of the faces (a region without overlaps: the
// charts are checked so) iff it touches the region's boundary or lies
// inside it, i.e. its centre is inside. So only the boundary edges are
// rasterized, and the rows between them filled by the even-odd rule at the
// texel centres: the same texels as rasterizing every face (that takes
// about a face's height in rows per face, ten times more work at 10^5
// faces), face by face only when the outline is not closed.
Mask Rasterize(const FlatChart& chart, const Outline& outline, double s, int quarter_turns) {
  Mask mask;
  if (chart.isolated) {
    mask.Reset(1, 1);
    mask.Set(0, 0);
    return mask;
  }
  RasterPlacement turn;
  turn.box_width = std::max(1, int(std::ceil(chart.width_m * s)));
  turn.box_height = std::max(1, int(std::ceil(chart.height_m * s)));
  turn.quarter_turns = quarter_turns;
  const bool swap = quarter_turns % 2 == 1;
  const int w = swap ? turn.box_height : turn.box_width;
  const int h = swap ? turn.box_width : turn.box_height;
  mask.Reset(w, h);
  const size_t n = chart.vertices.size();
  std::vector<double> tx(n), ty(n);
  for (size_t v = 0; v < n; ++v) {
    const auto texel = PlacedTexel(turn, s, chart.uv_m[2 * v], chart.uv_m[2 * v + 1]);
    tx[v] = texel[0];
    ty[v] = texel[1];
  }
  if (!outline.closed) {
    for (size_t f = 0; f < chart.faces.size(); ++f) {
      double x[3], y[3];
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = chart.corners[3 * f + k];
        x[k] = tx[v];
        y[k] = ty[v];
      }
      FillPolygonRows(x, y, 3, &mask);
    }
    return mask;
  }
  // The boundary's texels, and per row its crossings of the row's centre
  // line (half-open in y, so that a vertex on the line counts once).
  std::vector<int> count(size_t(h) + 1, 0);
  auto crossed_rows = [&](const std::array<uint32_t, 2>& e, int* r0, int* r1) {
    const double ya = ty[e[0]], yb = ty[e[1]];
    // Rows r with min(ya, yb) <= r + 0.5 < max(ya, yb).
    *r0 = std::max(0, int(std::ceil(std::min(ya, yb) - 0.5)));
    *r1 = std::min(h - 1, int(std::ceil(std::max(ya, yb) - 0.5)) - 1);
  };
  for (const auto& e : outline.edges) {
    const double x[2] = {tx[e[0]], tx[e[1]]}, y[2] = {ty[e[0]], ty[e[1]]};
    FillPolygonRows(x, y, 2, &mask);
    int r0, r1;
    crossed_rows(e, &r0, &r1);
    for (int r = r0; r <= r1; ++r) ++count[r + 1];
  }
  for (int r = 0; r < h; ++r) count[r + 1] += count[r];
  std::vector<double> crossing(count[h]);
  std::vector<int> next(count.begin(), count.end() - 1);
  for (const auto& e : outline.edges) {
    int r0, r1;
    crossed_rows(e, &r0, &r1);
    const double xa = tx[e[0]], ya = ty[e[0]], xb = tx[e[1]], yb = ty[e[1]];
    for (int r = r0; r <= r1; ++r) {
      crossing[next[r]++] = xa + (r + 0.5 - ya) / (yb - ya) * (xb - xa);
    }
  }
  for (int r = 0; r < h; ++r) {
    double* begin = crossing.data() + count[r];
    double* end = crossing.data() + count[r + 1];
    // Each boundary vertex decides alone which rows it counts for, so
    // closed loops cross every line an even number of times; an odd count
    // would be a boundary that is not made of loops: face by face then.
    if ((end - begin) % 2 != 0) {
      Outline open;
      open.closed = false;
      return Rasterize(chart, open, s, quarter_turns);
    }
    std::sort(begin, end);
    // The texels holding the crossings are boundary texels already.
    for (double* c = begin; c != end; c += 2) {
      const int a = std::clamp(int(std::floor(c[0])), 0, w - 1);
      const int b = std::clamp(int(std::floor(c[1])), 0, w - 1);
      FillRun(mask.Row(r), a, b);
    }
  }
  return mask;
}

// dst |= src shifted left (towards higher x) by `shift` bits.
void ShiftOr(uint64_t* dst, int dst_words, const uint64_t* src, int src_words, int shift) {
  const int word_shift = shift >> 6, bit_shift = shift & 63;
  for (int i = 0; i < src_words; ++i) {
    const int d = i + word_shift;
    if (d < dst_words) dst[d] |= src[i] << bit_shift;
    if (bit_shift != 0 && d + 1 < dst_words) dst[d + 1] |= src[i] >> (64 - bit_shift);
  }
}

// The mask grown by g texels in x and y (a square), offset by g: each
// direction is an OR over a window of 2g + 1, made by doubling (the window
// of `span` ORed with itself shifted by `span`), log2(2g + 1) passes.
Mask Dilate(const Mask& in, int g) {
  const int window = 2 * g + 1;
  Mask horizontal;
  horizontal.Reset(in.w + 2 * g, in.h);
  const int words = horizontal.words;
  for (int y = 0; y < in.h; ++y) {
    uint64_t* row = horizontal.Row(y);
    std::copy(in.Row(y), in.Row(y) + in.words, row);
    int span = 1;
    while (span < window) {
      // row |= row << step, in place from the top word down (each word
      // reads only lower words, not yet changed).
      const int step = std::min(span, window - span);
      const int word_shift = step >> 6, bit_shift = step & 63;
      for (int i = words - 1; i >= word_shift; --i) {
        uint64_t v = row[i - word_shift] << bit_shift;
        if (bit_shift != 0 && i - word_shift - 1 >= 0) {
          v |= row[i - word_shift - 1] >> (64 - bit_shift);
        }
        row[i] |= v;
      }
      span += step;
    }
  }
  Mask out;
  out.Reset(in.w + 2 * g, in.h + 2 * g);
  for (int y = 0; y < in.h; ++y) {
    std::copy(horizontal.Row(y), horizontal.Row(y) + out.words, out.Row(y));
  }
  // Row y ORs rows y - span + 1 .. y; top down so that row y - step is
  // still the narrower window.
  for (int span = 1; span < window;) {
    const int step = std::min(span, window - span);
    for (int y = out.h - 1; y >= step; --y) {
      uint64_t* row = out.Row(y);
      const uint64_t* below = out.Row(y - step);
      for (int i = 0; i < out.words; ++i) row[i] |= below[i];
    }
    span += step;
  }
  ComputeRuns(&out);
  return out;
}

struct SolidRect {
  int row, lo, width;
};

// Tall windows: besides windows of 2 gutter + 1 rows, the atlas keeps the
// free texels common to windows 2, 4, 8 and 16 times as tall, and the
// search skips rows where a probe's widest solid rectangle of such a
// height finds no free run wide enough. A pure pruning (the same position
// is found), and a strong one: a compact chart holds a solid rectangle
// about as tall as itself, which the fragmented bottom of a nearly full
// atlas rarely has room for.
constexpr int kTallLevels = 4;
constexpr int kTallLevel[kTallLevels] = {2, 4, 8, 16};

// The longest run of set bits of a row of `words` words, limited to
// `limit` bits: its start and length.
std::pair<int, int> LongestRun(const uint64_t* row, int words, int limit) {
  int best_lo = 0, best_len = 0;
  for (int x = 0; x < limit;) {
    const int a = NextBit(row, words, limit, x, true);
    if (a >= limit) break;
    const int e = NextBit(row, words, limit, a, false);
    if (e - a > best_len) {
      best_len = e - a;
      best_lo = a;
    }
    x = e;
  }
  return {best_lo, best_len};
}

// One chart's four turned shapes: the mask to stamp and the dilated one to test.
struct Shapes {
  Mask stamp[4], probe[4];
  std::vector<int> check_rows[4];  // probe rows, most discriminating first
  // Solid rectangles [lo, lo + width) x [row, row + 2 gutter] inside
  // probe[k] (see Atlas::LowestWindowWithRun); the widest first.
  std::vector<SolidRect> solid[4];
  // Per level l of Atlas's tall windows, the widest solid rectangle of
  // kTallLevel[l] x (2 gutter + 1) rows inside probe[k] (width 0: none).
  std::array<SolidRect, kTallLevels> tall[4];
};

Shapes MakeShapes(const FlatChart& chart, const Outline& outline, double s, int gutter) {
  Shapes shapes;
  for (int k = 0; k < (chart.isolated ? 1 : 4); ++k) {
    // Quarter turns 0 and 1 from the triangles, 2 and 3 by half turns.
    // The square dilation commutes with the half turn (the dilated mask is
    // offset by g on every side), so turns 2 and 3 turn the dilated masks too.
    if (k < 2) {
      shapes.stamp[k] = Rasterize(chart, outline, s, k);
      shapes.probe[k] = Dilate(shapes.stamp[k], gutter);
    } else {
      shapes.stamp[k] = HalfTurn(shapes.stamp[k - 2]);
      shapes.probe[k] = HalfTurn(shapes.probe[k - 2]);
      ComputeRuns(&shapes.probe[k]);
    }
    // A stamp row's longest run [a, a + n) at row j: the probe holds the
    // solid rectangle [a, a + n + 2g) x [j, j + 2g] (probe coordinates).
    // Kept for the stamp's longest run (first), and the longest runs of its
    // bottom, middle and top rows.
    {
      const Mask& m = shapes.stamp[k];
      std::vector<int> lo(m.h, 0), len(m.h, 0);
      int longest = 0;
      for (int y = 0; y < m.h; ++y) {
        const uint64_t* row = m.Row(y);
        for (int x = 0; x < m.w;) {
          const int a = NextBit(row, m.words, m.w, x, true);
          if (a >= m.w) break;
          const int e = NextBit(row, m.words, m.w, a, false);
          if (e - a > len[y]) {
            len[y] = e - a;
            lo[y] = a;
          }
          x = e;
        }
        if (len[y] > len[longest]) longest = y;
      }
      for (int y : {longest, 0, m.h - 1, m.h / 2}) {
        if (len[y] == 0) continue;
        bool seen = false;
        for (const SolidRect& rect : shapes.solid[k]) seen = seen || rect.row == y;
        if (!seen) shapes.solid[k].push_back({y, lo[y], len[y] + 2 * gutter});
      }
    }
    if (k >= 2) {
      // The half turn of turn k - 2's rectangles: rows and columns reversed.
      const Mask& m = shapes.probe[k];
      for (int l = 0; l < kTallLevels; ++l) {
        const SolidRect& r = shapes.tall[k - 2][l];
        const int rows = (2 * gutter + 1) * kTallLevel[l];
        shapes.tall[k][l] = r.width == 0
                                ? SolidRect{0, 0, 0}
                                : SolidRect{m.h - r.row - rows, m.w - r.lo - r.width, r.width};
      }
    } else {
      // The probe's rows ANDed over windows of 2 gutter + 1 rows, then
      // doubled level by level; each level's widest run.
      const Mask& m = shapes.probe[k];
      const int base = 2 * gutter + 1;
      std::vector<uint64_t> and_rows;
      int height = 0;  // rows ANDed in and_rows
      int rows = 0;    // valid windows
      for (int l = 0; l < kTallLevels; ++l) {
        shapes.tall[k][l] = {0, 0, 0};
        const int target = base * kTallLevel[l];
        if (target > m.h) continue;
        if (height == 0) {  // base windows first
          rows = m.h - base + 1;
          and_rows.assign(size_t(rows) * m.words, 0);
          for (int r = 0; r < rows; ++r) {
            uint64_t* dst = and_rows.data() + size_t(r) * m.words;
            std::copy(m.Row(r), m.Row(r) + m.words, dst);
            for (int j = 1; j < base; ++j) {
              const uint64_t* src = m.Row(r + j);
              for (int i = 0; i < m.words; ++i) dst[i] &= src[i];
            }
          }
          height = base;
        }
        while (height < target) {  // window r and window r + height
          rows -= height;
          for (int r = 0; r < rows; ++r) {
            uint64_t* dst = and_rows.data() + size_t(r) * m.words;
            const uint64_t* up = dst + size_t(height) * m.words;
            for (int i = 0; i < m.words; ++i) dst[i] &= up[i];
          }
          height *= 2;
        }
        for (int r = 0; r < rows; ++r) {
          const auto [lo, len] = LongestRun(and_rows.data() + size_t(r) * m.words, m.words, m.w);
          if (len > shapes.tall[k][l].width) shapes.tall[k][l] = {r, lo, len};
        }
      }
    }
    const Mask& p = shapes.probe[k];
    std::vector<int>& rows = shapes.check_rows[k];
    // Bottom, top, longest run, then quarters, then every row.
    int longest = 0;
    for (int y = 0; y < p.h; ++y) {
      if (p.run_len[y] > p.run_len[longest]) longest = y;
    }
    for (int y : {longest, 0, p.h - 1, p.h / 2, p.h / 4, 3 * p.h / 4}) {
      if (std::find(rows.begin(), rows.end(), y) == rows.end()) rows.push_back(y);
    }
  }
  return shapes;
}

constexpr int kPruneRows = 6;  // check_rows used to prune candidate x
constexpr int kNearRows = 32;  // rows each side of the last failing one, tried first

// The atlas being filled: `height` rows of `size` texels (twice the square,
// so that an overfull attempt still tells how tall it would be).
class Atlas {
 public:
  // Empties the atlas. An Atlas is reused from packing to packing: its
  // tens of megabytes are then allocated (and faulted in) once.
  void Reset(int size, int height, int window) {
    size_ = size;
    height_ = height;
    words_ = (size + 63) / 64 + 1;
    window_ = window;
    bits_.assign(size_t(words_) * size_t(height_), 0);
    // Bits at and beyond `size` are taken, so free runs end at the edge:
    // words size / 64 on, the same in every row.
    const int first_pad = size_ >> 6;
    const uint64_t partial = ~uint64_t(0) << (size_ & 63);  // of word first_pad
    for (int y = 0; y < height_; ++y) {
      uint64_t* row = Row(y);
      row[first_pad] |= partial;
      for (int w = first_pad + 1; w < words_; ++w) row[w] = ~uint64_t(0);
    }
    max_free_.assign(height_, size_);
    lowest_row_.assign(size_ + 1, 0);
    runs_.assign(height_, std::vector<std::pair<int, int>>(1, {0, size_}));
    window_max_free_.assign(height_, 0);
    window_runs_.assign(height_, {});
    for (int y = 0; y + window_ <= height_; ++y) {
      window_max_free_[y] = size_;
      window_runs_[y].push_back({0, size_});
    }
    lowest_window_.assign(size_ + 1, 0);
    // Every window starts free but for the bits beyond `size`.
    // resize, not assign: the levels keep their memory too (assign made
    // fresh vectors, allocated and faulted in again at every packing).
    level_bits_.resize(kTallLevels + 1);
    for (int l = 0; l <= kTallLevels; ++l) {
      level_bits_[l].assign(bits_.begin(), bits_.end());  // one pass, not zeros then a copy
    }
    for (int l = 0; l < kTallLevels; ++l) {
      const int rows = window_ * kTallLevel[l];
      tall_max_free_[l].assign(height_, 0);
      tall_max_lo_[l].assign(height_, 0);
      for (int y = 0; y + rows <= height_; ++y) tall_max_free_[l][y] = size_;
      lowest_tall_[l].assign(size_ + 1, 0);
    }
  }

  // The lowest-top, then leftmost position of `probe` (its lower-left
  // corner), or false. Positions whose top is above `best_top` are not
  // searched. `check_rows` starts with the rows used to prune candidates.
  struct Scratch {
    std::vector<std::pair<int, int>> candidates, next;
    int last_fail = 0;
  };

  bool Find(const Mask& probe, const std::vector<int>& check_rows,
            const std::vector<SolidRect>& solid, const std::array<SolidRect, kTallLevels>& tall,
            int64_t best_top, Scratch* scratch, int* x_out, int* y_out) const {
    if (probe.w > size_) return false;
    scratch->last_fail = 0;
    auto& candidates_ = scratch->candidates;
    auto& next_ = scratch->next;
    const int prune = std::min<int>(kPruneRows, int(check_rows.size()));
    // Below the lowest row with a long enough free run for a pruning row,
    // nothing fits.
    int start = 0;
    for (int i = 0; i < prune; ++i) {
      const int r = check_rows[i];
      start = std::max(start, LowestRowWithRun(probe.run_len[r]) - r);
    }
    // Nor below the lowest window of rows that holds the probe's solid
    // rectangle.
    for (const SolidRect& rect : solid) {
      start = std::max(start, LowestWindowWithRun(rect.width) - rect.row);
    }
    for (int l = 0; l < kTallLevels; ++l) {
      if (tall[l].width > 0) {
        start = std::max(start, LowestTallWithRun(l, tall[l].width) - tall[l].row);
      }
    }
    for (int y = start; y + probe.h <= height_ && y + probe.h <= best_top; ++y) {
      bool possible = true;
      for (int l = kTallLevels - 1; l >= 0 && possible; --l) {
        possible = tall_max_free_[l][y + tall[l].row] >= tall[l].width;
      }
      for (const SolidRect& rect : solid) {
        possible = possible && window_max_free_[y + rect.row] >= rect.width;
      }
      for (int i = 0; i < prune && possible; ++i) {
        const int r = check_rows[i];
        possible = max_free_[y + r] >= probe.run_len[r];
      }
      if (!possible) continue;
      // The next row's run lists are likely read next: fetch them now
      // (the search waits on memory more than it computes).
      if (y + 1 + probe.h <= height_) {
        for (const SolidRect& rect : solid) {
          __builtin_prefetch(window_runs_[y + 1 + rect.row].data());
        }
        for (int i = 0; i < prune; ++i) __builtin_prefetch(runs_[y + 1 + check_rows[i]].data());
      }
      // Candidate x: where the solid rectangle lies in a free run of its
      // window of rows, and each pruning row's longest run in a free run.
      candidates_.clear();
      {
        const int lo = solid[0].lo, len = solid[0].width;
        for (const auto& [s, e] : window_runs_[y + solid[0].row]) {
          if (e - s < len) continue;
          const int a = std::max(0, s - lo), b = std::min(size_ - probe.w, e - len - lo);
          if (a <= b) candidates_.push_back({a, b});
        }
      }
      const int windows = int(solid.size());
      for (int i = 1 - windows; i < prune && !candidates_.empty(); ++i) {
        // First the other solid rectangles in their windows, then the
        // pruning rows' longest runs in their rows.
        const bool window = i < 0;
        const int r = window ? solid[windows + i].row : check_rows[i];
        const int lo = window ? solid[windows + i].lo : probe.run_lo[r];
        const int len = window ? solid[windows + i].width : probe.run_len[r];
        if (len == 0) continue;
        const auto& runs = window ? window_runs_[y + r] : runs_[y + r];
        next_.clear();
        // Both lists are sorted: one merge pass.
        size_t k = 0;
        for (const auto& [a, b] : candidates_) {
          // Skip free runs that end before a + lo + len.
          while (k < runs.size() && runs[k].second < a + lo + len) ++k;
          for (size_t m = k; m < runs.size() && runs[m].first <= b + lo; ++m) {
            const int c = std::max(a, runs[m].first - lo),
                      d = std::min(b, runs[m].second - len - lo);
            if (c <= d) next_.push_back({c, d});
          }
        }
        candidates_.swap(next_);
      }
      for (const auto& [a, b] : candidates_) {
        for (int x = a; x <= b;) {
          const int next = Fits(probe, check_rows, x, y, &scratch->last_fail);
          if (next < 0) {
            *x_out = x;
            *y_out = y;
            return true;
          }
          x = next;
        }
      }
    }
    return false;
  }

  // The lowest row with a free run of `length` texels or more (height_ if
  // none). Rows only fill up, so the answer only rises: kept per length
  // and advanced lazily.
  int LowestRowWithRun(int length) const {
    if (length <= 0) return 0;
    if (length > size_) return height_;
    int& y = lowest_row_[length];
    while (y < height_ && max_free_[y] < length) ++y;
    return y;
  }

  // The lowest window of `window_` rows whose common free texels hold a run
  // of `length` or more (height_ if none); kept per length like
  // LowestRowWithRun.
  int LowestWindowWithRun(int length) const {
    if (length <= 0) return 0;
    if (length > size_) return height_;
    int& y = lowest_window_[length];
    while (y < height_ && window_max_free_[y] < length) ++y;
    return y;
  }

  // LowestWindowWithRun for the tall windows of level l.
  int LowestTallWithRun(int l, int length) const {
    if (length <= 0) return 0;
    if (length > size_) return height_;
    int& y = lowest_tall_[l][length];
    while (y < height_ && tall_max_free_[l][y] < length) ++y;
    return y;
  }

  // Takes the stamp's texels, its lower-left corner at (x0, y0), and
  // updates the rows' and windows' free runs. Texels are only ever taken,
  // so only the words the stamp covers change, and in each row or window
  // only the free runs over them (each into shorter runs), and a longest
  // free run elsewhere stays the longest.
  void Stamp(const Mask& stamp, int x0, int y0) {
    const int wa = x0 >> 6, wb = std::min(words_ - 1, (x0 + stamp.w - 1) >> 6);
    const int a = x0, b = std::min(size_, x0 + stamp.w);  // the texels that change
    for (int y = 0; y < stamp.h; ++y) {
      uint64_t* row = Row(y0 + y);
      ShiftOr(row, words_, stamp.Row(y), stamp.words, x0);
      auto& runs = runs_[y0 + y];
      SpliceRuns(row, a, b, 1, &runs);
      max_free_[y0 + y] = LongestOf(runs);
    }
    // The windows that contain a stamped row.
    const int first = std::max(0, y0 - window_ + 1);
    const int last = std::min(y0 + stamp.h - 1, height_ - window_);
    // Their words wa..wb: the rows' ORed over the window by doubling (row
    // y of `or_` ORs rows y .. y + span - 1).
    const int width = wb - wa + 1, count = last - first + 1;
    if (count > 0) {
      or_.resize(size_t(count + window_ - 1) * size_t(width));
      for (int y = 0; y < count + window_ - 1; ++y) {
        std::copy(Row(first + y) + wa, Row(first + y) + wb + 1, or_.data() + size_t(y) * width);
      }
      for (int span = 1; span < window_;) {
        const int step = std::min(span, window_ - span);
        for (int y = 0; y + step < count + window_ - 1; ++y) {
          uint64_t* row = or_.data() + size_t(y) * width;
          const uint64_t* up = row + size_t(step) * width;
          for (int i = 0; i < width; ++i) row[i] |= up[i];
        }
        span += step;
      }
    }
    for (int y = first; y <= last; ++y) {
      uint64_t* dst = level_bits_[0].data() + size_t(y) * size_t(words_);
      std::copy(or_.data() + size_t(y - first) * width, or_.data() + size_t(y - first + 1) * width,
                dst + wa);
      // Runs shorter than the window are of no use (every solid rectangle
      // is at least 2 gutter + 1 wide): not kept, and a longest run below
      // the window counts as none.
      auto& runs = window_runs_[y];
      SpliceRuns(dst, a, b, window_, &runs);
      window_max_free_[y] = LongestOf(runs);
    }
    // Each level's windows that contain a stamped row: the OR of two
    // windows of the level below.
    for (int l = 0; l < kTallLevels; ++l) {
      const int half = window_ * (kTallLevel[l] / 2), rows = 2 * half;
      const int top = std::min(y0 + stamp.h - 1, height_ - rows);
      for (int y = std::max(0, y0 - rows + 1); y <= top; ++y) {
        uint64_t* dst = level_bits_[l + 1].data() + size_t(y) * size_t(words_);
        const uint64_t* lower = level_bits_[l].data() + size_t(y) * size_t(words_);
        const uint64_t* upper = lower + size_t(half) * size_t(words_);
        for (int i = wa; i <= wb; ++i) dst[i] = lower[i] | upper[i];
        const int lo = tall_max_lo_[l][y];
        if (lo + tall_max_free_[l][y] <= a || lo >= b) continue;  // the longest is elsewhere
        const auto [best_lo, best] = LongestClearRun(dst, words_);
        tall_max_free_[l][y] = best;
        tall_max_lo_[l][y] = best_lo;
      }
    }
  }

 private:
  uint64_t* Row(int y) { return bits_.data() + size_t(y) * size_t(words_); }
  const uint64_t* Row(int y) const { return bits_.data() + size_t(y) * size_t(words_); }

  // 64 atlas bits from x on, in row y.
  uint64_t Bits(const uint64_t* row, int x) const {
    const int w = x >> 6, b = x & 63;
    return b == 0 ? row[w] : (row[w] >> b) | (row[w + 1] << (64 - b));
  }

  // -1 if the probe fits at (x, y); else the next x worth trying: past the
  // last taken texel under a one-run row that collides, or x + 1.
  int Fits(const Mask& probe, const std::vector<int>& check_rows, int x, int y,
           int* last_fail) const {
    int& last_fail_ = *last_fail;
    auto row_fits = [&](int r) {
      const uint64_t* row = Row(y + r);
      const uint64_t* p = probe.Row(r);
      for (int i = probe.first_word[r]; i <= probe.last_word[r]; ++i) {
        if (p[i] & Bits(row, x + 64 * i)) return false;
      }
      return true;
    };
    auto skip = [&](int r) {
      const uint64_t* row = Row(y + r);
      // The last taken atlas texel under the run [x + lo, x + lo + len).
      const int begin = x + probe.run_lo[r], end = begin + probe.run_len[r];
      int last = -1;
      for (int w = (end - 1) >> 6; w >= (begin >> 6) && last < 0; --w) {
        uint64_t m = row[w];
        if (w == ((end - 1) >> 6) && ((end - 1) & 63) != 63)
          m &= (uint64_t(2) << ((end - 1) & 63)) - 1;
        if (w == (begin >> 6)) m &= ~uint64_t(0) << (begin & 63);
        if (m != 0) last = w * 64 + 63 - __builtin_clzll(m);
      }
      return std::max(x + 1, last + 1 - probe.run_lo[r]);
    };
    // The row that failed last is likely to fail again one step on, else
    // one near it (a probe sliding along a neighbour's edge meets it row
    // after row); which failing row is found does not change the result,
    // every skip stops short of the first position that fits.
    if (last_fail_ < probe.h) {
      if (!row_fits(last_fail_)) return skip(last_fail_);
      const int failed = last_fail_;
      for (int d = 1; d <= kNearRows; ++d) {
        for (int r : {failed + d, failed - d}) {
          if (r >= 0 && r < probe.h && !row_fits(r)) {
            last_fail_ = r;
            return skip(r);
          }
        }
      }
    }
    for (int r : check_rows) {
      if (!row_fits(r)) {
        last_fail_ = r;
        return skip(r);
      }
    }
    for (int r = 0; r < probe.h; ++r) {
      if (!row_fits(r)) {
        last_fail_ = r;
        return skip(r);
      }
    }
    return -1;
  }

  // The free runs (of `min_len` texels or more) of a row of `bits` that
  // had `runs`, after texels in [a, b) were taken: the runs over [a, b)
  // are scanned again.
  void SpliceRuns(const uint64_t* bits, int a, int b, int min_len,
                  std::vector<std::pair<int, int>>* runs) {
    auto& all = *runs;
    auto first = std::partition_point(all.begin(), all.end(),
                                      [&](const auto& run) { return run.second <= a; });
    auto last = first;
    while (last != all.end() && last->first < b) ++last;
    if (first == last) return;
    const int from = first->first, to = (last - 1)->second;
    splice_.clear();
    for (int x = from; x < to;) {
      const int s = NextBit(bits, words_, to, x, false);
      if (s >= to) break;
      const int e = NextBit(bits, words_, to, s, true);
      if (e - s >= min_len) splice_.push_back({s, e});
      x = e;
    }
    const size_t at = size_t(first - all.begin());
    all.erase(first, last);
    all.insert(all.begin() + at, splice_.begin(), splice_.end());
  }

  static int LongestOf(const std::vector<std::pair<int, int>>& runs) {
    int best = 0;
    for (const auto& [s, e] : runs) best = std::max(best, e - s);
    return best;
  }

  int size_ = 0, height_ = 0, words_ = 0, window_ = 0;
  std::vector<int> window_max_free_;        // per window of rows y..y + window_ - 1
  mutable std::vector<int> lowest_window_;  // per run length, see LowestWindowWithRun
  // level_bits_[0]: the windows' taken texels (OR of window_ rows); [l + 1]:
  // of window_ * kTallLevel[l] rows, whose longest free runs are
  // tall_max_free_[l].
  std::vector<std::vector<uint64_t>> level_bits_;
  std::array<std::vector<int>, kTallLevels> tall_max_free_;
  std::array<std::vector<int>, kTallLevels> tall_max_lo_;  // where that run starts
  std::vector<std::pair<int, int>> splice_;                // scratch
  std::vector<uint64_t> or_;                               // scratch
  mutable std::array<std::vector<int>, kTallLevels> lowest_tall_;
  std::vector<std::vector<std::pair<int, int>>> window_runs_;  // free runs of each window
  std::vector<uint64_t> bits_;
  std::vector<int> max_free_;
  mutable std::vector<int> lowest_row_;                 // per run length, see LowestRowWithRun
  std::vector<std::vector<std::pair<int, int>>> runs_;  // free runs [s, e) per row
};

// A chart turned by a fraction of a quarter turn (see RasterPlacement):
// its turned copy, min corner at the origin, with its box.
struct Variant {
  FlatChart chart;
  double angle = 0, min_u = 0, min_v = 0;
};

Variant MakeVariant(const FlatChart& chart, double angle) {
  Variant variant;
  variant.angle = angle;
  variant.chart.faces = chart.faces;
  variant.chart.corners = chart.corners;
  variant.chart.vertices = chart.vertices;
  const size_t n = chart.vertices.size();
  double min_u = std::numeric_limits<double>::infinity(), min_v = min_u;
  for (size_t v = 0; v < n; ++v) {
    const auto t = Turned(angle, 0, 0, chart.uv_m[2 * v], chart.uv_m[2 * v + 1]);
    min_u = std::min(min_u, t[0]);
    min_v = std::min(min_v, t[1]);
  }
  variant.min_u = min_u;
  variant.min_v = min_v;
  variant.chart.uv_m.resize(2 * n);
  double max_u = 0, max_v = 0;
  for (size_t v = 0; v < n; ++v) {
    const auto t = Turned(angle, min_u, min_v, chart.uv_m[2 * v], chart.uv_m[2 * v + 1]);
    variant.chart.uv_m[2 * v] = t[0];
    variant.chart.uv_m[2 * v + 1] = t[1];
    max_u = std::max(max_u, t[0]);
    max_v = std::max(max_v, t[1]);
  }
  variant.chart.width_m = max_u;
  variant.chart.height_m = max_v;
  return variant;
}

// Per chart: its shapes in the minimal rectangle's orientation, then in
// each of its variants'.
std::vector<Shapes> MakeAllShapes(const FlatChart& chart, const Outline& outline,
                                  const std::vector<Variant>& variants, double s, int gutter) {
  std::vector<Shapes> all;
  all.reserve(1 + variants.size());
  all.push_back(MakeShapes(chart, outline, s, gutter));
  // Turning keeps every face counter-clockwise and the boundary the same.
  for (const Variant& v : variants) all.push_back(MakeShapes(v.chart, outline, s, gutter));
  return all;
}

// Packs everything at scale s into a size-wide atlas twice as tall; returns
// the height used (INT64_MAX if a chart fits nowhere) and the placements.
int64_t PackAtScale(const std::vector<FlatChart>& charts, const std::vector<uint32_t>& order,
                    double s, int size, int gutter, int64_t give_up_height,
                    const std::vector<Outline>& outlines,
                    const std::vector<std::vector<Variant>>& variants, bool fallback,
                    Atlas* workspace, std::vector<RasterPlacement>* placements,
                    const std::vector<std::vector<Shapes>>* made = nullptr) {
  // Nothing is placed above the give-up height: no need for those rows.
  Atlas& atlas = *workspace;
  atlas.Reset(size, int(std::min<int64_t>(2 * int64_t(size), give_up_height + 1)), 2 * gutter + 1);
  int64_t used = 0;
  placements->assign(charts.size(), RasterPlacement());
  // Shapes are made block by block in parallel (an attempt that gives up
  // early does not rasterize the rest), placed one by one.
  constexpr size_t kBlock = 64;
  std::vector<std::vector<Shapes>> block;
  Atlas::Scratch scratch;
  for (size_t begin = 0; begin < order.size(); begin += kBlock) {
    const size_t end = std::min(order.size(), begin + kBlock);
    if (made == nullptr) {  // else every chart's shapes are given, at s
      block.assign(end - begin, {});
      tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, 4), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
          const uint32_t c = order[i];
          block[i - begin] = MakeAllShapes(charts[c], outlines[c], variants[c], s, gutter);
        }
      });
    }
    for (size_t i = begin; i < end; ++i) {
      const uint32_t c = order[i];
      const std::vector<Shapes>& all = made != nullptr ? (*made)[c] : block[i - begin];
      // The four turns of each orientation one after the other, each
      // searched only up to the best top edge so far (a packing runs on one
      // thread: the scale search runs its trials side by side instead).
      const int turns = charts[c].isolated ? 1 : 4;
      int64_t best_top = std::numeric_limits<int64_t>::max();
      int best_x = 0, best_y = 0, best_k = -1;
      size_t best_o = 0;
      for (size_t o = 0; o < all.size(); ++o) {
        // Other orientations only for a chart that would raise the top edge.
        if (o > 0 && fallback && best_k >= 0 && best_top <= used) break;
        const Shapes& shape = all[o];
        for (int k = 0; k < turns; ++k) {
          int x = 0, y = 0;
          if (!atlas.Find(shape.probe[k], shape.check_rows[k], shape.solid[k], shape.tall[k],
                          best_top, &scratch, &x, &y)) {
            continue;
          }
          const int64_t top = int64_t(y) + shape.probe[k].h;
          if (top < best_top || (top == best_top && x < best_x)) {
            best_top = top;
            best_x = x;
            best_y = y;
            best_k = k;
            best_o = o;
          }
        }
      }
      if (best_k < 0) return std::numeric_limits<int64_t>::max();
      const Shapes& shape = all[best_o];
      atlas.Stamp(shape.stamp[best_k], best_x + gutter, best_y + gutter);
      used = std::max(used, int64_t(best_y) + shape.probe[best_k].h);
      if (used > give_up_height) return used;
      RasterPlacement& p = (*placements)[c];
      p.x = best_x + gutter;
      p.y = best_y + gutter;
      p.box_width = shape.stamp[0].w;
      p.box_height = shape.stamp[0].h;
      p.quarter_turns = best_k;
      if (best_o > 0) {
        const Variant& v = variants[c][best_o - 1];
        p.angle = v.angle;
        p.min_u = v.min_u;
        p.min_v = v.min_v;
      }
    }
  }
  return used;
}

}  // namespace

std::array<double, 2> PlacedTexel(const RasterPlacement& p, double s, double u, double v) {
  if (p.angle != 0) {
    const auto t = Turned(p.angle, p.min_u, p.min_v, u, v);
    u = t[0];
    v = t[1];
  }
  const double U = u * s, V = v * s;
  double x = U, y = V;
  switch (p.quarter_turns) {
    case 1:
      x = p.box_height - V;
      y = U;
      break;
    case 2:
      x = p.box_width - U;
      y = p.box_height - V;
      break;
    case 3:
      x = V;
      y = p.box_width - U;
      break;
    default:
      break;
  }
  return {double(p.x) + x, double(p.y) + y};
}

Expected<RasterPackResult> RasterPackCharts(const std::vector<FlatChart>& charts, int size_texels,
                                            int gutter_texels) {
  const int size = size_texels, g = gutter_texels;
  RasterPackResult result;
  result.placements.assign(charts.size(), RasterPlacement());
  if (charts.empty()) return result;
  auto too_many = [&]() {
    return Status::Invalid("uv packing: " + std::to_string(charts.size()) +
                           " charts with a gutter of " + std::to_string(g) +
                           " texels do not fit in a " + std::to_string(size) +
                           "-texel atlas; raise `size` or lower `gutter`");
  };
  if (double(charts.size()) * (1.0 + g) * (1.0 + g) > double(size - 2 * g) * (size - 2 * g)) {
    return too_many();
  }
  double area_m2 = 0, longest_m = 0;
  std::vector<double> chart_area(charts.size(), 0.0);
  for (size_t c = 0; c < charts.size(); ++c) {
    if (charts[c].isolated) continue;
    const FlatChart& chart = charts[c];
    for (size_t f = 0; f < chart.faces.size(); ++f) {
      const double* a = &chart.uv_m[2 * chart.corners[3 * f]];
      const double* b = &chart.uv_m[2 * chart.corners[3 * f + 1]];
      const double* d = &chart.uv_m[2 * chart.corners[3 * f + 2]];
      chart_area[c] +=
          0.5 * std::fabs((b[0] - a[0]) * (d[1] - a[1]) - (d[0] - a[0]) * (b[1] - a[1]));
    }
    area_m2 += chart_area[c];
    longest_m = std::max(longest_m, charts[c].width_m);
  }
  std::vector<Outline> outlines(charts.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, charts.size(), 4), [&](const auto& r) {
    for (size_t c = r.begin(); c < r.end(); ++c) outlines[c] = MakeOutline(charts[c]);
  });
  const std::vector<std::vector<Variant>> variants(charts.size());  // none at first
  std::vector<uint32_t> order(charts.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return chart_area[a] > chart_area[b]; });
  const double usable = size - 2.0 * g;
  // No chart may be wider than the square; nothing beats filling it.
  const double s_limit = longest_m > 0 ? (usable - 1) / longest_m : usable;
  const double s_area = area_m2 > 0 ? usable / std::sqrt(area_m2) : usable;
  // The scale search: rounds of two trial packings side by side (one per
  // core; each packing is sequential), the next pair aimed at the scale
  // where the packed height reaches the square (height grows about as s^2
  // on a fixed width: a secant on s^2), inside the bracket [lo, hi) of the
  // largest fitting and smallest failing scales, until it is within 0.8 %.
  // The choices depend only on the trials' results, never on timing.
  struct Trial {
    double s = 0;
    int64_t used = 0;
    std::vector<RasterPlacement> placements;
  };
  constexpr int64_t kNever = std::numeric_limits<int64_t>::max();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double lo = 0, hi = kInf;
  int64_t lo_used = 0;
  Atlas atlases[2];  // one per trial of a pair  // the packed height at lo
  double a = std::min(std::sqrt(0.70) * s_area, s_limit);
  double b = std::min(std::sqrt(0.80) * s_area, s_limit);
  if (b < a * 1.01) a = b / 1.05;
  for (int round = 0; round < 16; ++round) {
    // A failing trial stops a little above the square (its height still
    // aims the next pair) once some scale is known to fit.
    const int64_t give_up = lo > 0 ? size + size / 16 : 2 * int64_t(size);
    Trial trials[2];
    trials[0].s = a;
    trials[1].s = b;
    tbb::parallel_for(0, 2, [&](int i) {
      trials[i].used = PackAtScale(charts, order, trials[i].s, size, g, give_up, outlines, variants,
                                   false, &atlases[i], &trials[i].placements);
    });
    result.attempts += 2;
    // Measured (s^2, height) pairs of this round, for the secant.
    double x[2], y[2];
    int measured = 0;
    for (Trial& trial : trials) {
      if (trial.used <= size) {
        if (trial.s > lo) {
          lo = trial.s;
          lo_used = trial.used;
          result.texels_per_meter = trial.s;
          result.placements = std::move(trial.placements);
        }
      } else if (trial.s > lo && trial.s < hi) {
        hi = trial.s;
      }
      if (trial.used != kNever && trial.used <= give_up) {
        x[measured] = trial.s * trial.s;
        y[measured] = double(std::max<int64_t>(trial.used, 1));
        ++measured;
      }
    }
    if (hi <= lo) hi = kInf;  // a smaller scale failed where a larger fitted
    if (lo > 0 && (hi <= lo * 1.008 || lo >= s_limit || round >= 5)) break;
    // The scale where the height reaches the square, by the secant through
    // this round's heights, else by one height's s^2 rule.
    double target = 0;
    if (measured == 2 && y[1] != y[0] && x[1] != x[0]) {
      const double slope = (y[1] - y[0]) / (x[1] - x[0]);
      const double x_target = x[0] + (double(size) - y[0]) / slope;
      if (slope > 0 && x_target > 0) target = std::sqrt(x_target);
    }
    if (!(target > 0) && measured > 0) target = std::sqrt(x[0] * double(size) / y[0]);
    if (lo == 0 && hi == kInf) {  // nothing fits anywhere yet
      a = 0.5 * std::min(trials[0].s, trials[1].s);
      b = 0.7 * std::min(trials[0].s, trials[1].s);
    } else if (lo == 0) {  // everything tried fails: go below
      const double top = std::min(target > 0 ? target * 0.998 : 0.9 * hi, 0.99 * hi);
      b = top;
      a = top / 1.04;
    } else if (hi == kInf) {  // everything tried fits: go above
      const double bottom = std::max(target > 0 ? target * 0.998 : 1.03 * lo, 1.004 * lo);
      a = std::min(bottom, s_limit);
      b = std::min(bottom * 1.03, s_limit);
      if (a >= s_limit) a = 0.5 * (lo + s_limit);
    } else {  // a bracket: straddle the target by 0.4 % each way, inside it
      const double width = hi - lo;
      // After the first pair (70 % and 80 % of the area bound), when its
      // fitting trial already fills 95 % of the square: the packed height
      // near the square grew faster than s^2 and than the chord from the
      // overfull trial, so on the bunny's 10^5 faces the secant aimed
      // 0.6-1.2 % too high and both trials of the next round failed
      // (docs/uv.md). There the pair aims 0.5 % lower and is 0.78 % wide,
      // so a pair that splits ends the search (a pair 0.8 % wide brackets
      // 1.00803 and never does).
      const bool near_full = round == 0 && double(lo_used) >= 0.95 * double(size);
      const double aimed = near_full ? target * 0.995 : target;
      const double half = near_full ? 0.0039 : 0.004;
      const double center =
          target > 0 ? std::clamp(aimed, lo + 0.2 * width, hi - 0.2 * width) : lo + 0.5 * width;
      a = std::max(center * (1 - half), lo + 0.1 * width);
      b = std::min(center * (1 + half), hi - 0.1 * width);
      if (!(a < b)) {
        a = lo + width / 3;
        b = lo + 2 * width / 3;
      }
    }
  }
  // The packed height jumps with the scale (one chart more or less on the
  // top row), and other orders sometimes nest better: longest side first
  // and shortest side first are tried side by side one step above the best
  // scale so far, climbing while one of them fits (the first if both do).
  // Only while the best packing so far, its height grown as s^2 to the
  // step, would still fit: the other orders then need only to nest about
  // as well as it does. When it would not (a packing that already fills
  // the square), they never fitted on the benchmark meshes (docs/uv.md):
  // two full packings for nothing.
  constexpr double kClimb = 1.012;
  auto worth_climbing = [&]() {
    return lo > 0 && lo * kClimb <= s_limit && double(lo_used) * kClimb * kClimb <= double(size);
  };
  const bool climb = worth_climbing();
  std::vector<uint32_t> others[2];
  for (int variant = 0; variant < 2 && climb; ++variant) {
    others[variant].resize(charts.size());
    std::iota(others[variant].begin(), others[variant].end(), 0u);
    std::vector<double> key(charts.size(), 0.0);
    for (size_t c = 0; c < charts.size(); ++c) {
      if (!charts[c].isolated) key[c] = variant == 0 ? charts[c].width_m : charts[c].height_m;
    }
    std::stable_sort(others[variant].begin(), others[variant].end(),
                     [&](uint32_t a, uint32_t b) { return key[a] > key[b]; });
  }
  for (int step = 0; step < 8 && climb && worth_climbing(); ++step) {
    const double trial_s = lo * kClimb;
    // Both orders pack at the same scale: the masks are made once for both.
    std::vector<std::vector<Shapes>> shapes(charts.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, charts.size(), 4), [&](const auto& r) {
      for (size_t c = r.begin(); c < r.end(); ++c) {
        shapes[c] = MakeAllShapes(charts[c], outlines[c], variants[c], trial_s, g);
      }
    });
    Trial trials[2];
    tbb::parallel_for(0, 2, [&](int i) {
      trials[i].used = PackAtScale(charts, others[i], trial_s, size, g, size, outlines, variants,
                                   false, &atlases[i], &trials[i].placements, &shapes);
    });
    result.attempts += 2;
    Trial* fit = trials[0].used <= size   ? &trials[0]
                 : trials[1].used <= size ? &trials[1]
                                          : nullptr;
    if (fit == nullptr) break;
    lo = trial_s;
    lo_used = fit->used;
    result.texels_per_meter = trial_s;
    result.placements = std::move(fit->placements);
  }
  // Few irregular charts (a 10^4-face scan: tens of charts, each about half
  // its box) nest differently when turned by other angles than the minimal
  // rectangle's quarter turns, and with tens of charts one nesting more or
  // less decides whether the top row fits. Which angles nest better is not
  // predictable (docs/uv.md: on the bunny's 10^4 faces, 0.4 % above the
  // best scale, steps of 30 degrees fitted, everywhere or as a fallback,
  // and of 15 as a fallback; of 45 or 22.5, and of 15 everywhere, not), so a few
  // sets are tried one step above the best scale so far, two side by side,
  // climbing while one fits (the first if both do), switching to the other
  // pair of sets after a round where neither fits, at most kTurnRounds
  // rounds. Each set turns every chart by multiples of 90 / parts degrees;
  // `everywhere` lets every chart take its best turn, else only a chart
  // whose quarter turns would raise the top edge (the packing stays the
  // plain one's until the first such chart). Not for many charts (their
  // masks cost parts times more, and a few hundred charts have many small
  // ones to even out the top row) nor for nearly rectangular ones (a room's
  // walls: the minimal rectangle is their best orientation).
  struct TurnSet {
    int parts;
    bool everywhere;
  };
  constexpr TurnSet kTurnSets[2][2] = {{{3, true}, {3, false}}, {{6, false}, {2, true}}};
  constexpr size_t kTurnMaxCharts = 64;
  constexpr double kTurnMaxFill = 0.8;  // chart area / box area
  constexpr double kTurnStep = 1.004;
  constexpr int kTurnRounds = 3;
  size_t shaped = 0;
  double box_m2 = 0;
  for (const FlatChart& chart : charts) {
    if (chart.isolated) continue;
    ++shaped;
    box_m2 += chart.width_m * chart.height_m;
  }
  if (lo > 0 && shaped <= kTurnMaxCharts && area_m2 < kTurnMaxFill * box_m2) {
    auto make_variants = [&](int parts) {
      std::vector<std::vector<Variant>> out(charts.size());
      tbb::parallel_for(tbb::blocked_range<size_t>(0, charts.size(), 1), [&](const auto& r) {
        for (size_t c = r.begin(); c < r.end(); ++c) {
          if (charts[c].isolated) continue;
          for (int j = 1; j < parts; ++j) {
            out[c].push_back(MakeVariant(charts[c], 0.5 * M_PI * j / parts));
          }
        }
      });
      return out;
    };
    std::vector<std::vector<Variant>> turned[2][2];
    int pair = 0, failed = 0;
    for (int round = 0; round < kTurnRounds && failed < 2 && lo * kTurnStep <= s_limit; ++round) {
      const double trial_s = lo * kTurnStep;
      const TurnSet* sets = kTurnSets[pair];
      for (int i = 0; i < 2; ++i) {
        if (turned[pair][i].empty()) {
          turned[pair][i] = i == 1 && sets[1].parts == sets[0].parts ? turned[pair][0]
                                                                     : make_variants(sets[i].parts);
        }
      }
      // Sets of the same angles pack the same masks: made once for both.
      std::vector<std::vector<Shapes>> shapes;
      if (sets[0].parts == sets[1].parts) {
        shapes.resize(charts.size());
        tbb::parallel_for(tbb::blocked_range<size_t>(0, charts.size(), 1), [&](const auto& r) {
          for (size_t c = r.begin(); c < r.end(); ++c) {
            shapes[c] = MakeAllShapes(charts[c], outlines[c], turned[pair][0][c], trial_s, g);
          }
        });
      }
      Trial trials[2];
      tbb::parallel_for(0, 2, [&](int i) {
        trials[i].used = PackAtScale(charts, order, trial_s, size, g, size, outlines,
                                     turned[pair][i], !sets[i].everywhere, &atlases[i],
                                     &trials[i].placements, shapes.empty() ? nullptr : &shapes);
      });
      result.attempts += 2;
      Trial* fit = trials[0].used <= size   ? &trials[0]
                   : trials[1].used <= size ? &trials[1]
                                            : nullptr;
      if (fit == nullptr) {
        pair = 1 - pair;
        ++failed;
        continue;
      }
      failed = 0;
      lo = trial_s;
      lo_used = fit->used;
      result.texels_per_meter = trial_s;
      result.placements = std::move(fit->placements);
    }
  }
  // A few large, nearly rectangular charts (walls) can pack tighter as boxes
  // on a skyline (pack.h): keep whichever packing has the larger scale.
  std::vector<ChartExtent> extents(charts.size());
  for (size_t c = 0; c < charts.size(); ++c) {
    extents[c] =
        charts[c].isolated ? ChartExtent{0, 0} : ChartExtent{charts[c].width_m, charts[c].height_m};
  }
  auto boxes = PackCharts(extents, size, g);
  if (boxes.ok() && boxes->texels_per_meter > lo) {
    lo = boxes->texels_per_meter;
    result.texels_per_meter = lo;
    for (size_t c = 0; c < charts.size(); ++c) {
      RasterPlacement& p = result.placements[c];
      p.x = boxes->x_texels[c];
      p.y = boxes->y_texels[c];
      p.box_width = std::max(1, int(std::ceil(extents[c].width * lo)));
      p.box_height = std::max(1, int(std::ceil(extents[c].height * lo)));
      p.quarter_turns = boxes->turned[c] ? 1 : 0;
    }
    result.boxes = true;
  }
  if (!(lo > 0)) return too_many();
  return result;
}

}  // namespace pb
