// Campaign report: reads a finished campaign folder (the contract is in
// report.h) and writes results.json, results.csv, report.md, report.html and
// images/. docs/report.md describes every file, the time grouping (paper
// Fig. 7), the speed-ups and the crop rule.
//
// One file for the whole report: the CMake entry names only report.cc. Its
// sections, in order: reading the campaign, derived figures (speed-ups),
// images (thumbnails, crops), the data files, SVG charts, Markdown, HTML.
#include "stages/report/report.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "engine/base/env.h"
#include "stages/geometry/frames.h"
#include "stages/geometry/image.h"
#include "stages/geometry/table.h"

namespace pb {
namespace {

// Ordered: results.json keeps the contract's key order.
using Json = nlohmann::ordered_json;
using Opt = std::optional<double>;

// Construction-time groups (report.h), in the order of results.json.
constexpr int kGroupCount = 6;
constexpr int kIoGroup = 4;
constexpr std::array<const char*, kGroupCount> kGroups = {"points", "high_mesh", "low_mesh",
                                                          "uv",     "io",        "bake"};
constexpr std::array<const char*, kGroupCount> kGroupTitles = {"Normals (points)",
                                                               "High-mesh construction",
                                                               "Low-mesh construction",
                                                               "UV unwrapping",
                                                               "I/O",
                                                               "Baking"};
constexpr std::array<const char*, kGroupCount> kGroupColors = {"#8c6bb1", "#d94801", "#fd8d3c",
                                                               "#41ab5d", "#969696", "#2171b5"};

constexpr int kQualityCount = 5;
constexpr std::array<const char*, kQualityCount> kQualityColumns = {
    "psnr_db", "ssim_luma", "ssim_rgb", "ms_ssim_luma", "flip_mean"};
constexpr std::array<const char*, kQualityCount> kQualityTitles = {"PSNR dB", "SSIM luma",
                                                                   "SSIM RGB", "MS-SSIM", "FLIP"};
const char* kDash = "\xE2\x80\x94";  // "—"

struct Row {
  std::string name, scene, workflow, variant, status, error, dir;
  std::string run_dir;  // campaign_dir/dir
  std::array<Opt, kGroupCount> time_s{};
  Opt total_s, peak_ram_bytes;
  Opt faces, texture_width, texture_height, texture_bytes, fps;
  std::optional<bool> fits;
  std::string device;
  std::array<Opt, kQualityCount> vs_hpm{}, vs_truth{};
  bool ok() const { return status == "ok"; }
};

struct Campaign {
  std::string name, file, started;
  Opt total_wall_s;
  Json host = Json::object();
  std::vector<Row> rows;            // sorted: scene order, then workflow order
  std::vector<std::string> scenes;  // in order of first appearance
};

int WorkflowRank(const std::string& workflow) {
  static const std::array<const char*, 4> known = {"hpm", "lpm", "remeshing", "point_transfer"};
  for (size_t i = 0; i < known.size(); ++i)
    if (workflow == known[i]) return int(i);
  return int(known.size());
}

std::string DisplayName(const std::string& workflow, const std::string& variant) {
  static const std::map<std::string, std::string> names = {{"hpm", "HPM"},
                                                           {"lpm", "LPM"},
                                                           {"remeshing", "Remeshing"},
                                                           {"point_transfer", "Point transfer"}};
  auto it = names.find(workflow);
  std::string name = it == names.end() ? workflow : it->second;
  return variant.empty() ? name : name + " (" + variant + ")";
}
std::string DisplayName(const Row& row) { return DisplayName(row.workflow, row.variant); }

Opt JsonNumber(const Json& j, const char* key) {
  auto it = j.find(key);
  if (it == j.end() || !it->is_number()) return std::nullopt;
  return it->get<double>();
}
Opt TableOpt(const Table& table, size_t row, const char* column) {
  const double v = TableNumber(table.get(row, column));
  return std::isfinite(v) ? Opt(v) : std::nullopt;
}

Expected<Json> ReadJsonFile(const std::string& path) {
  PB_ASSIGN_OR_RETURN(std::string text, Env::Default()->ReadFile(path));
  try {
    return Json::parse(text);
  } catch (const Json::exception& e) {
    return Status::Corrupt(path + ": malformed JSON: " + e.what());
  }
}

// ---- Reading the campaign folder -----------------------------------------

// Fills time_s, total_s and peak_ram_bytes from the stage entries of run.json.
Status ReadRunTimes(const std::string& path, Row& row) {
  PB_ASSIGN_OR_RETURN(Json run, ReadJsonFile(path));
  try {
    if (!run.is_object() || !run.contains("stages") || !run["stages"].is_array())
      return Status::Corrupt(path + ": no \"stages\" array");
    std::array<double, kGroupCount> sum{};
    std::array<bool, kGroupCount> present{}, unknown{};
    std::optional<double> peak;
    for (const Json& stage : run["stages"]) {
      if (!stage.is_object()) return Status::Corrupt(path + ": a stage entry is not an object");
      const std::string group = stage.value("group", "");
      const auto g = std::find(kGroups.begin(), kGroups.end(), group);
      if (g == kGroups.end()) continue;  // input, evaluation, reference, none
      const int gi = int(g - kGroups.begin());
      const std::string status = stage.value("status", "");
      if (status == "skipped" || status == "pending") continue;
      const Json* figures = &stage;
      if (status == "hit")
        figures = stage.contains("cached_run") && stage["cached_run"].is_object()
                      ? &stage["cached_run"]
                      : nullptr;
      const Opt wall = figures ? JsonNumber(*figures, "wall_s") : std::nullopt;
      present[gi] = true;
      if (!wall) {
        unknown[gi] = true;
        continue;
      }
      double io_s = 0;
      if (figures->contains("phases") && (*figures)["phases"].is_array())
        for (const Json& phase : (*figures)["phases"])
          if (phase.is_object() && phase.value("name", "") == "io")
            io_s += JsonNumber(phase, "dur_s").value_or(0);
      io_s = std::clamp(io_s, 0.0, std::max(*wall, 0.0));
      if (gi == kIoGroup) {
        sum[kIoGroup] += std::max(*wall, 0.0);
      } else {
        sum[gi] += std::max(*wall, 0.0) - io_s;
        if (io_s > 0) {
          sum[kIoGroup] += io_s;
          present[kIoGroup] = true;
        }
      }
      if (Opt rss = JsonNumber(*figures, "peak_rss_bytes")) peak = std::max(peak.value_or(0), *rss);
    }
    double total = 0;
    bool any = false, total_known = true;
    for (int i = 0; i < kGroupCount; ++i) {
      if (!present[i]) continue;
      any = true;
      if (unknown[i]) {
        total_known = false;
        continue;
      }
      row.time_s[i] = sum[i];
      total += sum[i];
    }
    if (any && total_known) row.total_s = total;
    row.peak_ram_bytes = peak;
  } catch (const Json::exception& e) {
    return Status::Corrupt(path + ": " + e.what());
  }
  return Status::Ok();
}

// The "mean" row of a metrics.image table; absent file = all null.
Status ReadQuality(const std::string& path, std::array<Opt, kQualityCount>& out) {
  if (!Env::Default()->Exists(path)) return Status::Ok();
  PB_ASSIGN_OR_RETURN(Table table, ReadTable(path));
  for (size_t r = 0; r < table.rows.size(); ++r) {
    const TableValue frame = table.get(r, "frame");
    if (!std::holds_alternative<std::string>(frame) || std::get<std::string>(frame) != "mean")
      continue;
    for (int q = 0; q < kQualityCount; ++q) out[q] = TableOpt(table, r, kQualityColumns[q]);
    return Status::Ok();
  }
  return Status::Corrupt(path + ": no row with frame \"mean\"");
}

Status ReadFps(const std::string& path, Row& row) {
  if (!Env::Default()->Exists(path)) return Status::Ok();
  PB_ASSIGN_OR_RETURN(Table table, ReadTable(path));
  if (table.rows.empty()) return Status::Corrupt(path + ": the FPS table has no row");
  row.faces = TableOpt(table, 0, "triangles");
  row.texture_width = TableOpt(table, 0, "texture_width");
  row.texture_height = TableOpt(table, 0, "texture_height");
  row.texture_bytes = TableOpt(table, 0, "texture_bytes");
  row.fps = TableOpt(table, 0, "fps");
  const TableValue fits = table.get(0, "fits_texture_budget");
  if (std::holds_alternative<bool>(fits)) row.fits = std::get<bool>(fits);
  const TableValue device = table.get(0, "device");
  if (std::holds_alternative<std::string>(device)) row.device = std::get<std::string>(device);
  return Status::Ok();
}

Expected<Campaign> ReadCampaign(const std::string& campaign_dir) {
  const std::string path = JoinPath(campaign_dir, "campaign.json");
  PB_ASSIGN_OR_RETURN(Json manifest, ReadJsonFile(path));
  Campaign c;
  try {
    if (!manifest.is_object() || manifest.value("format", "") != "pointbake-campaign")
      return Status::Corrupt(
          path + ": not a campaign manifest (\"format\" is not \"pointbake-campaign\")");
    if (manifest.value("version", 0) > 1)
      return Status::Unsupported(path + ": campaign format version " +
                                 std::to_string(manifest.value("version", 0)) +
                                 " is newer than this reader (1)");
    c.name = manifest.value("name", "");
    c.file = manifest.value("file", "");
    c.started = manifest.value("started", "");
    c.total_wall_s = JsonNumber(manifest, "total_wall_s");
    if (manifest.contains("host") && manifest["host"].is_object()) c.host = manifest["host"];
    if (!manifest.contains("runs") || !manifest["runs"].is_array())
      return Status::Corrupt(path + ": no \"runs\" array");
    for (const Json& run : manifest["runs"]) {
      Row row;
      for (auto [key, field] : {std::pair{"name", &row.name},
                                {"scene", &row.scene},
                                {"workflow", &row.workflow},
                                {"dir", &row.dir},
                                {"status", &row.status}}) {
        if (!run.is_object() || !run.contains(key) || !run[key].is_string())
          return Status::Corrupt(path + ": run " + std::to_string(c.rows.size()) +
                                 " has no string \"" + key + "\"");
        *field = run[key].get<std::string>();
      }
      row.variant = run.value("variant", "");
      row.error = run.value("error", "");
      row.run_dir = JoinPath(campaign_dir, row.dir);
      if (std::find(c.scenes.begin(), c.scenes.end(), row.scene) == c.scenes.end())
        c.scenes.push_back(row.scene);
      c.rows.push_back(std::move(row));
    }
  } catch (const Json::exception& e) {
    return Status::Corrupt(path + ": " + e.what());
  }
  for (Row& row : c.rows) {
    if (!row.ok()) continue;  // failed runs: a row of nulls
    PB_RETURN_IF_ERROR(ReadRunTimes(JoinPath(row.run_dir, "run.json"), row));
    PB_RETURN_IF_ERROR(ReadQuality(JoinPath(row.run_dir, "vs_hpm.json"), row.vs_hpm));
    PB_RETURN_IF_ERROR(ReadQuality(JoinPath(row.run_dir, "vs_truth.json"), row.vs_truth));
    PB_RETURN_IF_ERROR(ReadFps(JoinPath(row.run_dir, "fps.json"), row));
  }
  auto scene_rank = [&](const std::string& s) {
    return std::find(c.scenes.begin(), c.scenes.end(), s) - c.scenes.begin();
  };
  std::stable_sort(c.rows.begin(), c.rows.end(), [&](const Row& a, const Row& b) {
    return std::make_tuple(scene_rank(a.scene), WorkflowRank(a.workflow), a.workflow, a.variant) <
           std::make_tuple(scene_rank(b.scene), WorkflowRank(b.workflow), b.workflow, b.variant);
  });
  return c;
}

// ---- Speed-ups -------------------------------------------------------------

struct SpeedUp {
  std::string scene, workflow, variant;
  double ratio;  // other workflow's total / point transfer's total
};
struct SpeedUpMean {
  std::string workflow, variant;
  double ratio;
  int scenes;
};

// The point-transfer row a scene's speed-ups are measured against: the one
// without variant, else the first variant.
const Row* PointTransferRow(const Campaign& c, const std::string& scene) {
  const Row* found = nullptr;
  for (const Row& r : c.rows)
    if (r.scene == scene && r.workflow == "point_transfer" &&
        (!found || (r.variant.empty() && !found->variant.empty())))
      found = &r;
  return found;
}

std::vector<SpeedUp> SpeedUps(const Campaign& c) {
  std::vector<SpeedUp> out;
  for (const std::string& scene : c.scenes) {
    const Row* pt = PointTransferRow(c, scene);
    if (!pt || !pt->total_s || *pt->total_s <= 0) continue;
    for (const Row& r : c.rows)
      if (&r != pt && r.scene == scene && r.total_s && *r.total_s > 0)
        out.push_back({scene, r.workflow, r.variant, *r.total_s / *pt->total_s});
  }
  return out;
}

std::vector<SpeedUpMean> GeometricMeans(const std::vector<SpeedUp>& speedups) {
  std::vector<SpeedUpMean> out;
  std::vector<std::pair<double, int>> acc;  // sum of logs, count; parallel to out
  for (const SpeedUp& s : speedups) {
    size_t i = 0;
    while (i < out.size() && !(out[i].workflow == s.workflow && out[i].variant == s.variant)) ++i;
    if (i == out.size()) {
      out.push_back({s.workflow, s.variant, 0, 0});
      acc.push_back({0, 0});
    }
    acc[i].first += std::log(s.ratio);
    acc[i].second += 1;
  }
  for (size_t i = 0; i < out.size(); ++i) {
    out[i].ratio = std::exp(acc[i].first / acc[i].second);
    out[i].scenes = acc[i].second;
  }
  return out;
}

// ---- Formatting ------------------------------------------------------------

std::string Printf(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}
std::string FmtSeconds(Opt v) {
  if (!v) return kDash;
  return Printf(*v >= 100 ? "%.0f" : *v >= 10 ? "%.1f" : "%.2f", *v);
}
std::string FmtBytes(Opt v) {
  if (!v) return kDash;
  if (*v >= 1024.0 * 1024 * 1024) return Printf("%.2f GiB", *v / (1024.0 * 1024 * 1024));
  return Printf("%.0f MiB", *v / (1024.0 * 1024));
}
std::string FmtFixed(Opt v, const char* format) { return v ? Printf(format, *v) : kDash; }
std::string FmtQuality(Opt v, int q) { return FmtFixed(v, q == 0 ? "%.2f" : "%.4f"); }
std::string FmtRatio(double r) { return Printf(r >= 10 ? "%.1f\xC3\x97" : "%.2f\xC3\x97", r); }
std::string FmtTexture(const Row& r) {
  if (!r.texture_width || !r.texture_height) return kDash;
  if (*r.texture_width == 0 && *r.texture_height == 0) return "none";
  return Printf("%.0f", *r.texture_width) + "\xC3\x97" + Printf("%.0f", *r.texture_height);
}
std::string FmtFits(const Row& r) { return r.fits ? (*r.fits ? "yes" : "no") : kDash; }

std::string EscapeHtml(const std::string& s) {
  std::string out;
  for (char ch : s) {
    switch (ch) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += ch;
    }
  }
  return out;
}
std::string EscapeMd(const std::string& s) {
  std::string out;
  for (char ch : s) {
    if (ch == '|' || ch == '*' || ch == '_' || ch == '`' || ch == '[' || ch == ']' || ch == '\\')
      out += '\\';
    out += ch == '\n' ? ' ' : ch;
  }
  return out;
}
std::string Slug(const std::string& s) {
  std::string out;
  for (char ch : s) out += (std::isalnum(static_cast<unsigned char>(ch)) || ch == '-') ? ch : '_';
  return out;
}

// ---- Images ----------------------------------------------------------------

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

// Box filter: each output pixel averages the source pixels it covers
// (integer bounds), so every source pixel counts once.
Image BoxDownscale(const Image& in, int max_side) {
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
      std::array<uint32_t, 3> sum{};
      for (int sy = y0; sy < y1; ++sy)
        for (int sx = x0; sx < x1; ++sx)
          for (int c = 0; c < 3; ++c) sum[c] += in.at_u8(sx, sy, c);
      const uint32_t n = uint32_t((y1 - y0) * (x1 - x0));
      for (int c = 0; c < 3; ++c) out.at_u8(x, y, c) = uint8_t((sum[c] + n / 2) / n);
    }
  }
  return out;
}

struct CropWindow {
  int x = 0, y = 0, size = 0;
};

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

// An image of the report: written to images/<file> (for report.md) and kept
// as a data: URI (for report.html).
struct ReportImage {
  std::string file;  // relative to the report folder
  std::string data_uri;
  int width = 0, height = 0;
};

Expected<ReportImage> SaveImage(const std::string& report_dir, const std::string& name,
                                const Image& image) {
  PB_ASSIGN_OR_RETURN(std::vector<uint8_t> png, EncodePng(image));
  ReportImage out{"images/" + name + ".png", "data:image/png;base64," + Base64(png), image.width,
                  image.height};
  PB_RETURN_IF_ERROR(Env::Default()->WriteFileAtomic(
      JoinPath(report_dir, out.file),
      std::string_view(reinterpret_cast<const char*>(png.data()), png.size())));
  return out;
}

// ---- The side-by-side frames ---------------------------------------------

struct FrameCell {
  std::string title;  // column title
  std::string note;   // why there is no image ("run failed", "no frames")
  std::optional<ReportImage> thumb, crop, flip;
  std::string flip_title;
};
struct ViewSection {
  std::string view;
  CropWindow window;
  std::vector<FrameCell> cells;
};
struct SceneImages {
  std::string scene;
  std::vector<ViewSection> views;
};

// Reads <dir>/frames.json if it exists; nullopt when absent.
Expected<std::optional<FrameSet>> MaybeReadFrames(const std::string& dir) {
  const std::string index = JoinPath(dir, kFramesIndexFile);
  if (!Env::Default()->Exists(index)) return std::optional<FrameSet>();
  PB_ASSIGN_OR_RETURN(FrameSet set, ReadFrames(index));
  return std::optional<FrameSet>(std::move(set));
}

Expected<SceneImages> BuildSceneImages(const Campaign& c, const std::string& scene,
                                       const std::string& report_dir,
                                       const ReportOptions& options) {
  struct Column {
    std::string title, note, flip_title;
    std::optional<FrameSet> frames, flip;
    const Row* row = nullptr;
  };
  std::vector<Column> columns;
  std::optional<FrameSet> truth;
  for (const Row& r : c.rows) {
    if (r.scene != scene || !r.ok() || truth) continue;
    PB_ASSIGN_OR_RETURN(truth, MaybeReadFrames(JoinPath(r.run_dir, "truth_frames")));
  }
  if (truth) columns.push_back({"Ground truth", "", "", std::move(truth), std::nullopt, nullptr});
  const bool has_truth = !columns.empty();
  for (const Row& r : c.rows) {
    if (r.scene != scene) continue;
    Column col{DisplayName(r), "", "", std::nullopt, std::nullopt, &r};
    if (!r.ok()) {
      col.note = "run failed";
    } else {
      PB_ASSIGN_OR_RETURN(col.frames, MaybeReadFrames(JoinPath(r.run_dir, "frames")));
      if (!col.frames) col.note = "no frames";
      if (has_truth) {
        PB_ASSIGN_OR_RETURN(col.flip, MaybeReadFrames(JoinPath(r.run_dir, "flip_truth")));
        col.flip_title = "FLIP vs ground truth";
      } else {
        PB_ASSIGN_OR_RETURN(col.flip, MaybeReadFrames(JoinPath(r.run_dir, "flip_hpm")));
        col.flip_title = "FLIP vs HPM";
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
      FrameCell cell{col.title, col.note, std::nullopt, std::nullopt, std::nullopt, col.flip_title};
      const std::string base =
          Slug(scene) + "__" + Slug(col.row ? col.row->name : "truth") + "__" + Slug(view);
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
      section.cells.push_back(std::move(cell));
    }
    out.views.push_back(std::move(section));
  }
  return out;
}

// ---- results.json / results.csv -------------------------------------------

Json OptJson(Opt v) { return v ? Json(*v) : Json(nullptr); }
Json IntJson(Opt v) { return v ? Json(int64_t(std::llround(*v))) : Json(nullptr); }

Json RowJson(const Row& r) {
  Json times = Json::object();
  // Microseconds are the clock's resolution; rounding hides summation noise.
  auto micro = [](Opt v) { return v ? OptJson(std::round(*v * 1e6) / 1e6) : Json(nullptr); };
  for (int g = 0; g < kGroupCount; ++g) times[kGroups[g]] = micro(r.time_s[g]);
  times["total"] = micro(r.total_s);
  auto quality = [](const std::array<Opt, kQualityCount>& q) {
    Json j = Json::object();
    for (int i = 0; i < kQualityCount; ++i) j[kQualityColumns[i]] = OptJson(q[i]);
    return j;
  };
  Json texture = nullptr;
  if (r.texture_width && r.texture_height)
    texture = {{"width_px", IntJson(r.texture_width)}, {"height_px", IntJson(r.texture_height)}};
  Json j = {{"name", r.name},
            {"scene", r.scene},
            {"workflow", r.workflow},
            {"variant", r.variant},
            {"display_name", DisplayName(r)},
            {"status", r.status},
            {"time_s", times},
            {"peak_ram_bytes", IntJson(r.peak_ram_bytes)},
            {"faces", IntJson(r.faces)},
            {"texture_size", texture},
            {"texture_bytes", IntJson(r.texture_bytes)},
            {"fps", OptJson(r.fps)},
            {"fits", r.fits ? Json(*r.fits) : Json(nullptr)},
            {"device", r.device.empty() ? Json(nullptr) : Json(r.device)},
            {"vs_hpm", quality(r.vs_hpm)},
            {"vs_truth", quality(r.vs_truth)}};
  if (!r.error.empty()) j["error"] = r.error;
  return j;
}

Json ResultsJson(const Campaign& c, const std::vector<SpeedUp>& speedups,
                 const std::vector<SpeedUpMean>& means) {
  Json rows = Json::array();
  for (const Row& r : c.rows) rows.push_back(RowJson(r));
  Json per_scene = Json::array(), mean = Json::array();
  for (const SpeedUp& s : speedups)
    per_scene.push_back(
        {{"scene", s.scene}, {"workflow", s.workflow}, {"variant", s.variant}, {"ratio", s.ratio}});
  for (const SpeedUpMean& m : means)
    mean.push_back({{"workflow", m.workflow},
                    {"variant", m.variant},
                    {"ratio", m.ratio},
                    {"scenes", m.scenes}});
  return {{"format", "pointbake-report"},
          {"version", 1},
          {"campaign",
           {{"name", c.name},
            {"file", c.file},
            {"started", c.started},
            {"total_wall_s", OptJson(c.total_wall_s)}}},
          {"host", c.host},
          {"rows", rows},
          {"speedups",
           {{"versus", "point_transfer"}, {"per_scene", per_scene}, {"geometric_mean", mean}}}};
}

std::string CsvField(const Json& v) {
  if (v.is_null()) return "";
  std::string s = v.is_string() ? v.get<std::string>() : v.dump();
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string quoted = "\"";
  for (char ch : s) quoted += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return quoted + "\"";
}

std::string ResultsCsv(const Campaign& c) {
  std::vector<std::string> header = {"name", "scene", "workflow", "variant", "status"};
  for (const char* g : kGroups) header.push_back(std::string("time_") + g + "_s");
  for (const char* h : {"time_total_s", "peak_ram_bytes", "faces", "texture_width_px",
                        "texture_height_px", "texture_bytes", "fps", "fits_budget", "device"})
    header.push_back(h);
  for (const char* prefix : {"vs_hpm_", "vs_truth_"})
    for (const char* q : kQualityColumns) header.push_back(prefix + std::string(q));
  header.push_back("error");
  std::string out;
  for (size_t i = 0; i < header.size(); ++i) out += (i ? "," : "") + header[i];
  out += "\n";
  for (const Row& r : c.rows) {
    const Json j = RowJson(r);
    std::vector<Json> values = {j["name"], j["scene"], j["workflow"], j["variant"], j["status"]};
    for (const char* g : kGroups) values.push_back(j["time_s"][g]);
    const Json& tex = j["texture_size"];
    for (const Json& v : {j["time_s"]["total"], j["peak_ram_bytes"], j["faces"],
                          tex.is_null() ? Json(nullptr) : tex["width_px"],
                          tex.is_null() ? Json(nullptr) : tex["height_px"], j["texture_bytes"],
                          j["fps"], j["fits"], j["device"]})
      values.push_back(v);
    for (const char* key : {"vs_hpm", "vs_truth"})
      for (const char* q : kQualityColumns) values.push_back(j[key][q]);
    values.push_back(r.error.empty() ? Json(nullptr) : Json(r.error));
    for (size_t i = 0; i < values.size(); ++i) out += (i ? "," : "") + CsvField(values[i]);
    out += "\n";
  }
  return out;
}

// ---- SVG charts --------------------------------------------------------------

// A "nice" axis step (1, 2 or 5 × 10^k) giving about five ticks up to `max`.
double NiceStep(double max) {
  if (!(max > 0)) return 1;
  const double raw = max / 5, magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (raw <= m * magnitude) return m * magnitude;
  return 10 * magnitude;
}

std::string Num(double v) { return Printf("%.1f", v); }

struct Bar {
  std::string label;
  std::vector<std::pair<int, double>> segments;  // (group or -1, value)
  std::string end_label;                         // total / "failed" / "—"
};

// Horizontal bars with an x axis in `unit`; `scale` divides raw values.
std::string SvgBars(const std::vector<Bar>& bars, const std::string& unit, double scale,
                    const std::string& title) {
  const double label_w = 190, plot_w = 460, row_h = 26, top = 8, width = 760;
  double max = 0;
  for (const Bar& b : bars) {
    double sum = 0;
    for (const auto& s : b.segments) sum += s.second / scale;
    max = std::max(max, sum);
  }
  const double step = NiceStep(max), axis_max = std::max(step, std::ceil(max / step - 1e-9) * step);
  const double height = top + row_h * double(bars.size()) + 34;
  std::string svg = "<svg class=\"chart\" role=\"img\" width=\"" + Num(width) + "\" height=\"" +
                    Num(height) + "\" viewBox=\"0 0 " + Num(width) + " " + Num(height) +
                    "\"><title>" + EscapeHtml(title) + "</title>";
  const double axis_y = top + row_h * double(bars.size());
  for (double t = 0; t <= axis_max + step * 1e-6; t += step) {
    const double x = label_w + plot_w * t / axis_max;
    svg += "<line x1=\"" + Num(x) + "\" y1=\"" + Num(top) + "\" x2=\"" + Num(x) + "\" y2=\"" +
           Num(axis_y + 4) + "\" stroke=\"#ddd\"/>";
    svg += "<text x=\"" + Num(x) + "\" y=\"" + Num(axis_y + 17) +
           "\" text-anchor=\"middle\" class=\"tick\">" + Printf(step < 1 ? "%.2g" : "%.0f", t) +
           "</text>";
  }
  svg += "<line x1=\"" + Num(label_w) + "\" y1=\"" + Num(axis_y) + "\" x2=\"" +
         Num(label_w + plot_w) + "\" y2=\"" + Num(axis_y) + "\" stroke=\"#333\"/>";
  svg += "<text x=\"" + Num(label_w + plot_w / 2) + "\" y=\"" + Num(axis_y + 31) +
         "\" text-anchor=\"middle\" class=\"axis\">" + EscapeHtml(unit) + "</text>";
  for (size_t i = 0; i < bars.size(); ++i) {
    const Bar& b = bars[i];
    const double y = top + row_h * double(i);
    svg += "<text x=\"" + Num(label_w - 8) + "\" y=\"" + Num(y + row_h * 0.65) +
           "\" text-anchor=\"end\">" + EscapeHtml(b.label) + "</text>";
    double x = label_w;
    for (const auto& [group, value] : b.segments) {
      const double w = plot_w * value / scale / axis_max;
      if (w <= 0) continue;
      const char* color = group >= 0 ? kGroupColors[size_t(group)] : "#6a51a3";
      svg += "<rect x=\"" + Num(x) + "\" y=\"" + Num(y + 4) + "\" width=\"" + Printf("%.2f", w) +
             "\" height=\"" + Num(row_h - 8) + "\" fill=\"" + color + "\"><title>" +
             EscapeHtml((group >= 0 ? std::string(kGroupTitles[size_t(group)]) + ": " : "") +
                        Printf("%.3g", value / scale) + " " + unit) +
             "</title></rect>";
      x += w;
    }
    svg += "<text x=\"" + Num(x + 6) + "\" y=\"" + Num(y + row_h * 0.65) + "\" class=\"value\">" +
           EscapeHtml(b.end_label) + "</text>";
  }
  return svg + "</svg>";
}

std::string TimeChart(const Campaign& c, const std::string& scene) {
  std::vector<Bar> bars;
  for (const Row& r : c.rows) {
    if (r.scene != scene) continue;
    Bar b{
        DisplayName(r), {}, r.ok() ? (r.total_s ? FmtSeconds(r.total_s) + " s" : kDash) : "failed"};
    for (int g = 0; g < kGroupCount; ++g)
      if (r.time_s[size_t(g)]) b.segments.push_back({g, *r.time_s[size_t(g)]});
    bars.push_back(std::move(b));
  }
  return SvgBars(bars, "seconds", 1, "Construction time, " + scene);
}

std::string RamChart(const Campaign& c, const std::string& scene) {
  double max = 0;
  for (const Row& r : c.rows)
    if (r.scene == scene && r.peak_ram_bytes) max = std::max(max, *r.peak_ram_bytes);
  const bool gib = max >= 1024.0 * 1024 * 1024;
  const double scale = gib ? 1024.0 * 1024 * 1024 : 1024.0 * 1024;
  std::vector<Bar> bars;
  for (const Row& r : c.rows) {
    if (r.scene != scene) continue;
    Bar b{DisplayName(r), {}, r.ok() ? FmtBytes(r.peak_ram_bytes) : "failed"};
    if (r.peak_ram_bytes) b.segments.push_back({-1, *r.peak_ram_bytes});
    bars.push_back(std::move(b));
  }
  return SvgBars(bars, gib ? "GiB" : "MiB", scale, "Peak RAM, " + scene);
}

std::string Legend() {
  std::string html = "<div class=\"legend\">";
  for (int g = 0; g < kGroupCount; ++g)
    html += std::string("<span><i style=\"background:") + kGroupColors[size_t(g)] + "\"></i>" +
            kGroupTitles[size_t(g)] + "</span>";
  return html + "</div>";
}

// ---- Tables (shared by Markdown and HTML) -----------------------------------

struct TextTable {
  size_t text_columns = 2;  // leading left-aligned columns; the rest are numbers
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

TextTable TimesTable(const Campaign& c) {
  TextTable t;
  t.text_columns = 3;
  t.header = {"Scene", "Workflow", "Status"};
  for (const char* g : kGroupTitles) t.header.push_back(std::string(g) + " s");
  t.header.push_back("Total s");
  t.header.push_back("Peak RAM");
  for (const Row& r : c.rows) {
    std::vector<std::string> cells = {r.scene, DisplayName(r), r.status};
    for (const Opt& v : r.time_s) cells.push_back(FmtSeconds(v));
    cells.push_back(FmtSeconds(r.total_s));
    cells.push_back(FmtBytes(r.peak_ram_bytes));
    t.rows.push_back(cells);
  }
  return t;
}

TextTable QualityTable(const Campaign& c, bool vs_truth) {
  TextTable t;
  t.header = {"Scene", "Workflow"};
  for (const char* q : kQualityTitles) t.header.push_back(q);
  for (const Row& r : c.rows) {
    std::vector<std::string> cells = {r.scene, DisplayName(r)};
    const auto& q = vs_truth ? r.vs_truth : r.vs_hpm;
    for (int i = 0; i < kQualityCount; ++i) cells.push_back(FmtQuality(q[size_t(i)], i));
    t.rows.push_back(cells);
  }
  return t;
}

TextTable FpsTable(const Campaign& c) {
  TextTable t;
  t.header = {"Scene",       "Workflow",    "Faces", "Texture",
              "Texture MiB", "Fits budget", "FPS",   "Device"};
  for (const Row& r : c.rows)
    t.rows.push_back({r.scene, DisplayName(r), FmtFixed(r.faces, "%.0f"), FmtTexture(r),
                      r.texture_bytes ? Printf("%.1f", *r.texture_bytes / (1024.0 * 1024)) : kDash,
                      FmtFits(r), FmtFixed(r.fps, "%.1f"), r.device.empty() ? kDash : r.device});
  return t;
}

TextTable SpeedUpTable(const Campaign& c, const std::vector<SpeedUp>& speedups,
                       const std::vector<SpeedUpMean>& means) {
  TextTable t;
  t.text_columns = 1;
  t.header = {"Versus"};
  for (const std::string& s : c.scenes) t.header.push_back(s);
  t.header.push_back("Geometric mean");
  for (const SpeedUpMean& m : means) {
    std::vector<std::string> cells = {DisplayName(m.workflow, m.variant)};
    for (const std::string& scene : c.scenes) {
      std::string cell = kDash;
      for (const SpeedUp& s : speedups)
        if (s.scene == scene && s.workflow == m.workflow && s.variant == m.variant)
          cell = FmtRatio(s.ratio);
      cells.push_back(cell);
    }
    cells.push_back(FmtRatio(m.ratio) + " (" + std::to_string(m.scenes) +
                    (m.scenes == 1 ? " scene)" : " scenes)"));
    t.rows.push_back(cells);
  }
  return t;
}

std::string MarkdownTable(const TextTable& t) {
  std::string md = "|";
  for (const std::string& h : t.header) md += " " + EscapeMd(h) + " |";
  md += "\n|";
  for (size_t i = 0; i < t.header.size(); ++i) md += i < t.text_columns ? " --- |" : " ---: |";
  md += "\n";
  for (const auto& row : t.rows) {
    md += "|";
    for (const std::string& cell : row) md += " " + EscapeMd(cell) + " |";
    md += "\n";
  }
  return md;
}

std::string HtmlTable(const TextTable& t) {
  std::string html = "<table><thead><tr>";
  for (size_t i = 0; i < t.header.size(); ++i)
    html += (i < t.text_columns ? "<th class=\"l\">" : "<th>") + EscapeHtml(t.header[i]) + "</th>";
  html += "</tr></thead><tbody>";
  for (const auto& row : t.rows) {
    html += "<tr>";
    for (size_t i = 0; i < row.size(); ++i)
      html += (i < t.text_columns ? "<td class=\"l\">" : "<td>") + EscapeHtml(row[i]) + "</td>";
    html += "</tr>";
  }
  return html + "</tbody></table>";
}

// ---- report.md / report.html ------------------------------------------------

std::string HostLine(const Campaign& c) {
  std::string s;
  for (const char* key : {"name", "hostname"})
    if (c.host.contains(key) && c.host[key].is_string()) s += c.host[key].get<std::string>() + ", ";
  if (c.host.contains("cpu") && c.host["cpu"].is_string()) s += c.host["cpu"].get<std::string>();
  if (Opt cores = JsonNumber(c.host, "cores")) s += Printf(", %.0f cores", *cores);
  if (Opt mem = JsonNumber(c.host, "memory_bytes")) s += ", " + FmtBytes(mem) + " RAM";
  return s.empty() ? "unknown" : s;
}

const char* kTimesNote =
    "Times are construction times, grouped as in the paper's Fig. 7 (plus the normals of the point "
    "preparation). They exclude producing the scan (group input), evaluation (rendering, metrics, "
    "FPS "
    "estimate) and the HPM reference chain inside other workflows. A stage's \"io\" phase counts "
    "as I/O; "
    "cache hits count with the figures of the run that computed them.";

std::string SpeedUpSentence(const std::vector<SpeedUpMean>& means) {
  if (means.empty())
    return "No speed-ups: the campaign has no point-transfer run with another workflow to compare.";
  std::string s = "Point transfer's speed-up: ";
  for (size_t i = 0; i < means.size(); ++i) {
    if (i) s += i + 1 == means.size() ? " and " : ", ";
    s += FmtRatio(means[i].ratio) + " over " + DisplayName(means[i].workflow, means[i].variant);
  }
  return s +
         " (the other workflow's total construction time divided by point transfer's, geometric "
         "mean "
         "over scenes; above 1\xC3\x97 point transfer is faster).";
}

std::string ReportMarkdown(const Campaign& c, const TextTable& times, const TextTable& vs_hpm,
                           const TextTable& vs_truth, const TextTable& fps, const TextTable& speed,
                           const std::string& speed_sentence,
                           const std::vector<SceneImages>& images) {
  std::string md = "# Campaign report: " + EscapeMd(c.name) + "\n\n";
  md += "- Started: " + (c.started.empty() ? std::string(kDash) : c.started) + "\n";
  md += "- Machine: " + EscapeMd(HostLine(c)) + "\n";
  md += "- Campaign file: " + (c.file.empty() ? std::string(kDash) : "`" + c.file + "`") + "\n\n";
  md +=
      kTimesNote + std::string("\n\n## Construction time and peak RAM\n\n") + MarkdownTable(times);
  md += "\n## Speed-ups of point transfer\n\n" + speed_sentence + "\n\n" + MarkdownTable(speed);
  md += "\n## Quality against HPM\n\n" + MarkdownTable(vs_hpm);
  md += "\n## Quality against ground truth\n\n" + MarkdownTable(vs_truth);
  md += "\n## Faces, textures and FPS estimate\n\n" + MarkdownTable(fps);
  for (const SceneImages& s : images) {
    for (const ViewSection& v : s.views) {
      md += "\n## " + EscapeMd(s.scene) + ", view " + EscapeMd(v.view) + "\n\n";
      for (const FrameCell& cell : v.cells) {
        md += "**" + EscapeMd(cell.title) + "**";
        if (!cell.note.empty()) md += " (" + EscapeMd(cell.note) + ")";
        md += "\n\n";
        if (cell.thumb) md += "![" + EscapeMd(cell.title) + "](" + cell.thumb->file + ") ";
        if (cell.crop) md += "![crop](" + cell.crop->file + ") ";
        if (cell.flip) md += "![" + EscapeMd(cell.flip_title) + "](" + cell.flip->file + ")";
        md += "\n\n";
      }
    }
  }
  return md;
}

const char* kCss =
    "body{font-family:sans-serif;margin:24px;color:#222;background:#fff;max-width:1400px}"
    "h1{font-size:24px}h2{font-size:19px;margin-top:32px;border-bottom:1px solid "
    "#ccc}h3{font-size:16px}"
    "table{border-collapse:collapse;margin:8px 0;font-size:13px}th,td{border:1px solid "
    "#ccc;padding:3px 8px;"
    "text-align:right}th{background:#f0f0f0}td.l,th.l{text-align:left}"
    "svg.chart text{font-size:12px;fill:#222}svg.chart text.tick{fill:#555;font-size:11px}"
    ".legend span{margin-right:14px;font-size:13px}.legend "
    "i{display:inline-block;width:12px;height:12px;"
    "margin-right:4px;vertical-align:-1px}.frames{display:flex;flex-wrap:wrap;gap:12px}"
    ".cell{border:1px solid #ddd;padding:6px;font-size:12px}.cell img{display:block;margin-top:4px}"
    ".crop{image-rendering:pixelated}.note{color:#a00}.meta{font-size:14px}";

std::string Img(const std::optional<ReportImage>& image, const std::string& alt,
                const char* cls = "") {
  if (!image) return "";
  return "<img class=\"" + std::string(cls) + "\" alt=\"" + EscapeHtml(alt) + "\" width=\"" +
         std::to_string(image->width) + "\" height=\"" + std::to_string(image->height) +
         "\" src=\"" + image->data_uri + "\">";
}

std::string ReportHtml(const Campaign& c, const TextTable& times, const TextTable& vs_hpm,
                       const TextTable& vs_truth, const TextTable& fps, const TextTable& speed,
                       const std::string& speed_sentence, const std::vector<SceneImages>& images,
                       const ReportOptions& options) {
  std::string h =
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>pointbake report: " +
      EscapeHtml(c.name) + "</title><style>" + kCss + "</style></head><body>\n";
  h += "<h1>Campaign report: " + EscapeHtml(c.name) + "</h1><div class=\"meta\"><p>Started " +
       EscapeHtml(c.started.empty() ? kDash : c.started) +
       (c.total_wall_s ? ", campaign wall time " + FmtSeconds(c.total_wall_s) + " s" : "") +
       ". Machine: " + EscapeHtml(HostLine(c)) + ".</p><p>" + EscapeHtml(kTimesNote) +
       "</p></div>\n";
  h += "<h2>Construction time</h2>" + Legend();
  for (const std::string& scene : c.scenes)
    h += "<h3>" + EscapeHtml(scene) + "</h3>" + TimeChart(c, scene);
  h += "\n<h2>Peak RAM</h2>";
  for (const std::string& scene : c.scenes)
    h += "<h3>" + EscapeHtml(scene) + "</h3>" + RamChart(c, scene);
  h += "\n<h2>Speed-ups of point transfer</h2><p>" + EscapeHtml(speed_sentence) + "</p>" +
       HtmlTable(speed);
  h += "\n<h2>Times and peak RAM</h2>" + HtmlTable(times);
  h += "\n<h2>Quality against HPM</h2>" + HtmlTable(vs_hpm);
  h += "\n<h2>Quality against ground truth</h2>" + HtmlTable(vs_truth);
  h += "\n<h2>Faces, textures and FPS estimate</h2>" + HtmlTable(fps);
  for (const SceneImages& s : images) {
    for (const ViewSection& v : s.views) {
      h +=
          "\n<h2>" + EscapeHtml(s.scene) + ", view " + EscapeHtml(v.view) +
          "</h2><p>Crop: " + std::to_string(v.window.size) + "\xC3\x97" +
          std::to_string(v.window.size) + " px at (" + std::to_string(v.window.x) + ", " +
          std::to_string(v.window.y) +
          "), where point transfer and LPM differ most (the frame centre without both), enlarged " +
          std::to_string(std::max(1, options.thumbnail_px / v.window.size)) +
          "\xC3\x97 (nearest neighbor); yellow box in the frames.</p><div class=\"frames\">";
      for (const FrameCell& cell : v.cells) {
        h += "<div class=\"cell\"><b>" + EscapeHtml(cell.title) + "</b>";
        if (!cell.note.empty()) h += "<div class=\"note\">" + EscapeHtml(cell.note) + "</div>";
        h += Img(cell.thumb, cell.title);
        if (cell.crop) h += "<div>Crop</div>" + Img(cell.crop, cell.title + " crop", "crop");
        if (cell.flip)
          h += "<div>" + EscapeHtml(cell.flip_title) + "</div>" + Img(cell.flip, cell.flip_title);
        h += "</div>";
      }
      h += "</div>";
    }
  }
  return h + "\n</body></html>\n";
}

}  // namespace

Status WriteCampaignReport(const std::string& campaign_dir, const std::string& report_dir,
                           const ReportOptions& options) {
  if (options.thumbnail_px < 16 || options.crop_px < 4 || options.max_viewpoints < 0)
    return Status::Invalid(
        "report options: thumbnail_px must be >= 16, crop_px >= 4, max_viewpoints >= 0");
  PB_ASSIGN_OR_RETURN(Campaign campaign, ReadCampaign(campaign_dir));
  Env* env = Env::Default();
  PB_RETURN_IF_ERROR(env->CreateDirs(JoinPath(report_dir, "images")));
  std::vector<SceneImages> images;
  for (const std::string& scene : campaign.scenes) {
    PB_ASSIGN_OR_RETURN(SceneImages s, BuildSceneImages(campaign, scene, report_dir, options));
    images.push_back(std::move(s));
  }
  const std::vector<SpeedUp> speedups = SpeedUps(campaign);
  const std::vector<SpeedUpMean> means = GeometricMeans(speedups);
  const TextTable times = TimesTable(campaign), vs_hpm = QualityTable(campaign, false),
                  vs_truth = QualityTable(campaign, true), fps = FpsTable(campaign),
                  speed = SpeedUpTable(campaign, speedups, means);
  const std::string sentence = SpeedUpSentence(means);
  PB_RETURN_IF_ERROR(env->WriteFileAtomic(JoinPath(report_dir, "results.json"),
                                          ResultsJson(campaign, speedups, means).dump(2) + "\n"));
  PB_RETURN_IF_ERROR(
      env->WriteFileAtomic(JoinPath(report_dir, "results.csv"), ResultsCsv(campaign)));
  PB_RETURN_IF_ERROR(env->WriteFileAtomic(
      JoinPath(report_dir, "report.md"),
      ReportMarkdown(campaign, times, vs_hpm, vs_truth, fps, speed, sentence, images)));
  return env->WriteFileAtomic(
      JoinPath(report_dir, "report.html"),
      ReportHtml(campaign, times, vs_hpm, vs_truth, fps, speed, sentence, images, options));
}

}  // namespace pb
