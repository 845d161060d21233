// The campaign report's internal data model, shared by its pieces (not a
// public API; the contract is report.h, the rules docs/report.md):
//   report_read.cc    campaign.json / run.json / tables -> Campaign; the
//                     speed-ups; results.json and results.csv
//   report_images.cc  thumbnails, crops (the crop-location rule), data: URIs
//   report_html.cc    SVG charts, tables, report.md and report.html
//   report.cc         WriteCampaignReport: the order and the atomic writes
#pragma once

#include <array>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "base/status.h"
#include "cli/report/report.h"

namespace pb::report_internal {

// Ordered: results.json keeps the contract's key order.
using Json = nlohmann::ordered_json;
// A figure that may be unknown (null in results.json, "—" in tables).
using Opt = std::optional<double>;

// Construction-time groups (report.h), in the order of results.json; the
// titles are the tables' and charts' names for them.
constexpr int kGroupCount = 6;
constexpr std::array<const char*, kGroupCount> kGroups = {"points", "high_mesh", "low_mesh",
                                                          "uv",     "io",        "bake"};
constexpr std::array<const char*, kGroupCount> kGroupTitles = {"Normals (points)",
                                                               "High-mesh construction",
                                                               "Low-mesh construction",
                                                               "UV unwrapping",
                                                               "I/O",
                                                               "Baking"};

// The metrics.image columns of the quality tables, and their titles.
constexpr int kQualityCount = 5;
constexpr std::array<const char*, kQualityCount> kQualityColumns = {
    "psnr_db", "ssim_luma", "ssim_rgb", "ms_ssim_luma", "flip_mean"};
constexpr std::array<const char*, kQualityCount> kQualityTitles = {"PSNR dB", "SSIM luma",
                                                                   "SSIM RGB", "MS-SSIM", "FLIP"};

// Against the scan (issue 15): the covered-pixel figures of the metrics.image
// table vs_scan.json (the first kScanImageCount), the truth-free geometry
// figures of geometry.json, and the share of the frames' mesh samples that
// see a face's back (render.frames' counter back_share of the stage that
// made the named output `frames`, from run.json), with their titles.
constexpr int kScanCount = 12;
constexpr int kScanImageCount = 8;
constexpr int kScanBackFace = 11;  // back_face_fraction
constexpr std::array<const char*, kScanCount> kScanColumns = {
    "covered_psnr_db",        "covered_ssim_luma", "covered_flip_mean",
    "coverage_iou",           "hole_fraction",     "nearer_fraction",
    "farther_fraction",       "splat_hole_fraction", "invented_area_fraction", "missing_fraction",
    "boundary_edges_per_1000_faces", "back_face_fraction"};
constexpr std::array<const char*, kScanCount> kScanTitles = {
    "PSNR dB", "SSIM luma", "FLIP", "Coverage IoU", "Holes %", "In front %", "Behind %", "Disk holes %",
    "Invented area %", "Missing scan %", "Boundary edges / 1000 faces", "Back faces %"};

// One run of the campaign: its manifest entry and the figures read from its
// folder (all null for a failed run).
struct Row {
  std::string name, scene, workflow, variant, status, error, dir;
  std::string run_dir;  // campaign_dir/dir
  std::array<Opt, kGroupCount> time_s{};
  Opt total_s, peak_ram_bytes;
  Opt faces, texture_width, texture_height, texture_bytes, fps;
  std::optional<bool> fits;
  std::string device;
  std::array<Opt, kQualityCount> vs_hpm{}, vs_truth{};
  std::array<Opt, kScanCount> vs_scan{};
  // The stages' warnings from run.json (StageContext::warning), in stage
  // order: (stage id, text). Read for failed runs too.
  std::vector<std::pair<std::string, std::string>> warnings;
  bool ok() const { return status == "ok"; }
};

struct Campaign {
  std::string name, file, started;
  Opt total_wall_s;
  Json host = Json::object();
  std::vector<Row> rows;            // sorted: scene order, then workflow order
  std::vector<std::string> scenes;  // in order of first appearance
};

struct SpeedUp {
  std::string scene, workflow, variant;
  double ratio;  // other workflow's total / point transfer's total
};
struct SpeedUpMean {
  std::string workflow, variant;
  double ratio;
  int scenes;
};

// ---- report_read.cc ---------------------------------------------------------

// Reads campaign.json and every ok run's run.json, vs_hpm.json,
// vs_truth.json, vs_scan.json, geometry.json and fps.json; errors name the
// file.
Expected<Campaign> ReadCampaign(const std::string& campaign_dir);

// "Point transfer (splat)" for workflow point_transfer, variant splat.
std::string DisplayName(const std::string& workflow, const std::string& variant);
std::string DisplayName(const Row& row);

// j[key] if it is a number, else nullopt.
Opt JsonNumber(const Json& j, const char* key);

// The point-transfer row a scene's speed-ups are measured against: the one
// without variant, else the first variant; nullptr when the scene has none.
const Row* PointTransferRow(const Campaign& c, const std::string& scene);
// Per scene, every other run's total / point transfer's total.
std::vector<SpeedUp> SpeedUps(const Campaign& c);
// Per workflow and variant, the geometric mean of its ratios over scenes.
std::vector<SpeedUpMean> GeometricMeans(const std::vector<SpeedUp>& speedups);

Json ResultsJson(const Campaign& c, const std::vector<SpeedUp>& speedups,
                 const std::vector<SpeedUpMean>& means);
std::string ResultsCsv(const Campaign& c);

// ---- report_images.cc -------------------------------------------------------

// A square crop window in full-size frame pixels.
struct CropWindow {
  int x = 0, y = 0, size = 0;
};

// An image of the report: written to images/<file> (for report.md) and kept
// as a data: URI (for report.html).
struct ReportImage {
  std::string file;  // relative to the report folder
  std::string data_uri;
  int width = 0, height = 0;
};

// The side-by-side frames: per scene, per view, one cell per column (ground
// truth, then each run).
struct FrameCell {
  std::string title;  // column title
  std::string note;   // why there is no image ("run failed", "no frames")
  std::optional<ReportImage> thumb, crop, flip;
  std::string flip_title;
  std::optional<ReportImage> coverage;  // the coverage map against the scan (metrics.image)
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

// Reads the scene's frames (first options.max_viewpoints views) and writes
// their thumbnails, crops and FLIP maps into <report_dir>/images/.
Expected<SceneImages> BuildSceneImages(const Campaign& c, const std::string& scene,
                                       const std::string& report_dir, const ReportOptions& options);

// ---- report_html.cc ---------------------------------------------------------

struct ReportTexts {
  std::string markdown;  // report.md
  std::string html;      // report.html
};
ReportTexts RenderReport(const Campaign& c, const std::vector<SpeedUp>& speedups,
                         const std::vector<SpeedUpMean>& means,
                         const std::vector<SceneImages>& images, const ReportOptions& options);

// Writes <report_dir>/viewer/ (report_viewer.cc): the 3-D viewer page, its
// models.json and three.js. Status::NotFound naming what to install when
// three.js (tools/node_modules) is missing.
Status WriteViewer(const Campaign& c, const std::string& report_dir);

}  // namespace pb::report_internal
