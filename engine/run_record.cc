#include "engine/run_record.h"

#include <cmath>

namespace pb {

nlohmann::json StageRecordJson(const StageOutcome& o) {
  nlohmann::json j = {{"stage", o.id},         {"type", o.type},       {"status", StateName(o.state)},
                      {"key", o.key},          {"start_s", o.start_s}, {"end_s", o.end_s},
                      {"wall_s", o.end_s - o.start_s}};
  if (o.state == StageOutcome::State::kRan || o.state == StageOutcome::State::kFailed) {
    const JobResult& r = o.result;
    j["wall_s"] = r.wall_s > 0 ? r.wall_s : o.end_s - o.start_s;
    j["user_s"] = r.user_s;
    j["sys_s"] = r.sys_s;
    j["peak_rss_bytes"] = r.peak_rss_bytes;
    j["read_bytes"] = r.read_bytes;
    j["write_bytes"] = r.write_bytes;
    j["counters"] = r.counters;
    j["phases"] = r.phases;
  }
  if (o.state == StageOutcome::State::kHit) j["cached_run"] = o.cached_record;
  if (!o.warnings.empty()) j["warnings"] = o.warnings;
  if (o.forced) j["forced"] = true;
  if (!o.error.empty()) j["error"] = o.error;
  if (!o.result.log_tail.empty()) j["log_tail"] = o.result.log_tail;
  nlohmann::json outs = nlohmann::json::object();
  for (const auto& [port, art] : o.outputs) outs[port] = art.ComputeDigest().Hex();
  j["outputs"] = outs;
  return j;
}

nlohmann::json RunRecordJson(const Workflow& wf, const std::vector<StageOutcome>& outcomes,
                             const nlohmann::json& run_info) {
  nlohmann::json stages = nlohmann::json::array();
  for (const auto& o : outcomes) {
    stages.push_back(StageRecordJson(o));
    auto node = wf.stages.find(o.id);
    if (node != wf.stages.end() && !node->second.group.empty())
      stages.back()["group"] = node->second.group;
  }
  nlohmann::json j = run_info;
  j["format"] = "pointbake-run 1";
  j["workflow"] = wf.name;
  j["workflow_file"] = wf.file;
  j["stages"] = stages;
  // Which stage output each named output is, so that a reader (the report)
  // can find the figures of the stage that made, say, `frames`.
  nlohmann::json named = nlohmann::json::object();
  for (const auto& [name, ref] : wf.outputs) named[name] = ref.first + "." + ref.second;
  j["outputs"] = named;
  if (!wf.disabled.empty()) j["disabled_stages"] = wf.disabled;
  return j;
}

nlohmann::json ChromeTraceJson(const Workflow& wf, const std::vector<StageOutcome>& outcomes) {
  nlohmann::json events = nlohmann::json::array();
  events.push_back({{"name", "process_name"}, {"ph", "M"}, {"pid", 1},
                    {"args", {{"name", "pointbake run " + wf.name}}}});
  auto us = [](double s) { return std::llround(s * 1e6); };
  for (const auto& o : outcomes) {
    if (o.state == StageOutcome::State::kSkipped || o.state == StageOutcome::State::kPending) continue;
    const double dur = std::max(o.end_s - o.start_s, 1e-6);
    events.push_back({{"name", o.id},
                      {"cat", std::string("stage,") + StateName(o.state)},
                      {"ph", "X"},
                      {"pid", 1},
                      {"tid", o.slot},
                      {"ts", us(o.start_s)},
                      {"dur", us(dur)},
                      {"args", {{"type", o.type}, {"status", StateName(o.state)}, {"key", o.key}}}});
    if (o.state != StageOutcome::State::kRan) continue;
    // Phases were timed in the child from its own start; place them in the
    // stage's box (the child starts a little after the stage does).
    const double child_offset = std::max(0.0, dur - o.result.wall_s);
    for (const auto& ph : o.result.phases)
      events.push_back({{"name", ph.value("name", "")},
                        {"cat", "phase"},
                        {"ph", "X"},
                        {"pid", 1},
                        {"tid", o.slot},
                        {"ts", us(o.start_s + child_offset + ph.value("start_s", 0.0))},
                        {"dur", us(ph.value("dur_s", 0.0))}});
  }
  return {{"traceEvents", events}, {"displayTimeUnit", "ms"}};
}

Status WriteRunOutputs(const Workflow& wf, const std::vector<StageOutcome>& outcomes,
                       const nlohmann::json& run_info, Cache& cache, const std::string& out_dir,
                       std::vector<std::string>* written) {
  Env* env = Env::Default();
  PB_RETURN_IF_ERROR(env->CreateDirs(out_dir));
  std::map<std::string, const StageOutcome*> by_id;
  for (const auto& o : outcomes) by_id[o.id] = &o;
  for (const auto& [name, ref] : wf.outputs) {
    const StageOutcome* o = by_id.at(ref.first);
    auto it = o->outputs.find(ref.second);
    if (it == o->outputs.end()) continue;
    const Artifact& art = it->second;
    for (const auto& [file, stored] : art.files) {
      std::string target;
      if (art.files.size() == 1) {
        const size_t dot = file.rfind('.');
        target = JoinPath(out_dir, name + (dot == std::string::npos ? "" : file.substr(dot)));
      } else {
        PB_RETURN_IF_ERROR(env->CreateDirs(JoinPath(out_dir, name)));
        target = JoinPath(JoinPath(out_dir, name), file);
      }
      // Skip identical copies (re-runs that hit everything stay fast).
      Expected<FileInfo> existing = env->Stat(target);
      if (existing.ok() && existing->size_bytes == stored.size_bytes) {
        Expected<Digest> d = cache.FileDigest(target);
        if (d.ok() && *d == stored.digest) {
          if (written) written->push_back(target);
          continue;
        }
      }
      PB_RETURN_IF_ERROR(env->CopyFileAtomic(cache.ObjectPath(stored.digest), target));
      if (written) written->push_back(target);
    }
  }
  const nlohmann::json record = RunRecordJson(wf, outcomes, run_info);
  PB_RETURN_IF_ERROR(env->WriteFileAtomic(JoinPath(out_dir, "run.json"), record.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n"));
  std::string lines;
  for (const auto& s : record["stages"]) lines += s.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  PB_RETURN_IF_ERROR(env->WriteFileAtomic(JoinPath(out_dir, "run.jsonl"), lines));
  PB_RETURN_IF_ERROR(
      env->WriteFileAtomic(JoinPath(out_dir, "trace.json"), ChromeTraceJson(wf, outcomes).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)));
  return Status::Ok();
}

}  // namespace pb
