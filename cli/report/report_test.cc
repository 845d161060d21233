// Campaign report on a tiny campaign folder written by the test: one scene,
// HPM + LPM (failed) + point transfer, with run records, tables and frames.
#include "cli/report/report.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "stages/geometry/io/frames.h"
#include "stages/geometry/metrics/image_metrics.h"
#include "stages/geometry/core/table.h"
#include "stages/geometry/testing/test_data.h"

namespace pb {
namespace {

using Json = nlohmann::json;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr int kW = 64, kH = 48;

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A smooth RGB gradient; `square` paints a 16×16 white block at (sx, sy).
Image TestFrame(int offset, bool square = false, int sx = 40, int sy = 8) {
  Image image = Image::Make(kW, kH, 3, Image::PixelType::kU8);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      image.at_u8(x, y, 0) = uint8_t(x * 3 + offset);
      image.at_u8(x, y, 1) = uint8_t(y * 4);
      image.at_u8(x, y, 2) = uint8_t(100 + offset);
      if (square && x >= sx && x < sx + 16 && y >= sy && y < sy + 16)
        for (int c = 0; c < 3; ++c) image.at_u8(x, y, c) = 255;
    }
  return image;
}

Table MetricsTable(const TableValue& psnr) {
  Table t;
  t.columns = {"frame", "psnr_db", "ssim_luma", "ssim_rgb", "ms_ssim_luma", "flip_mean"};
  t.rows.push_back({std::string("front"), psnr, 0.9, 0.91, 0.95, 0.05});
  t.rows.push_back({std::string("mean"), psnr, 0.9, 0.91, 0.95, 0.05});
  return t;
}

Table FpsTable(int64_t triangles, int64_t texture_px, double fps) {
  Table t;
  t.columns = {"device",
               "triangles",
               "texture_width",
               "texture_height",
               "texture_bytes",
               "texture_budget_bytes",
               "fits_texture_budget",
               "triangles_per_s",
               "refresh_hz",
               "fps"};
  t.rows.push_back({std::string("quest2"), triangles, texture_px, texture_px,
                    texture_px * texture_px * 4, int64_t(1) << 30, true, 1e9, 72.0, fps});
  return t;
}

Json Stage(const std::string& id, const std::string& group, double wall_s, double io_s,
           double peak) {
  Json phases = Json::array({{{"name", "compute"}, {"start_s", 0.0}, {"dur_s", wall_s - io_s}}});
  if (io_s > 0) phases.push_back({{"name", "io"}, {"start_s", wall_s - io_s}, {"dur_s", io_s}});
  return {{"stage", id},      {"type", "t"},
          {"status", "ran"},  {"group", group},
          {"wall_s", wall_s}, {"peak_rss_bytes", peak},
          {"phases", phases}, {"counters", Json::object()}};
}

class ReportTest : public testing::TempDirTest {
 protected:
  std::string Campaign() const { return Path("campaign"); }
  std::string RunDir(const std::string& workflow) const {
    return Path("campaign/runs/room/" + workflow);
  }

  void WriteFrameSet(const std::string& dir, const Image& image) {
    std::filesystem::create_directories(dir);
    FrameSet set;
    set.width = kW;
    set.height = kH;
    Frame frame;
    frame.entry.name = "front";
    frame.entry.file = "front.png";
    frame.entry.viewpoint = FrameViewpoint{{1.0, 2.0, 1.6}, {3.0, 2.0, 1.5}, std::nullopt, 70.0};
    frame.image = image;
    set.frames.push_back(std::move(frame));
    ASSERT_TRUE(WriteFrames(dir, set).ok());
  }
  void WriteJson(const std::string& path, const Json& j) {
    std::filesystem::create_directories(std::filesystem::path(path).parent_path());
    std::ofstream(path) << j.dump(2);
  }

  // workflows: name -> status; writes the campaign folder.
  void WriteCampaign(bool lpm_ok = false, bool with_pt = true) {
    Json runs = Json::array();
    auto run = [&](const std::string& workflow, const std::string& status) {
      Json r = {{"name", "room/" + workflow},
                {"scene", "room"},
                {"scene_file", "/x/room.yaml"},
                {"workflow", workflow},
                {"workflow_file", "/x/" + workflow + ".yaml"},
                {"variant", ""},
                {"sets", Json::array()},
                {"dir", "runs/room/" + workflow},
                {"status", status}};
      if (status == "failed") r["error"] = "stage bake failed: out of memory, exit 137";
      runs.push_back(r);
    };
    // Manifest order is not display order: the report sorts.
    if (with_pt) run("point_transfer", "ok");
    run("hpm", "ok");
    run("lpm", lpm_ok ? "ok" : "failed");
    WriteJson(Path("campaign/campaign.json"),
              {{"format", "pointbake-campaign"},
               {"version", 1},
               {"name", "tiny"},
               {"file", "/x/tiny.yaml"},
               {"started", "2026-11-21T10:00:00Z"},
               {"total_wall_s", 42.0},
               {"host", {{"cores", 2}, {"memory_bytes", 25769803776.0}, {"cpu", "Test CPU"}}},
               {"runs", runs}});

    // HPM: high mesh 10 s of which 2 s io; bake a cache hit (4 s, 1 s io);
    // export 1 s. Scan and render are not construction time.
    Json bake_hit = {{"stage", "bake"}, {"type", "bake.from_mesh"},
                     {"status", "hit"}, {"group", "bake"},
                     {"wall_s", 0.01},  {"cached_run", Stage("bake", "bake", 4, 1, 3e9)}};
    WriteJson(
        RunDir("hpm") + "/run.json",
        {{"format", "pointbake-run 1"},
         {"workflow", "hpm"},
         {"stages",
          {Stage("scan", "input", 5, 0, 1e8), Stage("poisson", "high_mesh", 10, 2, 2e9), bake_hit,
           Stage("export", "io", 1, 0, 1e8), Stage("render", "evaluation", 100, 0, 9e9)}}});
    WriteFrameSet(RunDir("hpm") + "/frames", TestFrame(2));
    WriteFrameSet(RunDir("hpm") + "/truth_frames", TestFrame(0));
    WriteFrameSet(RunDir("hpm") + "/flip_truth", TestFrame(50));
    ASSERT_TRUE(WriteTable(RunDir("hpm") + "/vs_truth.json", MetricsTable(35.0)).ok());
    ASSERT_TRUE(WriteTable(RunDir("hpm") + "/fps.json", FpsTable(4000000, 0, 20.5)).ok());

    if (with_pt) {
      // Point transfer: normals 2 s (0.5 io), low mesh 1, uv 0.5, bake 1.5
      // (0.25 io), export 0.5; the HPM reference chain is not its time.
      WriteJson(RunDir("point_transfer") + "/run.json",
                {{"format", "pointbake-run 1"},
                 {"workflow", "point_transfer"},
                 {"stages",
                  {Stage("scan", "input", 5, 0, 1e8), Stage("normals", "points", 2, 0.5, 1.5e9),
                   Stage("decimate", "low_mesh", 1, 0, 5e8), Stage("unwrap", "uv", 0.5, 0, 4e8),
                   Stage("bake", "bake", 1.5, 0.25, 1.2e9), Stage("export", "io", 0.5, 0, 1e8),
                   Stage("hpm_poisson", "reference", 50, 0, 8e9),
                   Stage("fps", "evaluation", 1, 0, 1e8)}}});
      WriteFrameSet(RunDir("point_transfer") + "/frames", TestFrame(0, true));
      WriteFrameSet(RunDir("point_transfer") + "/flip_truth", TestFrame(80));
      WriteFrameSet(RunDir("point_transfer") + "/flip_hpm", TestFrame(90));
      ASSERT_TRUE(WriteTable(RunDir("point_transfer") + "/vs_hpm.json", MetricsTable(30.0)).ok());
      ASSERT_TRUE(
          WriteTable(RunDir("point_transfer") + "/vs_truth.json", MetricsTable(TableValue{})).ok());
      ASSERT_TRUE(
          WriteTable(RunDir("point_transfer") + "/fps.json", FpsTable(240000, 2048, 72.0)).ok());
    }
    if (lpm_ok) {
      WriteJson(RunDir("lpm") + "/run.json",
                {{"format", "pointbake-run 1"},
                 {"workflow", "lpm"},
                 {"stages",
                  {Stage("decimate", "low_mesh", 1, 0, 5e8), Stage("bake", "bake", 1, 0, 5e8)}}});
      WriteFrameSet(RunDir("lpm") + "/frames", TestFrame(0));
    }
  }

  Json Results() { return Json::parse(ReadText(Path("report/results.json"))); }
};

TEST_F(ReportTest, GroupsTimesAndPeakRamAsTheContractSays) {
  WriteCampaign();
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("report")).ok());
  const Json r = Results();
  EXPECT_EQ(r["format"], "pointbake-report");
  EXPECT_EQ(r["campaign"]["name"], "tiny");
  ASSERT_EQ(r["rows"].size(), 3u);
  const Json& hpm = r["rows"][0];
  const Json& lpm = r["rows"][1];
  const Json& pt = r["rows"][2];
  EXPECT_EQ(hpm["workflow"], "hpm");
  EXPECT_EQ(lpm["workflow"], "lpm");
  EXPECT_EQ(pt["workflow"], "point_transfer");
  EXPECT_EQ(pt["display_name"], "Point transfer");

  EXPECT_NEAR(hpm["time_s"]["high_mesh"].get<double>(), 8.0, 1e-9);
  EXPECT_NEAR(hpm["time_s"]["bake"].get<double>(), 3.0,
              1e-9);                                          // from cached_run, not the hit's 0.01
  EXPECT_NEAR(hpm["time_s"]["io"].get<double>(), 4.0, 1e-9);  // 2 + 1 + 1
  EXPECT_TRUE(hpm["time_s"]["points"].is_null());
  EXPECT_TRUE(hpm["time_s"]["uv"].is_null());
  EXPECT_NEAR(hpm["time_s"]["total"].get<double>(), 15.0, 1e-9);
  EXPECT_EQ(hpm["peak_ram_bytes"].get<int64_t>(), 3000000000);  // render's 9e9 is evaluation

  EXPECT_NEAR(pt["time_s"]["points"].get<double>(), 1.5, 1e-9);
  EXPECT_NEAR(pt["time_s"]["low_mesh"].get<double>(), 1.0, 1e-9);
  EXPECT_NEAR(pt["time_s"]["uv"].get<double>(), 0.5, 1e-9);
  EXPECT_NEAR(pt["time_s"]["bake"].get<double>(), 1.25, 1e-9);
  EXPECT_NEAR(pt["time_s"]["io"].get<double>(), 1.25, 1e-9);
  EXPECT_NEAR(pt["time_s"]["total"].get<double>(), 5.5, 1e-9);
  EXPECT_EQ(pt["peak_ram_bytes"].get<int64_t>(), 1500000000);  // reference chain's 8e9 left out
  EXPECT_EQ(pt["faces"].get<int64_t>(), 240000);
  EXPECT_EQ(pt["texture_size"]["width_px"].get<int64_t>(), 2048);
  EXPECT_EQ(pt["fits"], true);
  EXPECT_NEAR(pt["fps"].get<double>(), 72.0, 1e-9);
  EXPECT_NEAR(pt["vs_hpm"]["psnr_db"].get<double>(), 30.0, 1e-9);
  EXPECT_NEAR(pt["vs_hpm"]["ms_ssim_luma"].get<double>(), 0.95, 1e-9);
  EXPECT_TRUE(pt["vs_truth"]["psnr_db"].is_null());  // infinite PSNR is null in the table
  EXPECT_NEAR(pt["vs_truth"]["flip_mean"].get<double>(), 0.05, 1e-9);
  EXPECT_TRUE(hpm["vs_hpm"]["psnr_db"].is_null());  // HPM has no comparison with itself

  EXPECT_EQ(lpm["status"], "failed");
  EXPECT_THAT(lpm["error"].get<std::string>(), HasSubstr("out of memory"));
  EXPECT_TRUE(lpm["time_s"]["total"].is_null());
  EXPECT_TRUE(lpm["peak_ram_bytes"].is_null());
  EXPECT_TRUE(lpm["fps"].is_null());

  // Speed-up of point transfer over HPM: 15 / 5.5; the failed LPM has none.
  ASSERT_EQ(r["speedups"]["per_scene"].size(), 1u);
  EXPECT_EQ(r["speedups"]["per_scene"][0]["workflow"], "hpm");
  EXPECT_NEAR(r["speedups"]["per_scene"][0]["ratio"].get<double>(), 15.0 / 5.5, 1e-9);
  ASSERT_EQ(r["speedups"]["geometric_mean"].size(), 1u);
  EXPECT_NEAR(r["speedups"]["geometric_mean"][0]["ratio"].get<double>(), 15.0 / 5.5, 1e-9);
}

std::vector<std::string> SplitCsvLine(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char ch = line[i];
    if (quoted && ch == '"' && i + 1 < line.size() && line[i + 1] == '"')
      fields.back() += '"', ++i;
    else if (ch == '"')
      quoted = !quoted;
    else if (ch == ',' && !quoted)
      fields.emplace_back();
    else
      fields.back() += ch;
  }
  return fields;
}

// The stages' warnings (run.json) reach results.json, results.csv (a count),
// report.md and report.html, for failed runs too.
TEST_F(ReportTest, WarningsOfEveryRunAreListed) {
  WriteCampaign();
  Json pt = Json::parse(ReadText(RunDir("point_transfer") + "/run.json"));
  pt["stages"][1]["warnings"] = {"depth 9 makes 1.2 mm cells, finer than <spacing>"};
  WriteJson(RunDir("point_transfer") + "/run.json", pt);
  // The failed LPM run still wrote its record.
  Json lpm_bake = Stage("bake", "bake", 1, 0, 5e8);
  lpm_bake["status"] = "failed";
  lpm_bake["warnings"] = {"first", "second"};
  WriteJson(RunDir("lpm") + "/run.json",
            {{"format", "pointbake-run 1"}, {"workflow", "lpm"}, {"stages", {lpm_bake}}});
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("report")).ok());
  const Json r = Results();
  EXPECT_EQ(r["rows"][0]["warnings"], Json::array());  // hpm
  EXPECT_EQ(r["rows"][1]["warnings"], Json({{{"stage", "bake"}, {"warning", "first"}},
                                            {{"stage", "bake"}, {"warning", "second"}}}));
  ASSERT_EQ(r["rows"][2]["warnings"].size(), 1u);
  EXPECT_EQ(r["rows"][2]["warnings"][0]["stage"], "normals");

  const std::string csv = ReadText(Path("report/results.csv"));
  const std::string header = csv.substr(0, csv.find('\n'));
  EXPECT_EQ(header.substr(header.rfind(',') + 1), "warnings");
  EXPECT_THAT(csv, HasSubstr(",2\n"));  // lpm's count ends its row

  // A failed run that did not load wrote no record: no warnings, and the
  // report is still written. A finished run without one is an error.
  std::filesystem::rename(RunDir("lpm") + "/run.json", Path("lpm-run.json"));
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("report")).ok());
  EXPECT_EQ(Results()["rows"][1]["warnings"], Json::array());
  std::filesystem::rename(Path("lpm-run.json"), RunDir("lpm") + "/run.json");
  std::filesystem::rename(RunDir("hpm") + "/run.json", Path("hpm-run.json"));
  const Status missing = WriteCampaignReport(Campaign(), Path("report"));
  EXPECT_FALSE(missing.ok());
  EXPECT_THAT(missing.message(), HasSubstr("runs/room/hpm/run.json"));
  std::filesystem::rename(Path("hpm-run.json"), RunDir("hpm") + "/run.json");
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("report")).ok());

  const std::string md = ReadText(Path("report/report.md"));
  EXPECT_THAT(md, HasSubstr("## Warnings"));
  EXPECT_THAT(md, HasSubstr("- LPM on room, stage `bake`: first"));
  EXPECT_THAT(md, HasSubstr("- Point transfer on room, stage `normals`: depth 9 makes"));
  const std::string html = ReadText(Path("report/report.html"));
  EXPECT_THAT(
      html,
      HasSubstr("<code>normals</code>: depth 9 makes 1.2 mm cells, finer than &lt;spacing&gt;"));

  // Without warnings the section says so.
  WriteCampaign(true);
  WriteJson(RunDir("point_transfer") + "/run.json",
            Json::parse(ReadText(RunDir("hpm") + "/run.json")));
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("report2")).ok());
  EXPECT_THAT(ReadText(Path("report2/report.md")),
              HasSubstr("No stage of any run reported a warning."));
}

TEST_F(ReportTest, CsvHasOneRowPerRunWithEmptyFieldsForUnknowns) {
  WriteCampaign();
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("report")).ok());
  std::istringstream csv(ReadText(Path("report/results.csv")));
  std::vector<std::vector<std::string>> lines;
  for (std::string line; std::getline(csv, line);) lines.push_back(SplitCsvLine(line));
  ASSERT_EQ(lines.size(), 4u);
  auto column = [&](const std::string& name) {
    auto it = std::find(lines[0].begin(), lines[0].end(), name);
    EXPECT_NE(it, lines[0].end()) << name;
    return size_t(it - lines[0].begin());
  };
  for (const auto& l : lines) ASSERT_EQ(l.size(), lines[0].size());
  EXPECT_EQ(lines[3][column("workflow")], "point_transfer");
  EXPECT_EQ(std::stod(lines[3][column("time_total_s")]), 5.5);
  EXPECT_EQ(lines[3][column("vs_truth_psnr_db")], "");
  EXPECT_EQ(lines[3][column("fits_budget")], "true");
  EXPECT_EQ(lines[2][column("status")], "failed");
  EXPECT_EQ(lines[2][column("time_total_s")], "");
  EXPECT_EQ(lines[2][column("error")],
            "stage bake failed: out of memory, exit 137");  // quoted comma
}

TEST_F(ReportTest, HtmlIsSelfContainedWithChartsAndFrames) {
  WriteCampaign();
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("report")).ok());
  const std::string html = ReadText(Path("report/report.html"));
  EXPECT_THAT(html, Not(HasSubstr("src=\"http")));
  // The only links are to the 3-D viewer written beside it.
  size_t links = 0;
  for (size_t at = html.find("href=\""); at != std::string::npos; at = html.find("href=\"", at + 1), ++links) {
    EXPECT_EQ(html.compare(at + 6, 17, "viewer/index.html"), 0) << html.substr(at, 60);
  }
  EXPECT_GE(links, 3u);  // all models, the scene, each run that is ok
  EXPECT_THAT(html, HasSubstr("href=\"viewer/index.html?run=room%2Fpoint_transfer\""));
  EXPECT_THAT(html, HasSubstr("pointbake serve"));
  EXPECT_THAT(html, Not(HasSubstr("<script")));
  EXPECT_THAT(html, Not(HasSubstr("url(")));
  EXPECT_THAT(html, Not(HasSubstr("HDR-VDP")));
  size_t images = 0, data_images = 0;
  for (size_t at = html.find("<img "); at != std::string::npos; at = html.find("<img ", at + 1))
    ++images;
  for (size_t at = html.find("src=\"data:image/png;base64,"); at != std::string::npos;
       at = html.find("src=\"data:image/png;base64,", at + 1))
    ++data_images;
  // Truth (frame + crop), HPM and point transfer (frame + crop + FLIP each).
  EXPECT_EQ(images, 8u);
  EXPECT_EQ(data_images, images);
  size_t svgs = 0;
  for (size_t at = html.find("<svg"); at != std::string::npos; at = html.find("<svg", at + 1))
    ++svgs;
  EXPECT_EQ(svgs, 2u);  // time bars and peak-RAM bars of the one scene
  EXPECT_THAT(html, HasSubstr("Point transfer"));
  EXPECT_THAT(html, HasSubstr("Ground truth"));
  EXPECT_THAT(html, HasSubstr("run failed"));
  EXPECT_THAT(html, HasSubstr("Test CPU"));
  EXPECT_THAT(html, HasSubstr("2026-11-21T10:00:00Z"));
  EXPECT_THAT(html, HasSubstr("exclude producing the scan"));
  EXPECT_THAT(html, HasSubstr("2.73\xC3\x97 over HPM"));
  // report.md links the same images, written beside it.
  const std::string md = ReadText(Path("report/report.md"));
  EXPECT_THAT(md, HasSubstr("](images/room__room_point_transfer__front_frame.png)"));
  EXPECT_TRUE(
      std::filesystem::exists(Path("report/images/room__room_point_transfer__front_crop.png")));
}

TEST_F(ReportTest, AgainstTheScanTableAndSplatFrames) {
  WriteCampaign();
  // Point transfer measured against the scan: metrics.image v2's covered
  // columns and metrics.geometry's scan rows; the scan's splat frames.
  Table image;
  image.columns = {"frame", "psnr_db", "covered_psnr_db", "covered_ssim_luma", "covered_flip_mean",
                   "coverage_iou", "hole_fraction", "nearer_fraction"};
  image.rows.push_back({std::string("front"), 20.0, 31.5, 0.8, 0.12, 0.9, 0.0125, 0.0775});
  image.rows.push_back({std::string("mean"), 20.0, 31.5, 0.8, 0.12, 0.9, 0.0125, 0.0775});
  ASSERT_TRUE(WriteTable(RunDir("point_transfer") + "/vs_scan.json", image).ok());
  Table geometry;
  geometry.columns = {"direction", "beyond_fraction", "boundary_edges_per_1000_faces"};
  geometry.rows.push_back({std::string("mesh_to_scan"), 0.25, 3.5});
  geometry.rows.push_back({std::string("scan_to_mesh"), 0.0625, 3.5});
  ASSERT_TRUE(WriteTable(RunDir("point_transfer") + "/geometry.json", geometry).ok());
  WriteFrameSet(RunDir("point_transfer") + "/scan_frames", TestFrame(7));
  // Its coverage map: the model's gray with one hole pixel at the outline.
  Image coverage = Image::Make(kW, kH, 3, Image::PixelType::kU8);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int c = 0; c < 3; ++c) coverage.at_u8(x, y, c) = uint8_t(x < kW / 2 ? 150 : 0);
  for (int c = 0; c < 3; ++c) coverage.at_u8(kW / 2, 13, c) = kCoverageMapHoleOutline[size_t(c)];
  // Rows 20-23: one model-only pixel in every 4 x 4 box of the model (the
  // gaps between sparse splats); rows 28-31, x 0-7: model only throughout.
  auto paint = [&](int x, int y, const std::array<uint8_t, 3>& rgb) {
    for (int c = 0; c < 3; ++c) coverage.at_u8(x, y, c) = rgb[size_t(c)];
  };
  for (int x = 1; x < kW / 2; x += 4) paint(x, 21, kCoverageMapTestOnly);
  for (int y = 28; y < 32; ++y)
    for (int x = 0; x < 8; ++x) paint(x, y, kCoverageMapTestOnly);
  WriteFrameSet(RunDir("point_transfer") + "/coverage_scan", coverage);
  ReportOptions small;
  small.thumbnail_px = kW / 4;  // every thumbnail pixel stands for 4 x 4
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("report_small"), small).ok());
  Expected<Image> thumb = ReadPng(Path("report_small/images/room__room_point_transfer__front_coverage.png"));
  ASSERT_TRUE(thumb.ok()) << thumb.status().message();
  EXPECT_EQ(thumb->width, kW / 4);
  // The one red pixel stays red where averaging would have made it gray.
  EXPECT_EQ(thumb->at_u8(kW / 8, 13 / 4, 0), 255);
  EXPECT_EQ(thumb->at_u8(kW / 8, 13 / 4, 1), 0);
  EXPECT_EQ(thumb->at_u8(kW / 8 - 1, 13 / 4, 0), 150);  // the model beside it
  EXPECT_EQ(thumb->at_u8(kW / 8 + 1, 13 / 4, 0), 0);    // black beyond
  // Boxes that are mostly the model show it, one blue pixel or not; a box
  // that is all model only shows blue.
  for (int x = 0; x < kW / 8; ++x) EXPECT_EQ(thumb->at_u8(x, 21 / 4, 2), 150) << x;
  for (int x = 0; x < 2; ++x) EXPECT_EQ(thumb->at_u8(x, 28 / 4, 2), kCoverageMapTestOnly[2]) << x;
  EXPECT_EQ(thumb->at_u8(2, 28 / 4, 2), 150);
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("report")).ok());

  const Json results = Results();
  const Json& pt = results["rows"][2];  // hpm, lpm (failed), point transfer
  ASSERT_EQ(pt["workflow"], "point_transfer");
  EXPECT_EQ(pt["vs_scan"]["covered_psnr_db"].get<double>(), 31.5);
  EXPECT_EQ(pt["vs_scan"]["hole_fraction"].get<double>(), 0.0125);
  EXPECT_EQ(pt["scan_geometry"]["invented_area_fraction"].get<double>(), 0.25);
  EXPECT_EQ(pt["scan_geometry"]["missing_fraction"].get<double>(), 0.0625);
  EXPECT_EQ(pt["scan_geometry"]["boundary_edges_per_1000_faces"].get<double>(), 3.5);
  EXPECT_TRUE(results["rows"][0]["vs_scan"]["covered_psnr_db"].is_null());  // HPM: no file

  const std::string html = ReadText(Path("report/report.html"));
  EXPECT_THAT(html, HasSubstr("Against the scan"));
  EXPECT_THAT(html, HasSubstr("<td>31.50</td>"));
  EXPECT_THAT(html, HasSubstr("<td>1.25</td>"));   // holes, %
  EXPECT_THAT(html, HasSubstr("<td>25.00</td>"));  // invented area, %
  EXPECT_THAT(html, HasSubstr("<td>7.75</td>"));   // surface in front, %
  EXPECT_EQ(pt["vs_scan"]["nearer_fraction"].get<double>(), 0.0775);
  EXPECT_TRUE(pt["vs_scan"]["farther_fraction"].is_null());
  EXPECT_THAT(html, HasSubstr("Scan (splats)"));
  // Truth, scan (frame + crop each), HPM and point transfer (frame + crop +
  // FLIP each).
  size_t images = 0;
  for (size_t at = html.find("<img "); at != std::string::npos; at = html.find("<img ", at + 1)) ++images;
  EXPECT_EQ(images, 11u);  // and point transfer's coverage map
  EXPECT_THAT(html, HasSubstr("Coverage vs scan"));
  EXPECT_THAT(html, HasSubstr("red, a hole pixel at the model"));
  EXPECT_THAT(ReadText(Path("report/report.md")), HasSubstr("room__room_point_transfer__front_coverage.png"));
  EXPECT_TRUE(std::filesystem::exists(Path("report/images/room__scan__front_frame.png")));
  const std::string csv = ReadText(Path("report/results.csv"));
  EXPECT_THAT(csv, HasSubstr("vs_scan_covered_psnr_db"));
  EXPECT_THAT(csv, HasSubstr("scan_invented_area_fraction"));
}

// Back faces: render.frames' counter back_share of the stage run.json's
// "outputs" name for `frames` (its cached_run's for a hit); unknown without
// "outputs" (records before them) or without the counter.
TEST_F(ReportTest, BackFacesComeFromTheStageThatMadeTheFrames) {
  WriteCampaign();
  Json hit_render = {{"stage", "render"}, {"type", "render.frames"}, {"status", "hit"}, {"group", "evaluation"},
                     {"wall_s", 0.01},     {"cached_run", Stage("render", "evaluation", 3, 0, 1e8)}};
  hit_render["cached_run"]["counters"] = {{"back_share", 0.03125}};
  Json truth_render = Stage("truth_render", "evaluation", 3, 0, 1e8);
  truth_render["counters"] = {{"back_share", 0.5}};  // another render.frames: not the workflow's frames
  WriteJson(RunDir("point_transfer") + "/run.json",
            {{"format", "pointbake-run 1"},
             {"workflow", "point_transfer"},
             {"outputs", {{"frames", "render.frames"}, {"truth_frames", "truth_render.frames"}}},
             {"stages", {Stage("decimate", "low_mesh", 1, 0, 5e8), truth_render, hit_render}}});
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("report")).ok());
  const Json results = Results();
  const Json& pt = results["rows"][2];
  ASSERT_EQ(pt["workflow"], "point_transfer");
  EXPECT_EQ(pt["scan_geometry"]["back_face_fraction"].get<double>(), 0.03125);
  EXPECT_TRUE(results["rows"][0]["scan_geometry"]["back_face_fraction"].is_null());  // HPM: no "outputs"
  EXPECT_THAT(ReadText(Path("report/report.html")), HasSubstr("<td>3.12</td>"));
  EXPECT_THAT(ReadText(Path("report/report.md")), HasSubstr("Back faces %"));
  const std::string csv = ReadText(Path("report/results.csv"));
  EXPECT_THAT(csv, HasSubstr("scan_back_face_fraction"));
  EXPECT_THAT(csv, HasSubstr(",0.03125,"));
}

TEST_F(ReportTest, CropIsWhereTransferAndLpmDifferMost) {
  WriteCampaign(/*lpm_ok=*/true);
  ReportOptions options;
  options.crop_px = 16;
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("report"), options).ok());
  const std::string html = ReadText(Path("report/report.html"));
  EXPECT_THAT(html, HasSubstr("Crop: 16\xC3\x97"
                              "16 px at (40, 8)"));
  // The crop is enlarged nearest-neighbor to about thumbnail_px: 16 * 20.
  Expected<Image> crop = ReadPng(Path("report/images/room__room_point_transfer__front_crop.png"));
  ASSERT_TRUE(crop.ok());
  EXPECT_EQ(crop->width, 320);
  EXPECT_EQ(crop->at_u8(5, 5, 0), 255);  // inside the white square
}

TEST_F(ReportTest, WithoutLpmTheCropIsTheFrameCentreAndThumbnailsAreBoxFiltered) {
  WriteCampaign();
  ReportOptions options;
  options.crop_px = 16;
  options.thumbnail_px = 32;
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("report"), options).ok());
  EXPECT_THAT(ReadText(Path("report/report.html")), HasSubstr("16 px at (24, 16)"));
  Expected<Image> thumb = ReadPng(Path("report/images/room__room_hpm__front_frame.png"));
  ASSERT_TRUE(thumb.ok());
  EXPECT_EQ(thumb->width, 32);
  EXPECT_EQ(thumb->height, 24);
  // Pixel (0, 0) averages source 2×2 block: red 2,5,2,5 -> 3.5 -> 4 (rounded).
  EXPECT_EQ(thumb->at_u8(0, 0, 0), 4);
  EXPECT_EQ(thumb->at_u8(0, 0, 1), 2);  // green 0,0,4,4
}

TEST_F(ReportTest, OneSceneOneWorkflowWorksAndOutputIsDeterministic) {
  WriteCampaign(false, /*with_pt=*/false);
  // Keep only HPM in the manifest.
  Json manifest = Json::parse(ReadText(Path("campaign/campaign.json")));
  manifest["runs"] = Json::array({manifest["runs"][0]});
  std::ofstream(Path("campaign/campaign.json")) << manifest.dump();
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("deep/new/report")).ok());
  const std::string first = ReadText(Path("deep/new/report/report.html"));
  EXPECT_THAT(first, HasSubstr("No speed-ups"));
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("deep/new/report")).ok());
  EXPECT_EQ(ReadText(Path("deep/new/report/report.html")), first);
  EXPECT_EQ(Json::parse(ReadText(Path("deep/new/report/results.json")))["rows"].size(), 1u);
}

// The report tools/check_report_html.sh opens in Chromium (ctest
// report_html_chromium): written to $PB_REPORT_EXAMPLE_DIR/report when set.
TEST_F(ReportTest, ExampleReportForTheBrowserCheck) {
  WriteCampaign(/*lpm_ok=*/true);
  const char* keep = std::getenv("PB_REPORT_EXAMPLE_DIR");
  const std::string report = (keep && *keep ? std::string(keep) : Path("example")) + "/report";
  ASSERT_TRUE(WriteCampaignReport(Campaign(), report).ok());
  const std::string html = ReadText(report + "/report.html");
  EXPECT_THAT(html, HasSubstr("<svg"));
  EXPECT_THAT(html, Not(HasSubstr("run failed")));
}

TEST_F(ReportTest, ViewerListsTheModelsWithViewpointsFiguresAndThreeJs) {
  WriteCampaign(/*lpm_ok=*/true);
  std::ofstream(RunDir("hpm") + "/model.glb") << "glb";
  std::ofstream(RunDir("point_transfer") + "/model.glb") << "glb";
  std::ofstream(RunDir("point_transfer") + "/model_ktx2.glb") << "glb";
  ASSERT_TRUE(WriteCampaignReport(Campaign(), Path("campaign/report")).ok());
  const Json index = Json::parse(ReadText(Path("campaign/report/viewer/models.json")));
  EXPECT_EQ(index["format"], "pointbake-viewer");
  ASSERT_EQ(index["scenes"].size(), 1u);
  const Json& scene = index["scenes"][0];
  EXPECT_EQ(scene["name"], "room");
  ASSERT_EQ(scene["viewpoints"].size(), 1u);
  EXPECT_EQ(scene["viewpoints"][0]["name"], "front");
  EXPECT_EQ(scene["viewpoints"][0]["eye"], Json::parse("[1.0, 2.0, 1.6]"));
  EXPECT_EQ(scene["viewpoints"][0]["fov_deg"], 70.0);
  EXPECT_EQ(scene["frame_size"], Json::parse("[" + std::to_string(kW) + "," + std::to_string(kH) + "]"));
  ASSERT_EQ(scene["models"].size(), 2u);  // the LPM run has no model.glb
  const Json& hpm = scene["models"][0];
  const Json& pt = scene["models"][1];
  EXPECT_EQ(hpm["run"], "room/hpm");
  EXPECT_EQ(hpm["glb"], "../../runs/room/hpm/model.glb");
  EXPECT_TRUE(hpm["glb_ktx2"].is_null());
  EXPECT_EQ(pt["glb_ktx2"], "../../runs/room/point_transfer/model_ktx2.glb");
  EXPECT_EQ(pt["frames"], "../../runs/room/point_transfer/frames");
  EXPECT_EQ(pt["title"], "Point transfer");
  EXPECT_EQ(pt["figures"]["faces"], 240000);
  EXPECT_EQ(pt["figures"]["fps"], 72.0);
  EXPECT_EQ(pt["figures"]["flip_hpm"], 0.05);
  for (const char* file : {"index.html", "viewer.js", "lib/three.module.js",
                           "lib/addons/loaders/GLTFLoader.js", "lib/addons/libs/basis/basis_transcoder.wasm"}) {
    EXPECT_TRUE(std::filesystem::exists(Path("campaign/report/viewer/") + file)) << file;
  }
  // Every module the page imports is there (relative imports of the addons).
  EXPECT_THAT(ReadText(Path("campaign/report/viewer/index.html")), HasSubstr("./lib/three.module.js"));

  // Without three.js the report is written and the error says what to install.
  setenv("POINTBAKE_TOOLS_DIR", Path("no_tools").c_str(), 1);
  const Status missing = WriteCampaignReport(Campaign(), Path("other"));
  unsetenv("POINTBAKE_TOOLS_DIR");
  EXPECT_EQ(missing.code(), Status::Code::kNotFound);
  EXPECT_THAT(missing.message(), HasSubstr("npm ci --prefix tools"));
  EXPECT_TRUE(std::filesystem::exists(Path("other/report.html")));
}

TEST_F(ReportTest, ErrorsNameTheFile) {
  WriteCampaign();
  std::ofstream(RunDir("point_transfer") + "/run.json") << "{\"stages\": [";
  Status s = WriteCampaignReport(Campaign(), Path("report"));
  EXPECT_FALSE(s.ok());
  EXPECT_THAT(s.message(), HasSubstr("runs/room/point_transfer/run.json"));

  WriteCampaign();
  Table no_mean = MetricsTable(1.0);
  no_mean.rows.pop_back();
  ASSERT_TRUE(WriteTable(RunDir("point_transfer") + "/vs_hpm.json", no_mean).ok());
  s = WriteCampaignReport(Campaign(), Path("report"));
  EXPECT_THAT(s.message(), HasSubstr("point_transfer/vs_hpm.json"));

  std::ofstream(Path("campaign/campaign.json")) << "{\"format\": \"something-else\"}";
  s = WriteCampaignReport(Campaign(), Path("report"));
  EXPECT_EQ(s.code(), Status::Code::kCorrupt);
  EXPECT_THAT(s.message(), HasSubstr("campaign/campaign.json"));

  s = WriteCampaignReport(Path("nowhere"), Path("report"));
  EXPECT_FALSE(s.ok());
  EXPECT_THAT(s.message(), HasSubstr("nowhere/campaign.json"));
}

}  // namespace
}  // namespace pb
