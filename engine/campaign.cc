#include "engine/campaign.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <atomic>
#include <mutex>
#include <set>
#include <thread>

#include "base/env.h"
#include "engine/progress.h"
#include "engine/scheduler.h"
#include "engine/schema.h"
#include "engine/workflow.h"
#include "engine/yaml_json.h"

namespace pb {

extern const char* const kCampaignSchemaText;

namespace {

using nlohmann::json;

// A --set value: strings as they are, numbers and booleans as YAML writes them.
std::string SetValueText(const json& value) {
  return value.is_string() ? value.get<std::string>() : value.dump();
}

// "transfer.interpolation" -> "interpolation": the parameter names a variant.
std::string ParamLabel(const std::string& key) { return key.substr(key.rfind('.') + 1); }

// Keeps names readable in folders: anything but [A-Za-z0-9_.,=+-] becomes '_'.
std::string FolderSafe(const std::string& text) {
  std::string out;
  for (char c : text) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '.' || c == ',' || c == '=' || c == '+' || c == '-';
    out += ok ? c : '_';
  }
  return out == "." || out == ".." ? "_" : out;
}

struct Entry {
  std::string file;   // absolute
  std::string label;  // may be empty
  std::vector<std::pair<std::string, json>> set;
  std::vector<std::pair<std::string, std::vector<json>>> matrix;
  std::string pointer;  // in the campaign file
};

std::string HostCpu() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      if (colon != std::string::npos) return line.substr(line.find_first_not_of(' ', colon + 1));
    }
  return "";
}

}  // namespace

const nlohmann::json& CampaignSchemaJson() {
  static const json schema = json::parse(kCampaignSchemaText);
  return schema;
}

Expected<Campaign> LoadCampaign(const std::string& path, Registry& registry) {
  PB_ASSIGN_OR_RETURN(YamlDocument doc, ParseYamlFile(path));
  static const JsonSchema schema =
      JsonSchema::Parse(CampaignSchemaJson(), "campaign schema").value();
  std::vector<std::string> errors;
  auto add = [&](const SourcePos& pos, const std::string& message) {
    errors.push_back(pos.ToString() + ": " + message);
  };
  auto fail = [&]() {
    std::string msg;
    for (size_t i = 0; i < errors.size(); ++i) msg += (i ? "\n" : "") + errors[i];
    return Status::Invalid(msg);
  };
  if (!doc.value.is_object()) {
    add(doc.PositionOf(""), "a campaign must be a mapping with 'name', 'scenes' and 'workflows'");
    return fail();
  }
  for (const SchemaError& e : schema.Validate(doc.value))
    add(e.about_key ? doc.KeyPositionOf(e.pointer) : doc.PositionOf(e.pointer), e.message);
  if (!errors.empty()) return fail();

  Campaign campaign;
  campaign.file = ResolvePath(".", path);
  const std::string dir = DirName(campaign.file);
  campaign.name = doc.value["name"].get<std::string>();
  campaign.description = doc.value.value("description", "");

  // Scenes: their names label the runs.
  struct Scene {
    std::string file, name, pointer;
  };
  std::vector<Scene> scenes;
  const json& scene_list = doc.value["scenes"];
  for (size_t i = 0; i < scene_list.size(); ++i) {
    const std::string pointer = "/scenes/" + std::to_string(i);
    Scene s{ResolvePath(dir, scene_list[i].get<std::string>()), "", pointer};
    if (!Env::Default()->Exists(s.file)) {
      add(doc.PositionOf(pointer), "scene file not found: " + s.file);
      continue;
    }
    Expected<json> scene = LoadScene(s.file);
    if (!scene.ok()) {
      errors.push_back(scene.status().message());
      continue;
    }
    s.name = (*scene)["name"].get<std::string>();
    for (const Scene& other : scenes)
      if (other.name == s.name)
        add(doc.PositionOf(pointer), "scene '" + s.name + "' is listed twice");
    scenes.push_back(std::move(s));
  }

  std::vector<Entry> entries;
  const json& workflow_list = doc.value["workflows"];
  for (size_t i = 0; i < workflow_list.size(); ++i) {
    const json& item = workflow_list[i];
    Entry e;
    e.pointer = "/workflows/" + std::to_string(i);
    const std::string file = item.is_string() ? item.get<std::string>() : item["file"].get<std::string>();
    e.file = ResolvePath(dir, file);
    if (item.is_object()) {
      e.label = item.value("label", "");
      if (item.contains("set"))
        for (auto& [k, v] : item["set"].items()) e.set.emplace_back(k, v);
      if (item.contains("matrix"))
        for (auto& [k, v] : item["matrix"].items())
          e.matrix.emplace_back(k, std::vector<json>(v.begin(), v.end()));
    }
    if (!Env::Default()->Exists(e.file)) {
      add(doc.PositionOf(item.is_string() ? e.pointer : e.pointer + "/file"),
          "workflow file not found: " + e.file);
      continue;
    }
    entries.push_back(std::move(e));
  }
  if (!errors.empty()) return fail();

  for (const Scene& scene : scenes) {
    for (const Entry& entry : entries) {
      // Every combination of the matrix values, the first key varying slowest.
      std::vector<size_t> index(entry.matrix.size(), 0);
      while (true) {
        CampaignRun run;
        run.scene = scene.name;
        run.scene_file = scene.file;
        run.workflow_file = entry.file;
        std::string variant = entry.label;
        for (const auto& [key, value] : entry.set) run.sets.push_back(key + "=" + SetValueText(value));
        for (size_t k = 0; k < entry.matrix.size(); ++k) {
          const auto& [key, values] = entry.matrix[k];
          const std::string text = SetValueText(values[index[k]]);
          run.sets.push_back(key + "=" + text);
          variant += (variant.empty() ? "" : ",") + ParamLabel(key) + "=" + text;
        }
        run.variant = variant;
        LoadOptions opts;
        opts.scene_file = scene.file;
        opts.sets = run.sets;
        Expected<Workflow> wf = LoadWorkflow(entry.file, opts, registry);
        if (!wf.ok()) {
          add(doc.PositionOf(entry.pointer), "workflow " + entry.file + " on scene " + scene.file +
                                                 (variant.empty() ? "" : " (" + variant + ")") +
                                                 " does not load:");
          errors.push_back(wf.status().message());
        } else {
          run.workflow = wf->name;
          for (const auto& [id, node] : wf->stages) run.stages.push_back(id);
          run.name = scene.name + "/" + wf->name + (variant.empty() ? "" : "+" + variant);
          run.dir = "runs/" + FolderSafe(scene.name) + "/" +
                    FolderSafe(wf->name + (variant.empty() ? "" : "+" + variant));
          for (const CampaignRun& other : campaign.runs)
            if (other.name == run.name || other.dir == run.dir)
              add(doc.PositionOf(entry.pointer),
                  "run '" + run.name + "' appears twice; give one entry a `label:`");
          campaign.runs.push_back(std::move(run));
        }
        // Next combination.
        size_t k = entry.matrix.size();
        while (k > 0 && ++index[k - 1] == entry.matrix[k - 1].second.size()) index[--k] = 0;
        if (k == 0) break;
      }
    }
  }
  if (!errors.empty()) return fail();
  return campaign;
}

Status CheckCampaignStageIds(const Campaign& campaign, const std::vector<std::string>& ids,
                             const std::string& flag) {
  if (ids.empty()) return Status::Ok();
  std::set<std::string> stages;
  for (const CampaignRun& run : campaign.runs) stages.insert(run.stages.begin(), run.stages.end());
  std::string unknown, known;
  for (const std::string& id : ids)
    if (!stages.count(id)) unknown += (unknown.empty() ? "'" : ", '") + id + "'";
  if (unknown.empty()) return Status::Ok();
  for (const std::string& id : stages) known += (known.empty() ? "" : ", ") + id;
  return Status::Invalid("<command line>: " + flag + ": no run of campaign " + campaign.name +
                         " has a stage " + unknown + " (its runs' stages: " + known + ")");
}

CampaignResult RunCampaign(const Campaign& campaign, Cache& cache, const CampaignOptions& options,
                           Registry& registry, const CampaignReportWriter& report) {
  CampaignResult result;
  result.out_dir = options.out_dir.empty() ? "out/" + campaign.name : options.out_dir;
  result.runs = static_cast<int>(campaign.runs.size());
  const std::string started = UtcTimestamp();
  const auto t0 = std::chrono::steady_clock::now();
  result.report = Env::Default()->CreateDirs(result.out_dir);
  if (!result.report.ok()) return result;
  std::vector<json> rows(campaign.runs.size());
  std::mutex print_mu;
  ForcedKeys forced_keys;  // --force: a stage the runs share is forced once
  const size_t parallel = std::max<size_t>(1, std::min<size_t>(options.parallel_runs, campaign.runs.size()));
  auto run_one = [&](size_t i) {
    const CampaignRun& run = campaign.runs[i];
    {
      std::lock_guard<std::mutex> g(print_mu);
      std::printf("[%zu/%zu] %s\n", i + 1, campaign.runs.size(), run.name.c_str());
      std::fflush(stdout);
    }
    json row = {{"name", run.name},         {"scene", run.scene},
                {"scene_file", run.scene_file}, {"workflow", run.workflow},
                {"workflow_file", run.workflow_file}, {"variant", run.variant},
                {"sets", run.sets},         {"dir", run.dir}};
    LoadOptions opts;
    opts.scene_file = run.scene_file;
    opts.sets = run.sets;
    // Loaded again: a file may have changed since the campaign was checked.
    Expected<Workflow> wf = [&] {
      std::lock_guard<std::mutex> g(print_mu);  // plugins load into the shared registry
      return LoadWorkflow(run.workflow_file, opts, registry);
    }();
    if (!wf.ok()) {
      row["status"] = "failed";
      row["error"] = wf.status().message();
      std::fprintf(stderr, "%s\n", wf.status().message().c_str());
      rows[i] = row;
      return;
    }
    WorkflowRunOptions run_options = options.run;
    run_options.sets = run.sets;
    // One run at a time: the first run that forces a shared key has replaced
    // its entry before the next run looks. Runs in parallel (a cluster)
    // could find the old entry first, so there each run forces its own.
    if (parallel == 1) run_options.forced_keys = &forced_keys;
    const WorkflowRunSummary s =
        RunWorkflowInto(*wf, cache, run_options, JoinPath(result.out_dir, run.dir));
    {
      std::lock_guard<std::mutex> g(print_mu);
      std::printf("  %s: %s in %s\n", run.name.c_str(), SummaryCounts(s).c_str(),
                  FormatSeconds(s.total_s).c_str());
      std::fflush(stdout);
    }
    row["status"] = s.ok() ? "ok" : "failed";
    if (s.warnings > 0) row["warnings"] = s.warnings;
    if (!s.outputs.ok()) row["error"] = s.outputs.message();
    else if (!s.ok()) row["error"] = std::to_string(s.failed) + " stage(s) failed, " +
                                     std::to_string(s.skipped) + " not run; see " + run.dir + "/run.json";
    rows[i] = row;
  };
  // Runs in parallel (a cluster): each run's scheduler submits its ready
  // stages; a stage two runs share is computed once, the other run waits on
  // its key lock and reuses the entry.
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t i; (i = next.fetch_add(1)) < campaign.runs.size();) run_one(i);
  };
  std::vector<std::thread> workers;
  for (size_t w = 1; w < parallel; ++w) workers.emplace_back(worker);
  worker();
  for (std::thread& t : workers) t.join();
  json runs = json::array();
  for (json& row : rows) {
    if (row.value("status", "failed") != "ok") ++result.failed_runs;
    runs.push_back(std::move(row));
  }
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const long pages = ::sysconf(_SC_PHYS_PAGES), page_size = ::sysconf(_SC_PAGE_SIZE);
  const json manifest = {
      {"format", "pointbake-campaign"},
      {"version", 1},
      {"name", campaign.name},
      {"file", campaign.file},
      {"description", campaign.description},
      {"started", started},
      {"total_wall_s", total_s},
      {"host",
       {{"cores", std::thread::hardware_concurrency()},
        {"memory_bytes", pages > 0 && page_size > 0 ? static_cast<uint64_t>(pages) * page_size : 0},
        {"cpu", HostCpu()}}},
      {"runs", runs}};
  result.report = Env::Default()->WriteFileAtomic(JoinPath(result.out_dir, "campaign.json"),
                                                  manifest.dump(2) + "\n");
  if (result.report.ok() && report) {
    result.report_dir = JoinPath(result.out_dir, "report");
    result.report = report(result.out_dir, result.report_dir);
    if (!result.report.ok()) result.report_dir.clear();
  }
  return result;
}

}  // namespace pb
