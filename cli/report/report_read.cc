// Campaign report, reading: campaign.json and the run folders it names into
// a Campaign (report_internal.h), the time grouping (paper Fig. 7), the
// speed-ups, and the data files results.json / results.csv. The rules are in
// report.h and docs/report.md.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "base/env.h"
#include "stages/geometry/core/table.h"
#include "cli/report/report_internal.h"

namespace pb::report_internal {
namespace {

constexpr int kIoGroup = 4;  // kGroups[kIoGroup] == "io"

int WorkflowRank(const std::string& workflow) {
  static const std::array<const char*, 4> known = {"hpm", "lpm", "remeshing", "point_transfer"};
  for (size_t i = 0; i < known.size(); ++i)
    if (workflow == known[i]) return int(i);
  return int(known.size());
}

}  // namespace

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

namespace {

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

// A run.json as read: an object with a "stages" array, or Status::Corrupt
// naming `path`.
Expected<Json> ReadRunRecord(const std::string& path) {
  PB_ASSIGN_OR_RETURN(Json run, ReadJsonFile(path));
  if (!run.is_object() || !run.contains("stages") || !run["stages"].is_array())
    return Status::Corrupt(path + ": no \"stages\" array");
  return run;
}

// Fills time_s, total_s and peak_ram_bytes from the stage entries of `run`
// (ReadRunRecord of `path`).
Status ReadRunTimes(const Json& run, const std::string& path, Row& row) {
  try {
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
    // render.frames' back_share of the stage whose output is `frames`
    // (run.json's "outputs" say which; records without them: unknown).
    if (run.contains("outputs") && run["outputs"].is_object() && run["outputs"].contains("frames") &&
        run["outputs"]["frames"].is_string()) {
      const std::string ref = run["outputs"]["frames"].get<std::string>();
      const std::string id = ref.substr(0, ref.rfind('.'));
      for (const Json& stage : run["stages"]) {
        if (!stage.is_object() || stage.value("stage", "") != id) continue;
        const Json& figures =
            stage.contains("cached_run") && stage["cached_run"].is_object() ? stage["cached_run"] : stage;
        if (figures.contains("counters") && figures["counters"].is_object())
          row.vs_scan[kScanBackFace] = JsonNumber(figures["counters"], "back_share");
      }
    }
  } catch (const Json::exception& e) {
    return Status::Corrupt(path + ": " + e.what());
  }
  return Status::Ok();
}

// The stages' `warnings` of `run` (ReadRunRecord).
void ReadRunWarnings(const Json& run, Row& row) {
  for (const Json& stage : run["stages"]) {
    if (!stage.is_object() || !stage.contains("warnings") || !stage["warnings"].is_array())
      continue;
    const std::string id = stage.contains("stage") && stage["stage"].is_string()
                               ? stage["stage"].get<std::string>()
                               : "?";
    for (const Json& w : stage["warnings"])
      if (w.is_string()) row.warnings.emplace_back(id, w.get<std::string>());
  }
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

// The covered-pixel columns of vs_scan.json's "mean" row and the scan rows of
// geometry.json (metrics.geometry with points); absent files = all null.
Status ReadScan(const std::string& image_path, const std::string& geometry_path, Row& row) {
  if (Env::Default()->Exists(image_path)) {
    PB_ASSIGN_OR_RETURN(Table table, ReadTable(image_path));
    bool found = false;
    for (size_t r = 0; r < table.rows.size() && !found; ++r) {
      const TableValue frame = table.get(r, "frame");
      if (!std::holds_alternative<std::string>(frame) || std::get<std::string>(frame) != "mean") continue;
      for (int q = 0; q < kScanImageCount; ++q) row.vs_scan[size_t(q)] = TableOpt(table, r, kScanColumns[size_t(q)]);
      found = true;
    }
    if (!found) return Status::Corrupt(image_path + ": no row with frame \"mean\"");
  }
  if (Env::Default()->Exists(geometry_path)) {
    PB_ASSIGN_OR_RETURN(Table table, ReadTable(geometry_path));
    for (size_t r = 0; r < table.rows.size(); ++r) {
      const TableValue direction = table.get(r, "direction");
      if (!std::holds_alternative<std::string>(direction)) continue;
      const std::string& d = std::get<std::string>(direction);
      if (d == "mesh_to_scan") row.vs_scan[kScanImageCount] = TableOpt(table, r, "beyond_fraction");
      if (d == "scan_to_mesh") row.vs_scan[kScanImageCount + 1] = TableOpt(table, r, "beyond_fraction");
      if (d == "mesh_to_scan" || d == "scan_to_mesh")
        row.vs_scan[kScanImageCount + 2] = TableOpt(table, r, "boundary_edges_per_1000_faces");
    }
  }
  return Status::Ok();
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

}  // namespace

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
    // A failed run may have no run.json (it did not load): no warnings then.
    const std::string run_path = JoinPath(row.run_dir, "run.json");
    if (!row.ok() && !Env::Default()->Exists(run_path)) continue;
    PB_ASSIGN_OR_RETURN(Json run, ReadRunRecord(run_path));
    ReadRunWarnings(run, row);
    if (!row.ok()) continue;  // failed runs: a row of nulls
    PB_RETURN_IF_ERROR(ReadRunTimes(run, run_path, row));
    PB_RETURN_IF_ERROR(ReadQuality(JoinPath(row.run_dir, "vs_hpm.json"), row.vs_hpm));
    PB_RETURN_IF_ERROR(ReadQuality(JoinPath(row.run_dir, "vs_truth.json"), row.vs_truth));
    PB_RETURN_IF_ERROR(
        ReadScan(JoinPath(row.run_dir, "vs_scan.json"), JoinPath(row.run_dir, "geometry.json"), row));
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

// ---- results.json / results.csv -------------------------------------------

namespace {

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
  auto scan = [&r](int begin, int end) {
    Json j = Json::object();
    for (int i = begin; i < end; ++i) j[kScanColumns[size_t(i)]] = OptJson(r.vs_scan[size_t(i)]);
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
            {"vs_truth", quality(r.vs_truth)},
            {"vs_scan", scan(0, kScanImageCount)},
            {"scan_geometry", scan(kScanImageCount, kScanCount)}};
  Json warnings = Json::array();
  for (const auto& [stage, text] : r.warnings)
    warnings.push_back({{"stage", stage}, {"warning", text}});
  j["warnings"] = warnings;
  if (!r.error.empty()) j["error"] = r.error;
  return j;
}

}  // namespace

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

namespace {

std::string CsvField(const Json& v) {
  if (v.is_null()) return "";
  std::string s = v.is_string() ? v.get<std::string>() : v.dump();
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string quoted = "\"";
  for (char ch : s) quoted += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return quoted + "\"";
}

}  // namespace

std::string ResultsCsv(const Campaign& c) {
  std::vector<std::string> header = {"name", "scene", "workflow", "variant", "status"};
  for (const char* g : kGroups) header.push_back(std::string("time_") + g + "_s");
  for (const char* h : {"time_total_s", "peak_ram_bytes", "faces", "texture_width_px",
                        "texture_height_px", "texture_bytes", "fps", "fits_budget", "device"})
    header.push_back(h);
  for (const char* prefix : {"vs_hpm_", "vs_truth_"})
    for (const char* q : kQualityColumns) header.push_back(prefix + std::string(q));
  for (int i = 0; i < kScanCount; ++i)
    header.push_back((i < kScanImageCount ? "vs_scan_" : "scan_") + std::string(kScanColumns[size_t(i)]));
  header.push_back("error");
  header.push_back("warnings");
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
    for (int i = 0; i < kScanCount; ++i)
      values.push_back(j[i < kScanImageCount ? "vs_scan" : "scan_geometry"][kScanColumns[size_t(i)]]);
    values.push_back(r.error.empty() ? Json(nullptr) : Json(r.error));
    values.push_back(Json(r.warnings.size()));
    for (size_t i = 0; i < values.size(); ++i) out += (i ? "," : "") + CsvField(values[i]);
    out += "\n";
  }
  return out;
}

}  // namespace pb::report_internal
