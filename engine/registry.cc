#include "engine/registry.h"

#include <dlfcn.h>

#include <algorithm>
#include <regex>
#include <sstream>

namespace pb {
namespace {

bool KnownArtifactType(const std::string& type) {
  return std::find(std::begin(kArtifactTypes), std::end(kArtifactTypes), type) !=
         std::end(kArtifactTypes);
}

Status CheckPorts(const StageType& type, const std::vector<PortSpec>& ports, const char* kind) {
  static const std::regex kPortName("^[A-Za-z][A-Za-z0-9_]*$");
  std::vector<std::string> seen;
  for (const PortSpec& port : ports) {
    if (!std::regex_match(port.name, kPortName))
      return Status::Invalid("stage type '" + type.id + "': bad " + kind + " port name '" +
                             port.name + "'");
    if (!KnownArtifactType(port.type))
      return Status::Invalid("stage type '" + type.id + "': " + kind + " port '" + port.name +
                             "' has unknown artifact type '" + port.type + "'");
    if (std::find(seen.begin(), seen.end(), port.name) != seen.end())
      return Status::Invalid("stage type '" + type.id + "': duplicate " + kind + " port '" +
                             port.name + "'");
    seen.push_back(port.name);
  }
  return Status::Ok();
}

}  // namespace

Status Registry::Register(StageType type) {
  static const std::regex kId("^[a-z][a-z0-9_]*\\.[a-z][a-z0-9_]*$");
  Status st;
  if (!std::regex_match(type.id, kId)) {
    st = Status::Invalid("stage type id '" + type.id + "' must look like family.name");
  } else if (entries_.count(type.id)) {
    st = Status::Invalid("stage type '" + type.id + "' is registered twice");
  } else if (!type.run) {
    st = Status::Invalid("stage type '" + type.id + "' has no run function");
  } else if (type.version < 1) {
    st = Status::Invalid("stage type '" + type.id + "' needs version >= 1");
  }
  if (st.ok()) st = CheckPorts(type, type.inputs, "input");
  if (st.ok()) st = CheckPorts(type, type.outputs, "output");
  nlohmann::json schema_json;
  if (st.ok()) {
    schema_json = nlohmann::json::parse(type.params_schema, nullptr, false);
    if (schema_json.is_discarded() || !schema_json.is_object() ||
        schema_json.value("type", "") != "object")
      st = Status::Invalid("stage type '" + type.id +
                           "': params_schema must be a JSON object schema with \"type\": \"object\"");
  }
  Expected<JsonSchema> schema = Status::Internal("unset");
  if (st.ok()) {
    schema = JsonSchema::Parse(schema_json, "params schema of " + type.id);
    if (!schema.ok()) st = schema.status();
  }
  if (!st.ok()) {
    errors_.push_back(st.message());
    return st;
  }
  const std::string id = type.id;
  entries_[id] = std::make_unique<Entry>(Entry{std::move(type), std::move(schema).value()});
  return Status::Ok();
}

const StageType* Registry::Find(std::string_view id) const {
  auto it = entries_.find(id);
  return it == entries_.end() ? nullptr : &it->second->type;
}

std::vector<const StageType*> Registry::All() const {
  std::vector<const StageType*> out;
  for (const auto& [id, entry] : entries_) out.push_back(&entry->type);
  return out;
}

const JsonSchema& Registry::ParamsSchema(std::string_view id) const {
  auto it = entries_.find(id);
  assert(it != entries_.end());
  return it->second->schema;
}

std::vector<std::string> Registry::TakeErrors() {
  std::vector<std::string> out;
  out.swap(errors_);
  return out;
}

Status Registry::LoadPlugin(const std::string& path) {
  if (std::find(loaded_plugins_.begin(), loaded_plugins_.end(), path) != loaded_plugins_.end())
    return Status::Ok();
  // RTLD_NODELETE: stage functions stay callable after the handle is dropped.
  void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  if (!handle) return Status::NotFound(std::string("cannot load plugin: ") + ::dlerror());
  using AbiFn = int (*)();
  using RegisterFn = void (*)(StageRegistry*);
  auto abi = reinterpret_cast<AbiFn>(::dlsym(handle, "pointbake_plugin_abi"));
  auto reg = reinterpret_cast<RegisterFn>(::dlsym(handle, "pointbake_register_stages"));
  if (!abi || !reg)
    return Status::Invalid(path +
                           ": not a pointbake plugin (missing pointbake_plugin_abi or "
                           "pointbake_register_stages)");
  if (abi() != kPluginAbi)
    return Status::Invalid(path + ": plugin ABI " + std::to_string(abi()) + ", this pointbake has " +
                           std::to_string(kPluginAbi) + "; rebuild the plugin");
  TakeErrors();
  reg(this);
  std::vector<std::string> errors = TakeErrors();
  loaded_plugins_.push_back(path);
  if (!errors.empty()) {
    std::string msg = path + ": plugin registration failed:";
    for (const auto& e : errors) msg += "\n  " + e;
    return Status::Invalid(msg);
  }
  return Status::Ok();
}

namespace {

using OrderedJson = nlohmann::ordered_json;

// A YAML-ish rendering of a value: plain words bare, other strings quoted,
// lists and mappings in flow style.
std::string YamlValue(const OrderedJson& v) {
  if (v.is_string()) {
    const std::string text = v.get<std::string>();
    static const std::regex plain("^[A-Za-z_/][A-Za-z0-9_./-]*$");
    static const std::regex reserved("^(true|false|yes|no|on|off|null|~)$", std::regex::icase);
    if (std::regex_match(text, plain) && !std::regex_match(text, reserved)) return text;
    return v.dump();
  }
  if (v.is_array()) {
    std::string out = "[";
    for (size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + YamlValue(v[i]);
    return out + "]";
  }
  if (v.is_object()) {
    std::string out = "{";
    bool first = true;
    for (const auto& [k, x] : v.items()) {
      out += (first ? "" : ", ") + k + ": " + YamlValue(x);
      first = false;
    }
    return out + "}";
  }
  return v.dump();
}

// "number", "integer or null", "array of number", "one of: a, b".
std::string TypeText(const OrderedJson& prop) {
  if (prop.contains("enum")) {
    std::string out = "one of: ";
    for (size_t i = 0; i < prop["enum"].size(); ++i)
      out += (i ? ", " : "") + YamlValue(prop["enum"][i]);
    return out;
  }
  std::string out;
  if (prop.contains("type")) {
    const OrderedJson& t = prop["type"];
    if (t.is_string()) {
      out = t.get<std::string>();
    } else if (t.is_array()) {
      for (size_t i = 0; i < t.size(); ++i) out += (i ? " or " : "") + YamlValue(t[i]);
    }
  } else if (prop.contains("oneOf") || prop.contains("anyOf")) {
    const OrderedJson& alts = prop.contains("oneOf") ? prop["oneOf"] : prop["anyOf"];
    for (size_t i = 0; i < alts.size(); ++i) out += (i ? " or " : "") + TypeText(alts[i]);
  } else {
    out = "any";
  }
  if (out == "array" && prop.contains("items") && prop["items"].is_object())
    out += " of " + TypeText(prop["items"]);
  return out;
}

// "> 0", ">= 1, <= 16": the bounds a number must keep.
std::string BoundsText(const OrderedJson& prop) {
  std::string out;
  for (const auto& [key, sign] : {std::pair{"exclusiveMinimum", ">"}, std::pair{"minimum", ">="},
                                  std::pair{"exclusiveMaximum", "<"}, std::pair{"maximum", "<="}})
    if (prop.contains(key) && prop[key].is_number())
      out += std::string(out.empty() ? "" : ", ") + sign + " " + prop[key].dump();
  return out;
}

}  // namespace

std::string DescribeStage(const StageType& type) {
  std::ostringstream out;
  out << type.id << "  (version " << type.version << ")\n  " << type.summary << "\n";
  if (!type.doc.empty()) out << "\n" << type.doc << "\n";
  auto ports = [&](const char* title, const std::vector<PortSpec>& list) {
    out << "\n" << title << ":\n";
    if (list.empty()) out << "  (none)\n";
    for (const auto& p : list)
      out << "  " << p.name << " : " << p.type << (p.optional ? " (optional)" : "")
          << (p.doc.empty() ? "" : "  — " + p.doc) << "\n";
  };
  ports("inputs", type.inputs);
  ports("outputs", type.outputs);
  // Parameters in a stable order: the required ones, then the others, each
  // in the order the stage's schema declares them (ordered_json keeps it).
  const OrderedJson schema = OrderedJson::parse(type.params_schema, nullptr, false);
  std::vector<std::string> required;
  if (schema.is_object() && schema.contains("required") && schema["required"].is_array())
    for (const auto& r : schema["required"]) required.push_back(r.get<std::string>());
  const OrderedJson properties = schema.is_object() && schema.contains("properties")
                                     ? schema["properties"]
                                     : OrderedJson::object();
  auto is_required = [&](const std::string& name) {
    return std::find(required.begin(), required.end(), name) != required.end();
  };
  std::vector<std::string> names;
  for (const auto& [name, prop] : properties.items())
    if (is_required(name)) names.push_back(name);
  for (const auto& [name, prop] : properties.items())
    if (!is_required(name)) names.push_back(name);

  out << "\nparameters:\n";
  if (names.empty()) out << "  (none)\n";
  for (const std::string& name : names) {
    const OrderedJson& prop = properties[name];
    out << "  " << name << " : " << TypeText(prop);
    if (const std::string bounds = BoundsText(prop); !bounds.empty()) out << " (" << bounds << ")";
    if (is_required(name)) out << "  required";
    if (prop.contains("default")) out << "  default " << YamlValue(prop["default"]);
    if (prop.value("x-path", false)) out << "  [a file path; its content enters the cache key]";
    if (!prop.value("x-affects-output", true)) out << "  [not in the cache key]";
    out << "\n";
    if (prop.contains("description") && prop["description"].is_string())
      out << "      " << prop["description"].get<std::string>() << "\n";
  }

  // A stage of this type in a workflow, with every parameter at its default.
  out << "\nin a workflow:\n  my_" << type.id.substr(type.id.find('.') + 1)
      << ":\n    uses: " << type.id << "\n";
  if (!type.inputs.empty()) {
    out << "    in:\n";
    for (const auto& p : type.inputs)
      out << "      " << p.name << ": STAGE.PORT   # " << p.type << (p.optional ? ", optional" : "")
          << "\n";
  }
  if (!names.empty()) {
    out << "    with:\n";
    for (const std::string& name : names) {
      const OrderedJson& prop = properties[name];
      if (prop.contains("default"))
        out << "      " << name << ": " << YamlValue(prop["default"]) << "\n";
      else
        out << "      " << name << ": <" << TypeText(prop) << ">   # required\n";
    }
  }
  return out.str();
}

}  // namespace pb
