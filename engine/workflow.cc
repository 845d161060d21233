#include "engine/workflow.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <functional>
#include <optional>
#include <queue>
#include <set>
#include <sstream>

#include "base/env.h"
#include "base/units.h"
#include "engine/schema.h"

namespace pb {

extern const char* const kWorkflowSchemaText;
extern const char* const kSceneSchemaText;

namespace {

using nlohmann::json;

// Collects `file:line:column: message` lines. Those about `sorted_file` are
// listed first, in the order of the file; the others (a scene, the command
// line) follow in the order they were found.
class Errors {
 public:
  explicit Errors(std::string sorted_file = "") : sorted_file_(std::move(sorted_file)) {}
  void Add(const SourcePos& pos, const std::string& message) {
    lines_.push_back({pos, pos.ToString() + ": " + message});
  }
  void AddRaw(const std::string& line) { lines_.push_back({SourcePos{}, line}); }
  bool empty() const { return lines_.empty(); }
  size_t size() const { return lines_.size(); }
  Status ToStatus() const {
    std::vector<const Line*> in_file, others;
    for (const Line& l : lines_)
      (!sorted_file_.empty() && l.pos.file == sorted_file_ ? in_file : others).push_back(&l);
    std::stable_sort(in_file.begin(), in_file.end(), [](const Line* a, const Line* b) {
      return std::pair(a->pos.line, a->pos.column) < std::pair(b->pos.line, b->pos.column);
    });
    in_file.insert(in_file.end(), others.begin(), others.end());
    std::string msg;
    for (size_t i = 0; i < in_file.size(); ++i) msg += (i ? "\n" : "") + in_file[i]->text;
    return Status::Invalid(msg);
  }

 private:
  struct Line {
    SourcePos pos;
    std::string text;
  };
  std::string sorted_file_;
  std::vector<Line> lines_;
};

size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

}  // namespace

std::string DidYouMean(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  size_t best_d = std::max<size_t>(2, word.size() / 3) + 1;
  for (const auto& c : candidates) {
    size_t d = EditDistance(word, c);
    if (d < best_d) best_d = d, best = c;
  }
  return best.empty() ? "" : " (did you mean '" + best + "'?)";
}

namespace {

std::string Suggest(const std::string& word, const std::vector<std::string>& candidates) {
  return DidYouMean(word, candidates);
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (size_t i = 0; i < names.size(); ++i) out += (i ? ", " : "") + names[i];
  return out.empty() ? "none" : out;
}

template <typename Map>
std::vector<std::string> KeysOf(const Map& m) {
  std::vector<std::string> out;
  for (const auto& kv : m) out.push_back(kv.first);
  return out;
}

void ReportSchemaErrors(const YamlDocument& doc, const std::vector<SchemaError>& errors,
                        const std::string& pointer_prefix, Errors& out) {
  for (const SchemaError& e : errors) {
    const std::string pointer = pointer_prefix + e.pointer;
    out.Add(e.about_key ? doc.KeyPositionOf(pointer) : doc.PositionOf(pointer), e.message);
  }
}

// Looks up "a.b.c" in the scene.
const json* SceneLookup(const json& scene, const std::string& dotted) {
  const json* cur = &scene;
  std::stringstream ss(dotted);
  std::string part;
  while (std::getline(ss, part, '.')) {
    size_t index = 0;
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), index);
    const bool is_index = !part.empty() && ec == std::errc() && end == part.data() + part.size();
    if (cur->is_object() && cur->contains(part)) cur = &(*cur)[part];
    else if (cur->is_array() && is_index && index < cur->size()) cur = &(*cur)[index];
    else return nullptr;
  }
  return cur;
}

struct SceneContext {
  const json* scene = nullptr;  // null: no scene
  std::string file;
  std::string dir;
};

// Replaces ${scene.KEY} in every string of `value`. A string that is exactly
// one reference takes the referenced value with its type; otherwise the value
// is formatted into the string. `from_scene` collects pointers (relative to
// `value`) whose whole value came from the scene, for path resolution.
void SubstituteScene(json& value, const std::string& pointer, const YamlDocument& doc,
                     const std::string& doc_pointer, const SceneContext& scene,
                     std::set<std::string>& from_scene, Errors& errors) {
  if (value.is_object()) {
    for (auto& [k, v] : value.items())
      SubstituteScene(v, pointer + "/" + PointerToken(k), doc, doc_pointer + "/" + PointerToken(k),
                      scene, from_scene, errors);
    return;
  }
  if (value.is_array()) {
    for (size_t i = 0; i < value.size(); ++i)
      SubstituteScene(value[i], pointer + "/" + std::to_string(i), doc,
                      doc_pointer + "/" + std::to_string(i), scene, from_scene, errors);
    return;
  }
  if (!value.is_string()) return;
  const std::string text = value.get<std::string>();
  if (text.find("${") == std::string::npos) return;
  std::string out;
  size_t pos = 0;
  bool whole = false;
  json whole_value;
  while (pos < text.size()) {
    size_t start = text.find("${", pos);
    if (start == std::string::npos) {
      out += text.substr(pos);
      break;
    }
    out += text.substr(pos, start - pos);
    size_t end = text.find('}', start);
    if (end == std::string::npos) {
      errors.Add(doc.PositionOf(doc_pointer), "unterminated '${' in \"" + text + "\"");
      return;
    }
    const std::string ref = text.substr(start + 2, end - start - 2);
    if (ref.rfind("scene.", 0) != 0) {
      errors.Add(doc.PositionOf(doc_pointer),
                 "unknown reference '${" + ref + "}' (only ${scene.KEY} is supported)");
      return;
    }
    if (!scene.scene) {
      errors.Add(doc.PositionOf(doc_pointer),
                 "'${" + ref + "}' refers to the scene, but the workflow names no scene "
                 "(add 'scene: FILE' or pass --scene FILE)");
      return;
    }
    const json* found = SceneLookup(*scene.scene, ref.substr(6));
    if (!found) {
      std::vector<std::string> keys;
      if (scene.scene->is_object())
        for (auto& [k, v] : scene.scene->items()) keys.push_back(k);
      // A scene written by hand for a scan often lacks what only the shipped
      // workflows need: say how to get it.
      const std::string key = ref.substr(6);
      const bool surveyable = key == "viewpoints" || key.rfind("params.", 0) == 0 || key == "spacing_m";
      errors.Add(doc.PositionOf(doc_pointer),
                 "scene " + scene.file + " has no key '" + key + "'" + Suggest(key, keys) +
                     (surveyable ? " (`pointbake scene SCAN -o FILE` writes a scene with viewpoints and "
                                   "parameters read off the scan)"
                                 : ""));
      return;
    }
    if (start == 0 && end == text.size() - 1) {
      whole = true;
      whole_value = *found;
    }
    out += found->is_string() ? found->get<std::string>() : found->dump();
    pos = end + 1;
  }
  if (whole) {
    value = whole_value;
    from_scene.insert(pointer);
  } else {
    value = out;
  }
}

// JSON has no NaN or infinity: they would reach stages (and cache keys) as
// null. Reports the pointer (relative to `value`) of the first one.
std::optional<std::string> FindNonFinite(const json& value, const std::string& pointer) {
  if (value.is_number_float() && !std::isfinite(value.get<double>())) return pointer;
  if (value.is_object())
    for (const auto& [k, v] : value.items())
      if (auto p = FindNonFinite(v, pointer + "/" + PointerToken(k))) return p;
  if (value.is_array())
    for (size_t i = 0; i < value.size(); ++i)
      if (auto p = FindNonFinite(value[i], pointer + "/" + std::to_string(i))) return p;
  return std::nullopt;
}

// Applies one --set STAGE.PARAM[.SUB]=VALUE to the stages' `with:` objects.
Status ApplySet(const std::string& set, json& stages) {
  const size_t eq = set.find('=');
  if (eq == std::string::npos)
    return Status::Invalid("--set " + set + ": expected STAGE.PARAM=VALUE");
  const std::string lhs = set.substr(0, eq);
  std::vector<std::string> parts;
  std::stringstream ss(lhs);
  for (std::string p; std::getline(ss, p, '.');) parts.push_back(p);
  if (parts.size() < 2 || std::any_of(parts.begin(), parts.end(), [](auto& p) { return p.empty(); }))
    return Status::Invalid("--set " + set + ": expected STAGE.PARAM=VALUE");
  if (!stages.is_object() || !stages.contains(parts[0])) {
    std::vector<std::string> ids;
    if (stages.is_object())
      for (auto& [k, v] : stages.items()) ids.push_back(k);
    return Status::Invalid("--set " + set + ": no stage '" + parts[0] + "' in the workflow" +
                           Suggest(parts[0], ids) + " (stages: " + JoinNames(ids) + ")");
  }
  Expected<json> value = ParseYamlValue(set.substr(eq + 1));
  if (!value.ok()) return value.status().WithContext("--set " + set);
  json& stage = stages[parts[0]];
  if (!stage.is_object()) return Status::Invalid("--set " + set + ": stage is not a mapping");
  json* cur = &stage["with"];
  if (cur->is_null()) *cur = json::object();
  if (!cur->is_object())
    return Status::Invalid("--set " + set + ": stage '" + parts[0] + "' has no mapping of parameters");
  for (size_t i = 1; i + 1 < parts.size(); ++i) {
    json& next = (*cur)[parts[i]];
    if (next.is_null()) next = json::object();
    if (!next.is_object())
      return Status::Invalid("--set " + set + ": '" + parts[i] + "' is not a mapping");
    cur = &next;
  }
  (*cur)[parts.back()] = *value;
  return Status::Ok();
}

}  // namespace

std::string DefaultWorkflowName(const std::string& path) {
  std::string stem = path.substr(path.find_last_of('/') + 1);
  const size_t dot = stem.rfind('.');
  if (dot != std::string::npos && dot > 0) stem.resize(dot);
  std::string name;
  for (char c : stem) {
    const bool alnum = std::isalnum(static_cast<unsigned char>(c)) != 0;
    if (name.empty() && !alnum) continue;  // a name starts with a letter or digit
    name += alnum || c == '_' || c == '.' || c == '-' ? c : '_';
  }
  return name.empty() ? "workflow" : name;
}

const nlohmann::json& WorkflowSchemaJson() {
  static const json schema = json::parse(kWorkflowSchemaText);
  return schema;
}

const nlohmann::json& SceneSchemaJson() {
  static const json schema = json::parse(kSceneSchemaText);
  return schema;
}

std::vector<std::string> Workflow::Dependents(const std::string& id) const {
  std::vector<std::string> out;
  for (const auto& [sid, node] : stages)
    if (std::find(node.deps.begin(), node.deps.end(), id) != node.deps.end()) out.push_back(sid);
  return out;
}

Expected<nlohmann::json> LoadScene(const std::string& path) {
  PB_ASSIGN_OR_RETURN(YamlDocument doc, ParseYamlFile(path));
  static const JsonSchema schema = JsonSchema::Parse(SceneSchemaJson(), "scene schema").value();
  Errors errors;
  if (!doc.value.is_object()) {
    errors.Add(doc.PositionOf(""), "a scene file must be a mapping with at least 'name'");
    return errors.ToStatus();
  }
  ReportSchemaErrors(doc, schema.Validate(doc.value), "", errors);
  if (!errors.empty()) return errors.ToStatus();
  json scene = ApplyDefaults(SceneSchemaJson(), doc.value);

  // Units: the project computes in meters. An io.read_points source reads
  // its file in the scene's units (its `with: units`, set here), and the
  // viewpoints, written in the same units as the scan, are converted.
  std::string unit = scene.value("units", "m");
  const bool unit_given = doc.value.contains("units");
  if (!unit_given && scene.contains("source") && scene["source"].contains("with") &&
      scene["source"]["with"].is_object() && scene["source"]["with"].contains("units") &&
      scene["source"]["with"]["units"].is_string() &&
      MetersPerUnit(scene["source"]["with"]["units"].get<std::string>())) {
    unit = scene["source"]["with"]["units"].get<std::string>();  // the source's, for the viewpoints
    scene["units"] = unit;
  }
  const double meters = MetersPerUnit(unit).value_or(1.0);  // the schema checked the name
  if (scene.contains("source") && scene["source"].value("uses", "") == "io.read_points") {
    json& with = scene["source"]["with"];
    if (!with.is_object()) with = json::object();
    if (with.contains("units") && with["units"] != unit) {
      errors.Add(doc.PositionOf("/source/with/units"),
                 "the source reads its file in " + with["units"].dump() + " but the scene's units are \"" +
                     unit + "\"; give the units once, as the scene's `units:`");
    }
    with["units"] = unit;
  } else if (meters != 1.0 && scene.contains("source")) {
    errors.Add(doc.PositionOf("/units"),
               "units \"" + unit + "\": only an io.read_points source converts a scan file to meters; " +
                   scene["source"].value("uses", "") + " makes its points in meters (say `units: m`)");
  }
  if (meters != 1.0 && scene.contains("viewpoints")) {
    for (json& view : scene["viewpoints"])
      for (const char* key : {"eye", "target"})
        if (view.contains(key))
          for (json& c : view[key]) c = c.get<double>() * meters;
  }
  if (!errors.empty()) return errors.ToStatus();
  return scene;
}

Expected<Workflow> LoadWorkflow(const std::string& path, const LoadOptions& options,
                                Registry& registry) {
  PB_ASSIGN_OR_RETURN(YamlDocument doc, ParseYamlFile(path));
  static const JsonSchema schema =
      JsonSchema::Parse(WorkflowSchemaJson(), "workflow schema").value();
  Errors errors(doc.file);
  if (!doc.value.is_object()) {
    errors.Add(doc.PositionOf(""), "a workflow must be a mapping with 'stages'");
    return errors.ToStatus();
  }
  // The checks below go on after schema errors, so one pass reports both; a
  // value the schema rejected is skipped there, not reported a second time.
  const std::vector<SchemaError> schema_errors = schema.Validate(doc.value);
  ReportSchemaErrors(doc, schema_errors, "", errors);
  auto rejected = [&](const std::string& pointer) {
    for (const SchemaError& e : schema_errors)
      if (e.pointer == pointer || e.pointer.rfind(pointer + "/", 0) == 0) return true;
    return false;
  };
  auto string_at = [&](const char* key) -> std::optional<std::string> {
    if (!doc.value.contains(key) || !doc.value[key].is_string() || rejected(std::string("/") + key))
      return std::nullopt;
    return doc.value[key].get<std::string>();
  };

  Workflow wf;
  wf.file = ResolvePath(".", path);
  const std::string dir = DirName(wf.file);
  wf.name = string_at("name").value_or(DefaultWorkflowName(wf.file));
  wf.salt = string_at("salt").value_or("");

  // Plugins first: they add stage types.
  if (doc.value.contains("plugins") && doc.value["plugins"].is_array()) {
    const json& plugins = doc.value["plugins"];
    for (size_t i = 0; i < plugins.size(); ++i) {
      if (!plugins[i].is_string()) continue;  // reported by the schema
      const std::string abs = ResolvePath(dir, plugins[i].get<std::string>());
      Status st = registry.LoadPlugin(abs);
      if (!st.ok()) errors.Add(doc.PositionOf("/plugins/" + std::to_string(i)), st.message());
      wf.plugins.push_back(abs);
    }
  }

  // Scene.
  SceneContext scene_ctx;
  json scene;
  std::string scene_path;
  SourcePos scene_pos{"--scene", 0, 0};
  if (!options.scene_file.empty()) {
    scene_path = ResolvePath(".", options.scene_file);
  } else if (const std::optional<std::string> scene_file = string_at("scene")) {
    scene_path = ResolvePath(dir, *scene_file);
    scene_pos = doc.PositionOf("/scene");
  }
  if (!scene_path.empty()) {
    if (!Env::Default()->Exists(scene_path)) {
      errors.Add(scene_pos, "scene file not found: " + scene_path);
    } else {
      Expected<json> loaded = LoadScene(scene_path);
      if (!loaded.ok()) errors.AddRaw(loaded.status().message());
      else scene = std::move(loaded).value();
    }
    wf.scene_file = scene_path;
    wf.scene = scene;
    if (!scene.is_null()) {
      scene_ctx.scene = &wf.scene;
      scene_ctx.file = scene_path;
      scene_ctx.dir = DirName(scene_path);
    }
  }

  // A whole `with: ${scene.KEY}` becomes the scene's mapping before --set
  // applies, so overrides reach its parameters (e.g. --set scan.points=...).
  json stages = doc.value.contains("stages") && doc.value["stages"].is_object()
                    ? doc.value["stages"]
                    : json::object();
  std::set<std::string> with_from_scene;
  for (auto& [id, spec] : stages.items()) {
    if (!spec.is_object() || !spec.contains("with") || !spec["with"].is_string() ||
        rejected("/stages/" + PointerToken(id) + "/with"))
      continue;
    std::set<std::string> unused;
    SubstituteScene(spec["with"], "", doc, "/stages/" + PointerToken(id) + "/with", scene_ctx, unused,
                    errors);
    with_from_scene.insert(id);
  }

  // --set overrides, applied to a copy of the stages; remember which
  // pointers they touched so errors point at the command line.
  std::map<std::string, std::string> set_by_pointer;
  for (const std::string& set : options.sets) {
    Status st = ApplySet(set, stages);
    if (!st.ok()) {
      errors.AddRaw("<command line>: " + st.message());
      continue;
    }
    const std::string lhs = set.substr(0, set.find('='));
    std::string pointer = "/stages";
    std::stringstream ss(lhs);
    int part_index = 0;
    for (std::string p; std::getline(ss, p, '.'); ++part_index) {
      pointer += "/" + PointerToken(p);
      if (part_index == 0) pointer += "/with";
    }
    set_by_pointer[pointer] = set;
  }
  auto pos_of = [&](const std::string& pointer) -> SourcePos {
    for (const auto& [p, set] : set_by_pointer)
      if (pointer == p || pointer.rfind(p + "/", 0) == 0)
        return SourcePos{"<command line> --set " + set, 0, 0};
    return doc.PositionOf(pointer);
  };

  std::vector<std::string> type_ids;
  for (const StageType* t : registry.All()) type_ids.push_back(t->id);

  std::set<std::string> disabled;
  for (auto& [id, spec] : stages.items()) {
    const std::string sp = "/stages/" + PointerToken(id);
    // The schema said what is wrong with a stage without a usable `uses:`.
    if (!spec.is_object() || !spec.contains("uses") || rejected(sp + "/uses") ||
        rejected(sp + "/when"))
      continue;
    StageNode node;
    node.id = id;
    node.pos = doc.KeyPositionOf(sp);
    if (spec.contains("group") && spec["group"].is_string())
      node.group = spec["group"].get<std::string>();
    const size_t errors_before = errors.size();
    std::set<std::string> from_scene;
    if (spec.contains("when")) {
      json when = spec["when"];
      SubstituteScene(when, "", doc, sp + "/when", scene_ctx, from_scene, errors);
      if (errors.size() != errors_before) continue;
      if (!when.is_boolean()) {
        errors.Add(doc.PositionOf(sp + "/when"), "stage '" + id + "': when: must be true or false, got " +
                                                     when.dump() + " from the scene");
        continue;
      }
      if (!when.get<bool>()) {
        disabled.insert(id);
        continue;
      }
    }
    json uses_value = spec["uses"];
    SubstituteScene(uses_value, "", doc, sp + "/uses", scene_ctx, from_scene, errors);
    if (errors.size() != errors_before) continue;
    if (!uses_value.is_string()) {
      errors.Add(doc.PositionOf(sp + "/uses"),
                 "stage '" + id + "': uses: the scene gives " + uses_value.dump() +
                     ", not a stage type name");
      continue;
    }
    const std::string uses = uses_value.get<std::string>();
    node.type = registry.Find(uses);
    if (!node.type) {
      errors.Add(doc.PositionOf(sp + "/uses"),
                 "unknown stage type '" + uses + "'" + Suggest(uses, type_ids) +
                     " (see `pointbake stages`)");
      continue;
    }
    // A `with:` the schema rejected leaves the parameters unchecked; the
    // stage's inputs are still checked.
    const bool with_rejected = rejected(sp + "/with");
    json with = spec.contains("with") && !with_rejected ? spec["with"] : json::object();
    if (!with.is_object()) {
      if (!with.is_string())  // an unresolved ${scene...} was reported above
        errors.Add(doc.PositionOf(sp + "/with"), "stage '" + id + "': with: the scene gives " +
                                                     with.dump() + ", not a mapping of parameters");
      continue;
    }
    from_scene.clear();
    SubstituteScene(with, "", doc, sp + "/with", scene_ctx, from_scene, errors);
    // An unresolved ${...} would only add a confusing type error below.
    if (errors.size() != errors_before) continue;
    // A whole `with:` taken from the scene makes every parameter a scene value.
    const bool whole_with_from_scene = with_from_scene.count(id) > 0;
    if (std::optional<std::string> bad = FindNonFinite(with, "")) {
      errors.Add(pos_of(sp + "/with" + *bad),
                 "stage '" + id + "' (" + uses + "): must be a finite number (no .inf or .nan)");
      continue;
    }
    const json& param_schema = registry.ParamsSchema(uses).json();
    with = ApplyDefaults(param_schema, with);
    for (const SchemaError& e :
         with_rejected ? std::vector<SchemaError>{} : registry.ParamsSchema(uses).Validate(with)) {
      const std::string pointer = sp + "/with" + e.pointer;
      SourcePos pos = pos_of(pointer);
      if (e.about_key && pos.file.rfind("<command line>", 0) != 0) pos = doc.KeyPositionOf(pointer);
      errors.Add(pos, "stage '" + id + "' (" + uses + "): " + e.message);
    }
    // Paths: absolute, relative to the file that named them.
    const json properties = param_schema.value("properties", json::object());
    for (auto& [name, prop] : properties.items()) {
      if (!prop.value("x-path", false) || !with.contains(name) || !with[name].is_string()) continue;
      // Paths typed on the command line are relative to where it was typed.
      const bool from_command_line =
          pos_of(sp + "/with/" + PointerToken(name)).file.rfind("<command line>", 0) == 0;
      const bool scene_value =
          !from_command_line &&
          (whole_with_from_scene || from_scene.count("/" + PointerToken(name)) > 0);
      const std::string base = scene_value ? scene_ctx.dir : from_command_line ? "." : dir;
      const std::string abs = ResolvePath(base, with[name].get<std::string>());
      with[name] = abs;
      if (!Env::Default()->Exists(abs)) {
        const std::string pointer = sp + "/with/" + PointerToken(name);
        std::string hint;
        if (scene_value) {
          hint = " (from scene " + scene_ctx.file + "; edit its path there";
          if (scene_ctx.scene->contains("data_note") && (*scene_ctx.scene)["data_note"].is_string())
            hint += ". The scene says: " + (*scene_ctx.scene)["data_note"].get<std::string>();
          hint += ")";
        }
        errors.Add(pos_of(pointer), "stage '" + id + "': file not found: " + abs + hint);
      }
    }
    node.params = std::move(with);

    // Inputs.
    const json in = spec.contains("in") && spec["in"].is_object() ? spec["in"] : json::object();
    std::set<std::string> rejected_inputs;  // named, but the schema rejected the reference
    for (auto& [port, ref] : in.items()) {
      const std::string ip = sp + "/in/" + PointerToken(port);
      const auto& inputs = node.type->inputs;
      auto port_it = std::find_if(inputs.begin(), inputs.end(),
                                  [&](const PortSpec& p) { return p.name == port; });
      if (port_it == inputs.end()) {
        std::vector<std::string> names;
        for (const auto& p : inputs) names.push_back(p.name);
        errors.Add(doc.KeyPositionOf(ip), "stage '" + id + "' (" + uses +
                                              ") has no input port '" + port + "'" +
                                              Suggest(port, names) + " (inputs: " +
                                              JoinNames(names) + ")");
        continue;
      }
      if (!ref.is_string() || rejected(ip) ||
          ref.get<std::string>().find('.') == std::string::npos) {
        rejected_inputs.insert(port);
        continue;
      }
      const std::string text = ref.get<std::string>();
      const size_t dot = text.find('.');
      InputRef input{text.substr(0, dot), text.substr(dot + 1), doc.PositionOf(ip)};
      node.inputs[port] = input;
    }
    for (const PortSpec& p : node.type->inputs)
      if (!p.optional && !node.inputs.count(p.name) && !rejected_inputs.count(p.name))
        errors.Add(node.pos, "stage '" + id + "' (" + uses + ") is missing required input '" +
                                 p.name + "' (" + p.type + "); add `in: { " + p.name +
                                 ": STAGE.PORT }`");
    wf.stages.emplace(id, std::move(node));
  }

  // Edges: sources exist, ports exist, types agree.
  const std::vector<std::string> stage_ids = KeysOf(wf.stages);
  for (auto& [id, node] : wf.stages) {
    std::set<std::string> deps;
    for (auto& [port, input] : node.inputs) {
      auto src = wf.stages.find(input.from_stage);
      if (src == wf.stages.end()) {
        if (disabled.count(input.from_stage)) {
          errors.Add(input.pos, "input '" + port + "' of stage '" + id + "' comes from stage '" +
                                    input.from_stage + "', which its `when:` leaves out; give '" +
                                    id + "' the same `when:`");
          continue;
        }
        // A stage that failed to resolve its type was reported already.
        if (!stages.contains(input.from_stage))
          errors.Add(input.pos, "input '" + port + "' of stage '" + id + "' names unknown stage '" +
                                    input.from_stage + "'" + Suggest(input.from_stage, stage_ids));
        continue;
      }
      const auto& outs = src->second.type->outputs;
      auto out_it = std::find_if(outs.begin(), outs.end(),
                                 [&](const PortSpec& p) { return p.name == input.from_port; });
      if (out_it == outs.end()) {
        std::vector<std::string> names;
        for (const auto& p : outs) names.push_back(p.name);
        errors.Add(input.pos, "stage '" + input.from_stage + "' (" + src->second.type->id +
                                  ") has no output port '" + input.from_port + "'" +
                                  Suggest(input.from_port, names) + " (outputs: " +
                                  JoinNames(names) + ")");
        continue;
      }
      const PortSpec& in_spec = *std::find_if(node.type->inputs.begin(), node.type->inputs.end(),
                                              [&](const PortSpec& p) { return p.name == port; });
      if (in_spec.type != "any" && in_spec.type != out_it->type)
        errors.Add(input.pos, "type mismatch: input '" + port + "' of stage '" + id +
                                  "' takes " + in_spec.type + ", but " + input.from_stage + "." +
                                  input.from_port + " is " + out_it->type);
      deps.insert(input.from_stage);
    }
    node.deps.assign(deps.begin(), deps.end());
  }

  // Outputs.
  if (doc.value.contains("outputs") && doc.value["outputs"].is_object()) {
    for (auto& [name, ref] : doc.value["outputs"].items()) {
      if (!ref.is_string() || rejected("/outputs/" + PointerToken(name)) ||
          ref.get<std::string>().find('.') == std::string::npos)
        continue;  // reported by the schema
      const std::string text = ref.get<std::string>();
      const std::string st = text.substr(0, text.find('.'));
      const std::string port = text.substr(text.find('.') + 1);
      auto it = wf.stages.find(st);
      const SourcePos pos = doc.PositionOf("/outputs/" + PointerToken(name));
      if (disabled.count(st)) continue;  // e.g. ground-truth outputs of a scanned scene
      if (it == wf.stages.end()) {
        if (!stages.contains(st))
          errors.Add(pos, "output '" + name + "' names unknown stage '" + st + "'" +
                              Suggest(st, stage_ids));
        continue;
      }
      const auto& outs = it->second.type->outputs;
      if (std::none_of(outs.begin(), outs.end(), [&](const PortSpec& p) { return p.name == port; })) {
        errors.Add(pos, "output '" + name + "': stage '" + st + "' has no output port '" + port + "'");
        continue;
      }
      wf.outputs[name] = {st, port};
    }
  }

  wf.disabled.assign(disabled.begin(), disabled.end());

  // Topological order (Kahn, ties by name) and cycle detection.
  std::map<std::string, int> indegree;
  for (const auto& [id, node] : wf.stages) indegree[id] = static_cast<int>(node.deps.size());
  std::priority_queue<std::string, std::vector<std::string>, std::greater<>> ready;
  for (const auto& [id, d] : indegree)
    if (d == 0) ready.push(id);
  while (!ready.empty()) {
    std::string id = ready.top();
    ready.pop();
    wf.order.push_back(id);
    for (const std::string& dep : wf.Dependents(id))
      if (--indegree[dep] == 0) ready.push(dep);
  }
  if (wf.order.size() != wf.stages.size()) {
    // Walk upstream from a stage left over until a stage repeats.
    std::string start;
    for (const auto& [id, d] : indegree)
      if (d > 0) {
        start = id;
        break;
      }
    std::vector<std::string> path;
    std::string cur = start;
    while (std::find(path.begin(), path.end(), cur) == path.end()) {
      path.push_back(cur);
      for (const std::string& dep : wf.stages[cur].deps)
        if (indegree[dep] > 0) {
          cur = dep;
          break;
        }
    }
    auto first = std::find(path.begin(), path.end(), cur);
    std::vector<std::string> cycle(first, path.end());
    std::reverse(cycle.begin(), cycle.end());
    std::string text;
    for (const auto& s : cycle) text += s + " -> ";
    text += cycle.front();
    // Report at the input that closes the cycle: cycle.front() feeds cycle[1].
    const StageNode& consumer = wf.stages[cycle.size() > 1 ? cycle[1] : cycle[0]];
    SourcePos pos = consumer.pos;
    for (const auto& [port, input] : consumer.inputs)
      if (input.from_stage == cycle.front()) pos = input.pos;
    errors.Add(pos, "cycle: " + text);
  }
  if (!errors.empty()) return errors.ToStatus();

  // Default outputs: every output of every stage nothing consumes.
  if (!doc.value.contains("outputs")) {
    for (const auto& [id, node] : wf.stages)
      if (wf.Dependents(id).empty())
        for (const PortSpec& p : node.type->outputs)
          wf.outputs[id + "." + p.name] = {id, p.name};
  }
  return wf;
}

Status CheckStageIds(const Workflow& wf, const std::vector<std::string>& ids,
                     const std::string& flag) {
  const std::vector<std::string> known = KeysOf(wf.stages);
  Errors errors;
  for (const std::string& id : ids) {
    if (wf.stages.count(id)) continue;
    if (std::find(wf.disabled.begin(), wf.disabled.end(), id) != wf.disabled.end())
      errors.AddRaw("<command line>: " + flag + " " + id + ": stage '" + id +
                    "' is left out of this run by its `when:`");
    else
      errors.AddRaw("<command line>: " + flag + " " + id + ": no stage '" + id + "' in workflow " +
                    wf.name + Suggest(id, known) + " (stages: " + JoinNames(known) + ")");
  }
  return errors.empty() ? Status::Ok() : errors.ToStatus();
}

Status KeepUpstreamOf(Workflow& wf, const std::vector<std::string>& targets) {
  PB_RETURN_IF_ERROR(CheckStageIds(wf, targets, "--until"));
  std::set<std::string> keep;
  std::vector<std::string> todo(targets.begin(), targets.end());
  while (!todo.empty()) {
    const std::string id = todo.back();
    todo.pop_back();
    if (!keep.insert(id).second) continue;
    for (const std::string& dep : wf.stages.at(id).deps) todo.push_back(dep);
  }
  for (auto it = wf.stages.begin(); it != wf.stages.end();)
    it = keep.count(it->first) ? std::next(it) : wf.stages.erase(it);
  std::vector<std::string> order;
  for (const std::string& id : wf.order)
    if (keep.count(id)) order.push_back(id);
  wf.order = std::move(order);
  for (auto it = wf.outputs.begin(); it != wf.outputs.end();)
    it = keep.count(it->second.first) ? std::next(it) : wf.outputs.erase(it);
  // What the run was cut short for is worth a copy in the output folder.
  for (const std::string& id : targets) {
    const StageNode& node = wf.stages.at(id);
    for (const PortSpec& p : node.type->outputs) {
      const bool named = std::any_of(wf.outputs.begin(), wf.outputs.end(), [&](const auto& o) {
        return o.second == std::pair<std::string, std::string>{id, p.name};
      });
      if (!named && !wf.outputs.count(id + "." + p.name))
        wf.outputs[id + "." + p.name] = {id, p.name};
    }
  }
  return Status::Ok();
}

std::string WorkflowToDot(const Workflow& wf) {
  std::ostringstream out;
  auto quote = [](const std::string& s) {
    std::string q = "\"";
    for (char c : s) {
      if (c == '"') q += '\\';  // labels keep their \n line breaks
      q += c;
    }
    return q + "\"";
  };
  out << "digraph " << quote(wf.name) << " {\n  rankdir=LR;\n  node [shape=box, fontname=\"Helvetica\"];\n";
  for (const std::string& id : wf.order) {
    const StageNode& n = wf.stages.at(id);
    out << "  " << quote(id) << " [label=" << quote(id + "\\n" + n.type->id) << "];\n";
  }
  for (const std::string& id : wf.order)
    for (const auto& [port, in] : wf.stages.at(id).inputs)
      out << "  " << quote(in.from_stage) << " -> " << quote(id)
          << " [label=" << quote(in.from_port + " → " + port) << "];\n";
  out << "}\n";
  return out.str();
}

}  // namespace pb
