// Campaign report, presentation: the tables (shared by Markdown and HTML),
// the SVG bar charts, report.md and report.html (self-contained: inline CSS
// and SVG, images as data: URIs, no scripts).
#include <cctype>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "base/markup.h"
#include "cli/report/report_internal.h"

namespace pb::report_internal {
namespace {

// Bar colors of the construction-time groups, parallel to kGroups.
constexpr std::array<const char*, kGroupCount> kGroupColors = {"#8c6bb1", "#d94801", "#fd8d3c",
                                                               "#41ab5d", "#969696", "#2171b5"};
const char* kDash = "\xE2\x80\x94";  // "—"

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

std::string EscapeMd(const std::string& s) {
  std::string out;
  for (char ch : s) {
    if (ch == '|' || ch == '*' || ch == '_' || ch == '`' || ch == '[' || ch == ']' || ch == '\\')
      out += '\\';
    out += ch == '\n' ? ' ' : ch;
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
                    "\"><title>" + EscapeMarkup(title) + "</title>";
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
         "\" text-anchor=\"middle\" class=\"axis\">" + EscapeMarkup(unit) + "</text>";
  for (size_t i = 0; i < bars.size(); ++i) {
    const Bar& b = bars[i];
    const double y = top + row_h * double(i);
    svg += "<text x=\"" + Num(label_w - 8) + "\" y=\"" + Num(y + row_h * 0.65) +
           "\" text-anchor=\"end\">" + EscapeMarkup(b.label) + "</text>";
    double x = label_w;
    for (const auto& [group, value] : b.segments) {
      const double w = plot_w * value / scale / axis_max;
      if (w <= 0) continue;
      const char* color = group >= 0 ? kGroupColors[size_t(group)] : "#6a51a3";
      svg += "<rect x=\"" + Num(x) + "\" y=\"" + Num(y + 4) + "\" width=\"" + Printf("%.2f", w) +
             "\" height=\"" + Num(row_h - 8) + "\" fill=\"" + color + "\"><title>" +
             EscapeMarkup((group >= 0 ? std::string(kGroupTitles[size_t(group)]) + ": " : "") +
                        Printf("%.3g", value / scale) + " " + unit) +
             "</title></rect>";
      x += w;
    }
    svg += "<text x=\"" + Num(x + 6) + "\" y=\"" + Num(y + row_h * 0.65) + "\" class=\"value\">" +
           EscapeMarkup(b.end_label) + "</text>";
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

// Against the scan: covered-pixel image figures (unlit frames vs the scan's
// splats), coverage, holes, and the mesh's agreement with the scan.
TextTable ScanTable(const Campaign& c) {
  TextTable t;
  t.header = {"Scene", "Workflow"};
  for (const char* q : kScanTitles) t.header.push_back(q);
  for (const Row& r : c.rows) {
    std::vector<std::string> cells = {r.scene, DisplayName(r)};
    for (int i = 0; i < kScanCount; ++i) {
      const Opt& v = r.vs_scan[size_t(i)];
      const std::string col = kScanColumns[size_t(i)];
      if (col == "covered_psnr_db")
        cells.push_back(FmtFixed(v, "%.2f"));
      else if (col.size() > 9 && col.compare(col.size() - 9, 9, "_fraction") == 0)
        cells.push_back(v ? Printf("%.2f", *v * 100) : kDash);
      else if (col == "boundary_edges_per_1000_faces")
        cells.push_back(FmtFixed(v, "%.1f"));
      else
        cells.push_back(FmtFixed(v, "%.4f"));
    }
    t.rows.push_back(cells);
  }
  return t;
}

// The coverage maps' caption (metrics.image output `coverage`, the run's
// `coverage_scan`), and their key, said once per report.
const char* kCoverageTitle = "Coverage vs scan";
const char* kCoverageKey =
    "Coverage vs scan: gray, the model where the scan has it too; red, a hole pixel at the model's "
    "outline (a scan sample the model leaves as background); orange, a deeper open hole; yellow, a "
    "hole the model encloses; magenta, the model's surface in front of the scan's (invented); cyan, "
    "behind it; blue, the model where the scan shows nothing; dark gray, only the scan's splat disks; "
    "black, neither. In the thumbnails a pixel whose pixels hold a hole, or surface in front or "
    "behind, shows the most telling of them, in that order, so single hole pixels stay visible; any "
    "other shows what most of its pixels are.";

bool AnyCoverage(const std::vector<SceneImages>& images) {
  for (const SceneImages& s : images)
    for (const ViewSection& v : s.views)
      for (const FrameCell& cell : v.cells)
        if (cell.coverage) return true;
  return false;
}

const char* kScanNote =
    "Each workflow's model drawn unlit against the scan itself drawn as splats from the same "
    "viewpoints (render.splats; the scan's colors are already lit, so both sides are unlit). "
    "PSNR, SSIM and FLIP on the pixels covered in both frames (edge pixels left out); coverage IoU "
    "= covered in both / covered in either; holes = pixels into which a visible scan point projects "
    "(the scan's evidence) where the model leaves background, % of those pixels; disk holes = the same "
    "on every pixel the scan's splats cover (a disk reaches a local spacing past its point, several "
    "pixels at a sparse border), % of them; in front / behind = pixels both cover where the model's "
    "surface lies more than 5 % of the depth in front of (invented surface) or behind the scan's, % "
    "of the scan's pixels, left out of PSNR, SSIM and FLIP. Invented area: % of the mesh's area farther than "
    "max(3 local spacings, its mean edge) from every scan point; missing scan: % of scan points "
    "farther than 3 local spacings from the mesh; boundary edges: edges with one face; back faces: "
    "% of the lit frames' samples on the model that see a face from behind (a headset culls those: "
    "a high share means a model turned inside out).";

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
    html += (i < t.text_columns ? "<th class=\"l\">" : "<th>") + EscapeMarkup(t.header[i]) + "</th>";
  html += "</tr></thead><tbody>";
  for (const auto& row : t.rows) {
    html += "<tr>";
    for (size_t i = 0; i < row.size(); ++i)
      html += (i < t.text_columns ? "<td class=\"l\">" : "<td>") + EscapeMarkup(row[i]) + "</td>";
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

bool AnyWarnings(const Campaign& c) {
  return std::any_of(c.rows.begin(), c.rows.end(),
                     [](const Row& r) { return !r.warnings.empty(); });
}
constexpr const char* kNoWarnings = "No stage of any run reported a warning.";

// The links to the 3-D viewer (viewer/index.html, report_viewer.cc): every
// model, each scene, each run. The page loads the models over HTTP, so the
// text says how to serve the campaign folder.
constexpr const char* kViewerNote =
    "Open them through `pointbake serve CAMPAIGN_DIR` (it prints the address; a browser cannot "
    "load the models from a file: page).";

std::string ViewerUrl(const std::string& key, const std::string& value) {
  std::string url = "viewer/index.html?" + key + "=";
  for (unsigned char ch : value) {
    if (std::isalnum(ch) || ch == '-' || ch == '_' || ch == '.') {
      url.push_back(char(ch));
    } else {
      char escaped[4];
      std::snprintf(escaped, sizeof(escaped), "%%%02X", ch);
      url += escaped;
    }
  }
  return url;
}

std::string ViewerHtml(const Campaign& c) {
  std::string h = "<h2>3-D viewer</h2><p><a href=\"viewer/index.html\">All models in 3-D</a> (linked "
                  "cameras, orbit and walk, color/normal/wireframe toggles, PNG or KTX2 textures, "
                  "Enter VR). " + EscapeMarkup(kViewerNote) + "</p><p>";
  for (const std::string& scene : c.scenes) {
    h += "<b>" + EscapeMarkup(scene) + "</b>: <a href=\"" + EscapeMarkup(ViewerUrl("scene", scene)) + "\">all</a>";
    for (const Row& r : c.rows) {
      if (r.scene == scene && r.ok()) {
        h += " · <a href=\"" + EscapeMarkup(ViewerUrl("run", r.name)) + "\">" + EscapeMarkup(DisplayName(r)) + "</a>";
      }
    }
    h += "<br>";
  }
  return h + "</p>\n";
}

std::string ViewerMarkdown(const Campaign& c) {
  std::string md = "3-D viewer: [all models](viewer/index.html)";
  for (const std::string& scene : c.scenes) md += ", [" + EscapeMd(scene) + "](" + ViewerUrl("scene", scene) + ")";
  return md + ". " + kViewerNote + "\n\n";
}

std::string ReportMarkdown(const Campaign& c, const TextTable& times, const TextTable& vs_hpm,
                           const TextTable& vs_truth, const TextTable& vs_scan, const TextTable& fps, const TextTable& speed,
                           const std::string& speed_sentence,
                           const std::vector<SceneImages>& images) {
  std::string md = "# Campaign report: " + EscapeMd(c.name) + "\n\n";
  md += "- Started: " + (c.started.empty() ? std::string(kDash) : c.started) + "\n";
  md += "- Machine: " + EscapeMd(HostLine(c)) + "\n";
  md += "- Campaign file: " + (c.file.empty() ? std::string(kDash) : "`" + c.file + "`") + "\n\n";
  md += ViewerMarkdown(c);
  md +=
      kTimesNote + std::string("\n\n## Construction time and peak RAM\n\n") + MarkdownTable(times);
  md += "\n## Speed-ups of point transfer\n\n" + speed_sentence + "\n\n" + MarkdownTable(speed);
  md += "\n## Quality against HPM\n\n" + MarkdownTable(vs_hpm);
  md += "\n## Quality against ground truth\n\n" + MarkdownTable(vs_truth);
  md += "\n## Against the scan\n\n" + std::string(kScanNote) + "\n\n" + MarkdownTable(vs_scan);
  md += "\n## Faces, textures and FPS estimate\n\n" + MarkdownTable(fps);
  md += "\n## Warnings\n\n";
  if (!AnyWarnings(c)) md += std::string(kNoWarnings) + "\n";
  for (const Row& r : c.rows)
    for (const auto& [stage, text] : r.warnings)
      md += "- " + EscapeMd(DisplayName(r)) + " on " + EscapeMd(r.scene) + ", stage `" + stage +
            "`: " + EscapeMd(text) + "\n";
  if (AnyCoverage(images)) md += "\n" + std::string(kCoverageKey) + "\n";
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
        if (cell.coverage) md += " ![" + std::string(kCoverageTitle) + "](" + cell.coverage->file + ")";
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
  return "<img class=\"" + std::string(cls) + "\" alt=\"" + EscapeMarkup(alt) + "\" width=\"" +
         std::to_string(image->width) + "\" height=\"" + std::to_string(image->height) +
         "\" src=\"" + image->data_uri + "\">";
}

std::string ReportHtml(const Campaign& c, const TextTable& times, const TextTable& vs_hpm,
                       const TextTable& vs_truth, const TextTable& vs_scan, const TextTable& fps, const TextTable& speed,
                       const std::string& speed_sentence, const std::vector<SceneImages>& images,
                       const ReportOptions& options) {
  std::string h =
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>pointbake report: " +
      EscapeMarkup(c.name) + "</title><style>" + kCss + "</style></head><body>\n";
  h += "<h1>Campaign report: " + EscapeMarkup(c.name) + "</h1><div class=\"meta\"><p>Started " +
       EscapeMarkup(c.started.empty() ? kDash : c.started) +
       (c.total_wall_s ? ", campaign wall time " + FmtSeconds(c.total_wall_s) + " s" : "") +
       ". Machine: " + EscapeMarkup(HostLine(c)) + ".</p><p>" + EscapeMarkup(kTimesNote) +
       "</p></div>\n";
  h += ViewerHtml(c);
  h += "<h2>Construction time</h2>" + Legend();
  for (const std::string& scene : c.scenes)
    h += "<h3>" + EscapeMarkup(scene) + "</h3>" + TimeChart(c, scene);
  h += "\n<h2>Peak RAM</h2>";
  for (const std::string& scene : c.scenes)
    h += "<h3>" + EscapeMarkup(scene) + "</h3>" + RamChart(c, scene);
  h += "\n<h2>Speed-ups of point transfer</h2><p>" + EscapeMarkup(speed_sentence) + "</p>" +
       HtmlTable(speed);
  h += "\n<h2>Times and peak RAM</h2>" + HtmlTable(times);
  h += "\n<h2>Quality against HPM</h2>" + HtmlTable(vs_hpm);
  h += "\n<h2>Quality against ground truth</h2>" + HtmlTable(vs_truth);
  h += "\n<h2>Against the scan</h2><p>" + EscapeMarkup(kScanNote) + "</p>" + HtmlTable(vs_scan);
  h += "\n<h2>Faces, textures and FPS estimate</h2>" + HtmlTable(fps);
  h += "\n<h2>Warnings</h2>";
  if (!AnyWarnings(c))
    h += "<p>" + std::string(kNoWarnings) + "</p>";
  else
    h += "<ul>";
  for (const Row& r : c.rows)
    for (const auto& [stage, text] : r.warnings)
      h += "<li>" + EscapeMarkup(DisplayName(r)) + " on " + EscapeMarkup(r.scene) + ", stage <code>" +
           EscapeMarkup(stage) + "</code>: " + EscapeMarkup(text) + "</li>";
  if (AnyWarnings(c)) h += "</ul>";
  if (AnyCoverage(images)) h += "\n<p>" + EscapeMarkup(kCoverageKey) + "</p>";
  for (const SceneImages& s : images) {
    for (const ViewSection& v : s.views) {
      h +=
          "\n<h2>" + EscapeMarkup(s.scene) + ", view " + EscapeMarkup(v.view) +
          "</h2><p>Crop: " + std::to_string(v.window.size) + "\xC3\x97" +
          std::to_string(v.window.size) + " px at (" + std::to_string(v.window.x) + ", " +
          std::to_string(v.window.y) +
          "), where point transfer and LPM differ most (the frame centre without both), enlarged " +
          std::to_string(std::max(1, options.thumbnail_px / v.window.size)) +
          "\xC3\x97 (nearest neighbor); yellow box in the frames.</p><div class=\"frames\">";
      for (const FrameCell& cell : v.cells) {
        h += "<div class=\"cell\"><b>" + EscapeMarkup(cell.title) + "</b>";
        if (!cell.note.empty()) h += "<div class=\"note\">" + EscapeMarkup(cell.note) + "</div>";
        h += Img(cell.thumb, cell.title);
        if (cell.crop) h += "<div>Crop</div>" + Img(cell.crop, cell.title + " crop", "crop");
        if (cell.flip)
          h += "<div>" + EscapeMarkup(cell.flip_title) + "</div>" + Img(cell.flip, cell.flip_title);
        if (cell.coverage)
          h += "<div>" + EscapeMarkup(kCoverageTitle) + "</div>" + Img(cell.coverage, kCoverageTitle);
        h += "</div>";
      }
      h += "</div>";
    }
  }
  return h + "\n</body></html>\n";
}

}  // namespace

ReportTexts RenderReport(const Campaign& c, const std::vector<SpeedUp>& speedups,
                         const std::vector<SpeedUpMean>& means,
                         const std::vector<SceneImages>& images, const ReportOptions& options) {
  const TextTable times = TimesTable(c), vs_hpm = QualityTable(c, false),
                  vs_truth = QualityTable(c, true), vs_scan = ScanTable(c), fps = FpsTable(c),
                  speed = SpeedUpTable(c, speedups, means);
  const std::string sentence = SpeedUpSentence(means);
  return {ReportMarkdown(c, times, vs_hpm, vs_truth, vs_scan, fps, speed, sentence, images),
          ReportHtml(c, times, vs_hpm, vs_truth, vs_scan, fps, speed, sentence, images, options)};
}

}  // namespace pb::report_internal
