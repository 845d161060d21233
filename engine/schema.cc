#include "engine/schema.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <regex>
#include <set>
#include <stdexcept>
#include <string_view>
#include <utility>

// valijson reports failures through exceptions only when this is set before its headers;
// otherwise it prints and aborts. (<stdexcept> above must come first: valijson includes it from
// inside its own namespace.)
#define VALIJSON_USE_EXCEPTIONS 1
#include <valijson/adapters/nlohmann_json_adapter.hpp>
#include <valijson/schema.hpp>
#include <valijson/schema_parser.hpp>
#include <valijson/validation_results.hpp>
#include <valijson/validator.hpp>

#include "base/env.h"
#include "engine/yaml_json.h"

namespace pb {
namespace {

using Json = nlohmann::json;

bool StartsWith(std::string_view s, std::string_view prefix) {
  return s.substr(0, prefix.size()) == prefix;
}

// ---------------------------------------------------------------------------------------------
// Instance navigation.

// The value an error is about, and its JSON pointer. valijson's context is "<root>" followed by
// "[name]" for object members and "[0]" for array items; the two are told apart by looking at
// the instance, since a member may well be called "0".
struct Location {
  std::vector<std::string> tokens;  // unescaped
  std::string pointer;
  const Json* value = nullptr;  // nullptr when the context leaves the instance
};

Location Locate(const std::vector<std::string>& context, const Json& instance) {
  Location loc;
  loc.value = &instance;
  for (size_t i = 0; i < context.size(); ++i) {
    const std::string& part = context[i];
    if (i == 0 && part == "<root>") continue;
    std::string token = part;
    if (token.size() >= 2 && token.front() == '[' && token.back() == ']') {
      token = token.substr(1, token.size() - 2);
    }
    const Json* next = nullptr;
    if (loc.value != nullptr && loc.value->is_array()) {
      char* end = nullptr;
      const unsigned long index = std::strtoul(token.c_str(), &end, 10);
      if (!token.empty() && *end == '\0' && index < loc.value->size()) next = &(*loc.value)[index];
    } else if (loc.value != nullptr && loc.value->is_object()) {
      if (auto it = loc.value->find(token); it != loc.value->end()) next = &*it;
    }
    loc.value = next;
    loc.pointer += "/" + PointerToken(token);
    loc.tokens.push_back(std::move(token));
  }
  return loc;
}

// ---------------------------------------------------------------------------------------------
// Schema navigation: valijson does not say which subschema failed, so the subschemas that apply
// at an instance location are found again here, and the keyword that failed is looked up in
// them to write a precise message.

bool RegexSearch(const std::string& pattern, const std::string& text) {
  try {
    return std::regex_search(text, std::regex(pattern, std::regex::ECMAScript));
  } catch (const std::regex_error&) {
    return false;
  }
}

class SchemaWalker {
 public:
  explicit SchemaWalker(const Json& root) : root_(root) {}

  // All object subschemas applying at `tokens` below the root (through properties,
  // patternProperties, additionalProperties, items, allOf/anyOf/oneOf, if/then/else and local
  // $refs).
  std::vector<const Json*> At(const Json& instance, const std::vector<std::string>& tokens) const {
    std::vector<const Json*> current;
    Expand(root_, 0, &current);
    const Json* value = &instance;
    for (const std::string& token : tokens) {
      std::vector<const Json*> next;
      for (const Json* s : current) {
        for (const Json* child : Children(*s, value, token)) Expand(*child, 0, &next);
      }
      current = std::move(next);
      value = Step(value, token);
    }
    return current;
  }

 private:
  static const Json* Step(const Json* value, const std::string& token) {
    if (value == nullptr) return nullptr;
    if (value->is_object()) {
      auto it = value->find(token);
      return it == value->end() ? nullptr : &*it;
    }
    if (value->is_array()) {
      char* end = nullptr;
      const unsigned long index = std::strtoul(token.c_str(), &end, 10);
      if (!token.empty() && *end == '\0' && index < value->size()) return &(*value)[index];
    }
    return nullptr;
  }

  const Json* ResolveRef(const std::string& ref) const {
    if (ref == "#") return &root_;
    if (!StartsWith(ref, "#/")) return nullptr;  // remote references are not followed
    try {
      return &root_.at(Json::json_pointer(ref.substr(1)));
    } catch (const std::exception&) {
      return nullptr;
    }
  }

  void Expand(const Json& s, int depth, std::vector<const Json*>* out) const {
    if (depth > 32 || !s.is_object()) return;
    if (std::find(out->begin(), out->end(), &s) != out->end()) return;
    out->push_back(&s);
    if (auto ref = s.find("$ref"); ref != s.end() && ref->is_string()) {
      if (const Json* target = ResolveRef(ref->get<std::string>())) Expand(*target, depth + 1, out);
    }
    for (const char* keyword : {"allOf", "anyOf", "oneOf"}) {
      if (auto it = s.find(keyword); it != s.end() && it->is_array()) {
        for (const Json& branch : *it) Expand(branch, depth + 1, out);
      }
    }
    for (const char* keyword : {"then", "else"}) {
      if (auto it = s.find(keyword); it != s.end()) Expand(*it, depth + 1, out);
    }
  }

  static std::vector<const Json*> Children(const Json& s, const Json* parent,
                                           const std::string& token) {
    std::vector<const Json*> out;
    if (parent == nullptr || parent->is_object()) {
      bool matched = false;
      if (auto props = s.find("properties"); props != s.end() && props->is_object()) {
        if (auto it = props->find(token); it != props->end()) {
          out.push_back(&*it);
          matched = true;
        }
      }
      if (auto pats = s.find("patternProperties"); pats != s.end() && pats->is_object()) {
        for (auto it = pats->begin(); it != pats->end(); ++it) {
          if (RegexSearch(it.key(), token)) {
            out.push_back(&it.value());
            matched = true;
          }
        }
      }
      if (!matched) {
        if (auto add = s.find("additionalProperties"); add != s.end() && add->is_object()) {
          out.push_back(&*add);
        }
      }
    }
    if (parent == nullptr || parent->is_array()) {
      char* end = nullptr;
      const unsigned long index = std::strtoul(token.c_str(), &end, 10);
      if (token.empty() || *end != '\0') return out;
      if (auto items = s.find("items"); items != s.end()) {
        if (items->is_object()) {
          out.push_back(&*items);
        } else if (items->is_array()) {
          if (index < items->size()) {
            out.push_back(&(*items)[index]);
          } else if (auto extra = s.find("additionalItems");
                     extra != s.end() && extra->is_object()) {
            out.push_back(&*extra);
          }
        }
      }
    }
    return out;
  }

  const Json& root_;
};

// ---------------------------------------------------------------------------------------------
// Messages.

std::string Show(const Json& v) { return v.dump(-1, ' ', false, Json::error_handler_t::replace); }

// "the string \"abc\"", "the integer 5", ... for "got ..." clauses.
std::string DescribeValue(const Json* v) {
  if (v == nullptr) return "nothing";
  switch (v->type()) {
    case Json::value_t::string:
      return "the string " + Show(*v);
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
      return "the integer " + Show(*v);
    case Json::value_t::number_float:
      return "the number " + Show(*v);
    case Json::value_t::boolean:
      return "the boolean " + Show(*v);
    case Json::value_t::null:
      return "null";
    case Json::value_t::object:
      return "an object";
    case Json::value_t::array:
      return "an array";
    default:
      return Show(*v);
  }
}

std::string TypeNoun(const std::string& type) {
  if (type == "integer") return "an integer";
  if (type == "number") return "a number";
  if (type == "string") return "a string";
  if (type == "boolean") return "a boolean";
  if (type == "object") return "an object";
  if (type == "array") return "an array";
  return type;  // "null"
}

// Mirrors valijson's strict type checks (an integer is a number; 1.0 is not an integer).
bool TypeMatches(const std::string& type, const Json& v) {
  if (type == "integer") return v.is_number_integer();
  if (type == "number") return v.is_number();
  if (type == "string") return v.is_string();
  if (type == "boolean") return v.is_boolean();
  if (type == "object") return v.is_object();
  if (type == "array") return v.is_array();
  if (type == "null") return v.is_null();
  return false;
}

std::vector<std::string> TypesOf(const Json& s) {
  std::vector<std::string> out;
  auto it = s.find("type");
  if (it == s.end()) return out;
  if (it->is_string()) out.push_back(it->get<std::string>());
  if (it->is_array()) {
    for (const Json& t : *it) {
      if (t.is_string()) out.push_back(t.get<std::string>());
    }
  }
  return out;
}

std::string Join(const std::vector<std::string>& parts, std::string_view sep) {
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) {
    if (i > 0) out += sep;
    out += parts[i];
  }
  return out;
}

// The first subschema in `schemas` having `keyword` for which `fails` holds, else the first
// having `keyword` at all.
template <typename Pred>
const Json* FindKeyword(const std::vector<const Json*>& schemas, const char* keyword, Pred fails) {
  const Json* any = nullptr;
  for (const Json* s : schemas) {
    auto it = s->find(keyword);
    if (it == s->end()) continue;
    if (any == nullptr) any = &*it;
    if (fails(*it, *s)) return &*it;
  }
  return any;
}

std::optional<std::string> TypeMessage(const std::vector<const Json*>& schemas, const Json* v) {
  std::vector<std::string> expected;
  for (const Json* s : schemas) {
    const std::vector<std::string> types = TypesOf(*s);
    if (types.empty()) continue;
    const bool ok = v != nullptr && std::any_of(types.begin(), types.end(),
                                                [&](const auto& t) { return TypeMatches(t, *v); });
    if (ok) continue;
    for (const std::string& t : types) {
      if (std::find(expected.begin(), expected.end(), t) == expected.end()) expected.push_back(t);
    }
  }
  if (expected.empty()) return std::nullopt;
  std::vector<std::string> nouns;
  for (const std::string& t : expected) nouns.push_back(TypeNoun(t));
  return "expected " + Join(nouns, " or ") + ", got " + DescribeValue(v);
}

bool Less(const Json& a, const Json& b) { return a.get<double>() < b.get<double>(); }

std::optional<std::string> BoundMessage(const std::vector<const Json*>& schemas, const Json* v,
                                        bool lower) {
  if (v == nullptr || !v->is_number()) return std::nullopt;
  const char* inclusive_kw = lower ? "minimum" : "maximum";
  const char* exclusive_kw = lower ? "exclusiveMinimum" : "exclusiveMaximum";
  for (const Json* s : schemas) {
    auto bound = s->find(inclusive_kw);
    auto exclusive = s->find(exclusive_kw);
    // Draft 7: exclusiveMinimum is a number.
    if (exclusive != s->end() && exclusive->is_number()) {
      const bool fails = lower ? !Less(*exclusive, *v) : !Less(*v, *exclusive);
      if (fails) {
        return std::string("must be ") + (lower ? "> " : "< ") + Show(*exclusive) + ", got " +
               Show(*v);
      }
    }
    if (bound != s->end() && bound->is_number()) {
      // Draft 4: exclusiveMinimum: true qualifies minimum.
      const bool strict =
          exclusive != s->end() && exclusive->is_boolean() && exclusive->get<bool>();
      const bool fails = lower ? (strict ? !Less(*bound, *v) : Less(*v, *bound))
                               : (strict ? !Less(*v, *bound) : Less(*bound, *v));
      if (fails) {
        return std::string("must be ") +
               (lower ? (strict ? "> " : ">= ") : (strict ? "< " : "<= ")) + Show(*bound) +
               ", got " + Show(*v);
      }
    }
  }
  return std::nullopt;
}

size_t Utf8Length(const std::string& s) {
  size_t n = 0;
  for (unsigned char c : s) n += (c & 0xC0) != 0x80;
  return n;
}

std::string Plural(const Json& n, const char* noun) {
  return Show(n) + " " + noun + (n == 1 ? "" : "s");
}

std::optional<std::string> SizeMessage(const std::vector<const Json*>& schemas, const Json* v,
                                       const char* keyword) {
  if (v == nullptr) return std::nullopt;
  const std::string kw = keyword;
  const bool at_least = StartsWith(kw, "min");
  size_t actual = 0;
  const char* noun = "";
  if (kw == "minItems" || kw == "maxItems") {
    if (!v->is_array()) return std::nullopt;
    actual = v->size();
    noun = "item";
  } else if (kw == "minProperties" || kw == "maxProperties") {
    if (!v->is_object()) return std::nullopt;
    actual = v->size();
    noun = "key";
  } else {
    if (!v->is_string()) return std::nullopt;
    actual = Utf8Length(v->get<std::string>());
    noun = "character";
  }
  const Json* limit = FindKeyword(schemas, keyword, [&](const Json& k, const Json&) {
    if (!k.is_number_unsigned() && !k.is_number_integer()) return false;
    const auto n = k.get<int64_t>();
    return at_least ? static_cast<int64_t>(actual) < n : static_cast<int64_t>(actual) > n;
  });
  if (limit == nullptr || !limit->is_number()) return std::nullopt;
  const std::string bound = at_least ? "at least " : "at most ";
  if (v->is_string()) {
    return "must be " + bound + Plural(*limit, noun) + " long, got " + Show(*v);
  }
  return "must have " + bound + Plural(*limit, noun) + ", got " + std::to_string(actual);
}

std::string EnumList(const Json& values) {
  std::vector<std::string> parts;
  for (const Json& e : values) parts.push_back(e.is_string() ? e.get<std::string>() : Show(e));
  return Join(parts, ", ");
}

// The key named in a valijson description such as "Missing required property 'uses'.".
std::string QuotedName(const std::string& description) {
  const size_t open = description.find('\'');
  const size_t close = description.rfind('\'');
  if (open == std::string::npos || close <= open) return "";
  return description.substr(open + 1, close - open - 1);
}

bool IsWrapper(const std::string& description) {
  // Reported when several oneOf branches match: nothing beneath it explains it.
  if (description == "Failed to validate against exactly one child schema.") return false;
  return StartsWith(description, "Failed to validate") ||
         StartsWith(description, "Cannot validate item #");
}

class MessageBuilder {
 public:
  MessageBuilder(const Json& schema, const Json& instance) : walker_(schema), instance_(instance) {}

  // Rewrites one specific valijson error into user-facing errors (usually one; an unknown-key
  // error names every unknown key, not just the first one valijson saw).
  std::vector<SchemaError> Rewrite(const Location& loc, const std::string& description) const {
    const std::vector<const Json*> schemas = walker_.At(instance_, loc.tokens);
    const Json* v = loc.value;
    auto one = [&](std::optional<std::string> message) {
      return std::vector<SchemaError>{{loc.pointer, message ? *message : description}};
    };

    if (StartsWith(description, "Value type not permitted")) return one(TypeMessage(schemas, v));
    if (StartsWith(description, "Missing required property")) {
      return one("missing required key '" + QuotedName(description) + "'");
    }
    if (StartsWith(description, "Object contains a property that could not be validated")) {
      return UnknownKeys(loc, schemas, QuotedName(description));
    }
    if (StartsWith(description, "Expected number greater than")) {
      return one(BoundMessage(schemas, v, /*lower=*/true));
    }
    if (StartsWith(description, "Expected number less than")) {
      return one(BoundMessage(schemas, v, /*lower=*/false));
    }
    if (StartsWith(description, "Failed to match against any enum values") && v != nullptr) {
      const Json* values = FindKeyword(schemas, "enum", [&](const Json& e, const Json&) {
        return e.is_array() && std::find(e.begin(), e.end(), *v) == e.end();
      });
      if (values != nullptr && values->is_array()) {
        return one("must be one of: " + EnumList(*values) + ", got " + Show(*v));
      }
    }
    if (StartsWith(description, "Failed to match expected value set by 'const'") && v != nullptr) {
      const Json* c =
          FindKeyword(schemas, "const", [&](const Json& k, const Json&) { return k != *v; });
      if (c != nullptr) return one("must be " + Show(*c) + ", got " + Show(*v));
    }
    if (StartsWith(description, "Failed to match regex specified by 'pattern'") && v != nullptr &&
        v->is_string()) {
      const Json* p = FindKeyword(schemas, "pattern", [&](const Json& k, const Json&) {
        return k.is_string() && !RegexSearch(k.get<std::string>(), v->get<std::string>());
      });
      if (p != nullptr && p->is_string()) {
        return one("must match pattern " + p->get<std::string>() + ", got " + Show(*v));
      }
    }
    static const std::pair<const char*, const char*> kSizes[] = {
        {"Array should contain no fewer than", "minItems"},
        {"Array should contain no more than", "maxItems"},
        {"String should be no fewer than", "minLength"},
        {"String should be no more than", "maxLength"},
        {"Object should have no fewer than", "minProperties"},
        {"Object should have no more than", "maxProperties"},
    };
    for (const auto& [prefix, keyword] : kSizes) {
      if (StartsWith(description, prefix)) return one(SizeMessage(schemas, v, keyword));
    }
    if (StartsWith(description, "Value should be a multiple of") && v != nullptr) {
      const Json* m =
          FindKeyword(schemas, "multipleOf", [](const Json&, const Json&) { return true; });
      if (m != nullptr) return one("must be a multiple of " + Show(*m) + ", got " + Show(*v));
    }
    if (StartsWith(description, "Array contains more items than allowed") && v != nullptr &&
        v->is_array()) {
      const Json* items = FindKeyword(schemas, "items", [&](const Json& k, const Json& s) {
        auto extra = s.find("additionalItems");
        return k.is_array() && k.size() < v->size() && extra != s.end() && *extra == false;
      });
      if (items != nullptr && items->is_array()) {
        return one("must have at most " + Plural(Json(items->size()), "item") + ", got " +
                   std::to_string(v->size()));
      }
    }
    if (description == "Failed to validate against exactly one child schema.") {
      return one("must match exactly one of the schemas in 'oneOf', but matches several");
    }
    if (StartsWith(description, "String should be a valid") && v != nullptr) {
      return one("must be a valid " + description.substr(std::strlen("String should be a valid ")) +
                 ", got " + Show(*v));
    }
    return one(std::nullopt);
  }

 private:
  std::vector<SchemaError> UnknownKeys(const Location& loc, const std::vector<const Json*>& schemas,
                                       const std::string& reported) const {
    std::vector<SchemaError> out;
    const Json* object = loc.value;
    for (const Json* s : schemas) {
      auto add = s->find("additionalProperties");
      if (add == s->end() || !add->is_boolean() || add->get<bool>()) continue;
      if (object == nullptr || !object->is_object()) break;
      std::vector<std::string> allowed;
      if (auto props = s->find("properties"); props != s->end() && props->is_object()) {
        for (auto it = props->begin(); it != props->end(); ++it) allowed.push_back(it.key());
      }
      std::sort(allowed.begin(), allowed.end());
      const auto pats = s->find("patternProperties");
      std::vector<std::string> patterns;
      if (pats != s->end() && pats->is_object()) {
        for (auto p = pats->begin(); p != pats->end(); ++p) patterns.push_back(p.key());
      }
      for (auto it = object->begin(); it != object->end(); ++it) {
        const std::string& key = it.key();
        if (std::binary_search(allowed.begin(), allowed.end(), key)) continue;
        bool by_pattern = false;
        if (pats != s->end() && pats->is_object()) {
          for (auto p = pats->begin(); p != pats->end() && !by_pattern; ++p) {
            by_pattern = RegexSearch(p.key(), key);
          }
        }
        if (by_pattern) continue;
        out.push_back(
            {loc.pointer + "/" + PointerToken(key), UnknownKeyMessage(key, allowed, patterns), true});
      }
      if (!out.empty()) return out;
    }
    out.push_back({loc.pointer + "/" + PointerToken(reported), UnknownKeyMessage(reported, {}), true});
    return out;
  }

  static std::string UnknownKeyMessage(const std::string& key,
                                       const std::vector<std::string>& allowed,
                                       const std::vector<std::string>& patterns = {}) {
    if (allowed.empty() && !patterns.empty()) {
      return "unknown key '" + key + "' (keys must match: " + Join(patterns, ", ") + ")";
    }
    if (allowed.empty()) return "unknown key '" + key + "'";
    return "unknown key '" + key + "' (expected one of: " + Join(allowed, ", ") + ")";
  }

  SchemaWalker walker_;
  const Json& instance_;
};

bool IsAtOrBelow(const std::string& pointer, const std::string& ancestor) {
  return pointer == ancestor ||
         (StartsWith(pointer, ancestor) && pointer.size() > ancestor.size() &&
          pointer[ancestor.size()] == '/');
}

}  // namespace

namespace {

// valijson compiles "pattern"/"patternProperties" regexes only while validating, where a bad one
// would surface as a confusing error about the user's input; catch them when loading instead.
std::optional<std::string> FindBadPattern(const Json& schema) {
  if (schema.is_array()) {
    for (const Json& item : schema) {
      if (auto bad = FindBadPattern(item)) return bad;
    }
    return std::nullopt;
  }
  if (!schema.is_object()) return std::nullopt;
  auto check = [](const std::string& pattern) -> std::optional<std::string> {
    try {
      std::regex re(pattern, std::regex::ECMAScript);
    } catch (const std::regex_error& e) {
      return "pattern '" + pattern + "': " + e.what();
    }
    return std::nullopt;
  };
  if (auto p = schema.find("pattern"); p != schema.end() && p->is_string()) {
    if (auto bad = check(p->get<std::string>())) return bad;
  }
  if (auto pats = schema.find("patternProperties"); pats != schema.end() && pats->is_object()) {
    for (auto it = pats->begin(); it != pats->end(); ++it) {
      if (auto bad = check(it.key())) return bad;
    }
  }
  for (auto it = schema.begin(); it != schema.end(); ++it) {
    // Data, not subschemas.
    if (it.key() == "enum" || it.key() == "const" || it.key() == "default" ||
        it.key() == "examples") {
      continue;
    }
    if (auto bad = FindBadPattern(it.value())) return bad;
  }
  return std::nullopt;
}

}  // namespace

Expected<JsonSchema> JsonSchema::Parse(const nlohmann::json& schema, const std::string& name) {
  if (auto bad = FindBadPattern(schema)) return Status::Invalid(name + ": invalid schema: " + *bad);
  JsonSchema out;
  try {
    auto parsed = std::make_shared<valijson::Schema>();
    valijson::SchemaParser parser(valijson::SchemaParser::kDraft7);
    valijson::adapters::NlohmannJsonAdapter adapter(schema);
    parser.populateSchema(adapter, *parsed);
    out.schema_ = std::move(parsed);
  } catch (const std::exception& e) {
    return Status::Invalid(name + ": invalid schema: " + e.what());
  }
  out.schema_json_ = schema;
  return out;
}

Expected<JsonSchema> JsonSchema::ParseFile(const std::string& path) {
  PB_ASSIGN_OR_RETURN(std::string text, Env::Default()->ReadFile(path));
  nlohmann::json schema;
  try {
    schema = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    // what() is "[json.exception.parse_error.101] parse error at line 3, column 5: ..."; the
    // bracketed id means nothing to a user.
    std::string what = e.what();
    if (!what.empty() && what[0] == '[') {
      if (const size_t end = what.find("] "); end != std::string::npos) what.erase(0, end + 2);
    }
    return Status::Invalid(path + ": invalid JSON: " + what);
  }
  return Parse(schema, path);
}

namespace {

// valijson reports a `propertyNames` failure only as a generic wrapper error at
// the enclosing object, so keys are checked here against "propertyNames":
// {"pattern": ...}, following "properties" and "additionalProperties".
void CheckPropertyNames(const Json& schema, const Json& instance, const std::string& pointer,
                        std::vector<SchemaError>& out) {
  if (!schema.is_object() || !instance.is_object()) return;
  if (auto names = schema.find("propertyNames"); names != schema.end() && names->is_object()) {
    if (auto pattern = names->find("pattern"); pattern != names->end() && pattern->is_string()) {
      for (const auto& [key, value] : instance.items())
        if (!RegexSearch(pattern->get<std::string>(), key))
          out.push_back({pointer + "/" + PointerToken(key),
                         "bad key '" + key + "': must match pattern " + pattern->get<std::string>(), true});
    }
  }
  const auto props = schema.find("properties");
  const auto extra = schema.find("additionalProperties");
  for (const auto& [key, value] : instance.items()) {
    const std::string child = pointer + "/" + PointerToken(key);
    if (props != schema.end() && props->is_object() && props->contains(key))
      CheckPropertyNames((*props)[key], value, child, out);
    else if (extra != schema.end() && extra->is_object())
      CheckPropertyNames(*extra, value, child, out);
  }
}

}  // namespace

std::vector<SchemaError> JsonSchema::Validate(const nlohmann::json& instance) const {
  if (schema_ == nullptr) return {};
  const auto* schema = static_cast<const valijson::Schema*>(schema_.get());
  valijson::ValidationResults results;
  try {
    valijson::Validator validator(valijson::Validator::kStrongTypes);
    valijson::adapters::NlohmannJsonAdapter target(instance);
    if (validator.validate(*schema, target, &results)) return {};
  } catch (const std::exception& e) {
    // E.g. a "pattern" std::regex cannot compile; that is the schema's fault, not the input's.
    return {{"", std::string("schema error: ") + e.what()}};
  }

  struct Raw {
    Location loc;
    std::string description;
    bool wrapper;
  };
  std::vector<Raw> raw;
  for (const valijson::ValidationResults::Error& error : results) {
    raw.push_back(
        {Locate(error.context, instance), error.description, IsWrapper(error.description)});
  }

  std::vector<SchemaError> name_errors;
  CheckPropertyNames(schema_json_, instance, "", name_errors);
  for (const SchemaError& e : name_errors) {
    Location loc;
    loc.pointer = e.pointer;
    raw.push_back({loc, e.message, false});
  }

  MessageBuilder builder(schema_json_, instance);
  std::vector<SchemaError> out;
  std::set<std::pair<std::string, std::string>> seen;
  for (const SchemaError& e : name_errors)
    if (seen.emplace(e.pointer, e.message).second) out.push_back(e);
  for (const Raw& r : raw) {
    if (r.wrapper) {
      // "Failed to validate against schema associated with property name 'x'." only says that
      // something below failed; keep it only if nothing more specific was reported there.
      const bool covered = std::any_of(raw.begin(), raw.end(), [&](const Raw& other) {
        return !other.wrapper && IsAtOrBelow(other.loc.pointer, r.loc.pointer);
      });
      if (covered) continue;
      if (seen.emplace(r.loc.pointer, r.description).second) {
        out.push_back({r.loc.pointer, r.description});
      }
      continue;
    }
    for (SchemaError& e : builder.Rewrite(r.loc, r.description)) {
      if (seen.emplace(e.pointer, e.message).second) out.push_back(std::move(e));
    }
  }
  return out;
}

nlohmann::json ApplyDefaults(const nlohmann::json& schema, nlohmann::json instance) {
  if (!instance.is_object() || !schema.is_object()) return instance;
  auto props = schema.find("properties");
  if (props == schema.end() || !props->is_object()) return instance;
  for (auto it = props->begin(); it != props->end(); ++it) {
    const nlohmann::json& sub = it.value();
    if (!sub.is_object()) continue;
    auto member = instance.find(it.key());
    if (member == instance.end()) {
      if (auto def = sub.find("default"); def != sub.end()) instance[it.key()] = *def;
      continue;
    }
    if (member->is_object() && sub.contains("properties")) {
      *member = ApplyDefaults(sub, std::move(*member));
    }
  }
  return instance;
}

}  // namespace pb
