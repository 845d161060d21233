#include "engine/key.h"

#include <cmath>
#include <set>

namespace pb {
namespace {

using nlohmann::json;

json Canonical(const json& v) {
  if (v.is_object()) {
    json out = json::object();
    for (const auto& [k, x] : v.items()) out[k] = Canonical(x);
    return out;
  }
  if (v.is_array()) {
    json out = json::array();
    for (const auto& x : v) out.push_back(Canonical(x));
    return out;
  }
  if (v.is_number_float()) {
    const double d = v.get<double>();
    // 1 and 1.0 are the same parameter value.
    if (std::isfinite(d) && std::floor(d) == d && std::fabs(d) < 9e15) return static_cast<int64_t>(d);
  }
  return v;
}

std::string Short(const json& v) {
  std::string s = v.dump();
  return s.size() > 60 ? s.substr(0, 57) + "..." : s;
}

}  // namespace

Expected<json> KeyComponents(const StageNode& node, const std::string& salt,
                             const std::map<std::string, std::string>& input_digests,
                             Cache& cache) {
  json params = json::object();
  const json schema = json::parse(node.type->params_schema, nullptr, false);
  const json props = schema.value("properties", json::object());
  for (const auto& [name, value] : node.params.items()) {
    const json prop = props.value(name, json::object());
    if (!prop.value("x-affects-output", true)) continue;
    if (prop.value("x-path", false) && value.is_string()) {
      Expected<Digest> d = cache.FileDigest(value.get<std::string>());
      if (!d.ok())
        return d.status().WithContext("stage '" + node.id + "': parameter '" + name + "'");
      params[name] = {{"file_digest", d->Hex()}};
      continue;
    }
    params[name] = Canonical(value);
  }
  json inputs = json::object();
  for (const auto& [port, digest] : input_digests) inputs[port] = digest;
  return json{{"engine_format", kEngineFormatVersion},
              {"type", node.type->id},
              {"version", node.type->version},
              {"params", params},
              {"inputs", inputs},
              {"salt", salt}};
}


std::vector<std::string> DiffComponents(const json& before, const json& after) {
  std::vector<std::string> out;
  if (before.value("engine_format", 0) != after.value("engine_format", 0))
    out.push_back("engine format " + std::to_string(before.value("engine_format", 0)) + " -> " +
                  std::to_string(after.value("engine_format", 0)));
  if (before.value("type", "") != after.value("type", ""))
    out.push_back("stage type " + before.value("type", "") + " -> " + after.value("type", ""));
  else if (before.value("version", 0) != after.value("version", 0))
    out.push_back("implementation version " + std::to_string(before.value("version", 0)) + " -> " +
                  std::to_string(after.value("version", 0)));
  const json pb = before.value("params", json::object()), pa = after.value("params", json::object());
  std::set<std::string> names;
  for (const auto& [k, v] : pb.items()) names.insert(k);
  for (const auto& [k, v] : pa.items()) names.insert(k);
  for (const std::string& n : names) {
    if (!pb.contains(n)) out.push_back("parameter '" + n + "' added: " + Short(pa[n]));
    else if (!pa.contains(n)) out.push_back("parameter '" + n + "' removed (was " + Short(pb[n]) + ")");
    else if (pb[n] != pa[n]) {
      if (pb[n].is_object() && pb[n].contains("file_digest"))
        out.push_back("file of parameter '" + n + "' changed (content)");
      else
        out.push_back("parameter '" + n + "' changed: " + Short(pb[n]) + " -> " + Short(pa[n]));
    }
  }
  const json ib = before.value("inputs", json::object()), ia = after.value("inputs", json::object());
  std::set<std::string> ports;
  for (const auto& [k, v] : ib.items()) ports.insert(k);
  for (const auto& [k, v] : ia.items()) ports.insert(k);
  for (const std::string& p : ports)
    if (ib.value(p, "") != ia.value(p, "")) out.push_back("input '" + p + "' changed (upstream output differs)");
  if (before.value("salt", "") != after.value("salt", "")) out.push_back("salt changed");
  return out;
}

Expected<std::vector<PlanLine>> PlanWorkflow(const Workflow& wf, Cache& cache,
                                             const PlanOptions& options) {
  std::vector<PlanLine> lines;
  // By "stage.port": the artifact digest of a stage that hits, else a
  // stand-in "pending:<key>.<port>" for the output a run would produce. A
  // stand-in makes its dependents' keys symbolic: never in the cache, but
  // equal across the runs of a campaign that share the same upstream chain.
  std::map<std::string, std::string> known;
  constexpr const char* kPending = "pending:";
  for (const std::string& id : wf.order) {
    const StageNode& node = wf.stages.at(id);
    PlanLine line;
    line.stage = id;
    line.type = node.type->id;
    std::map<std::string, std::string> digests;
    std::set<std::string> waiting;  // upstream stages whose outputs are pending
    for (const auto& [port, in] : node.inputs) {
      const std::string& digest = known.at(in.from_stage + "." + in.from_port);
      if (digest.rfind(kPending, 0) == 0) waiting.insert(in.from_stage);
      digests[port] = digest;
    }
    const std::optional<json> history = cache.LoadHistory(wf.name, id);
    PB_ASSIGN_OR_RETURN(json comps, KeyComponents(node, wf.salt, digests, cache));
    const std::string key = KeyOf(comps).Hex();
    auto pending_outputs = [&] {
      for (const PortSpec& p : node.type->outputs)
        known[id + "." + p.name] = kPending + key + "." + p.name;
      if (options.planned_keys) options.planned_keys->insert(key);
    };
    const bool planned_earlier = options.planned_keys && options.planned_keys->count(key) > 0;
    if (!waiting.empty()) {
      if (planned_earlier) {
        line.state = PlanLine::State::kEarlierRun;
        line.reasons.push_back(
            "an earlier run of this campaign computes it (same stage after the same stages)");
      } else {
        line.state = PlanLine::State::kDependsOnUpstream;
        std::string names;
        for (const auto& s : waiting) names += (names.empty() ? "'" : ", '") + s + "'";
        line.reasons.push_back(
            "runs after " + names +
            " re-run; stays cached if their outputs come out unchanged (early cutoff)");
        // Parameter changes can still be named.
        if (history && history->contains("components")) {
          json before = (*history)["components"], after = comps;
          before["inputs"] = after["inputs"] = json::object();
          for (const std::string& r : DiffComponents(before, after)) line.reasons.push_back(r);
        }
      }
      pending_outputs();
      lines.push_back(line);
      continue;
    }
    line.key = key;
    const bool forced = options.force.count(id) > 0;
    std::optional<CacheEntry> entry = cache.Lookup(KeyOf(comps));
    if (forced && planned_earlier) {
      line.state = PlanLine::State::kEarlierRun;
      line.reasons.push_back(
          "forced (--force), and computed by an earlier run of this campaign (same key): a hit by "
          "then");
    } else if (forced) {
      line.state = PlanLine::State::kMiss;
      line.reasons.push_back(entry ? "forced (--force): in the cache, but runs again; its result "
                                     "replaces the entry"
                                   : "forced (--force); not in the cache either");
    } else if (entry) {
      line.state = PlanLine::State::kHit;
      for (const auto& [port, art] : entry->outputs) known[id + "." + port] = art.ComputeDigest().Hex();
    } else if (planned_earlier) {
      line.state = PlanLine::State::kEarlierRun;
      line.reasons.push_back(
          "computed by an earlier run of this campaign (same key); a hit by then");
    } else {
      line.state = PlanLine::State::kMiss;
      if (!history || !history->contains("components")) {
        line.reasons.push_back("no earlier run of this stage in this cache");
      } else {
        std::vector<std::string> diff = DiffComponents((*history)["components"], comps);
        if (diff.empty()) line.reasons.push_back("same key as the last run, but the entry is gone (gc'd or damaged)");
        for (const std::string& r : diff) line.reasons.push_back(r);
      }
    }
    if (line.state != PlanLine::State::kHit) pending_outputs();
    lines.push_back(line);
  }
  return lines;
}

}  // namespace pb
