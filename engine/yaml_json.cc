#include "engine/yaml_json.h"

#include <yaml-cpp/yaml.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <optional>
#include <regex>
#include <utility>
#include <vector>

#include "base/env.h"

namespace pb {
namespace {

using Json = nlohmann::json;

// Guards against alias cycles (`&a [*a]` makes yaml-cpp build a cyclic graph) and against
// "billion laughs" style alias expansion, both of which would otherwise exhaust the stack or
// memory while converting.
constexpr int kMaxDepth = 256;
constexpr size_t kMaxValues = 2'000'000;

// A conversion failure with the place it happened (yaml-cpp marks are 0-based; -1 = unknown).
struct ConvertError {
  YAML::Mark mark;
  std::string message;
};

bool IsNullWord(std::string_view s) {
  return s.empty() || s == "~" || s == "null" || s == "Null" || s == "NULL";
}

std::optional<bool> BoolWord(std::string_view s) {
  if (s == "true" || s == "True" || s == "TRUE") return true;
  if (s == "false" || s == "False" || s == "FALSE") return false;
  return std::nullopt;
}

bool AllDigits(std::string_view s, int base) {
  if (s.empty()) return false;
  for (char c : s) {
    const bool ok = base == 16  ? std::isxdigit(static_cast<unsigned char>(c)) != 0
                    : base == 8 ? (c >= '0' && c <= '7')
                                : (c >= '0' && c <= '9');
    if (!ok) return false;
  }
  return true;
}

// YAML 1.2 core schema integers: [-+]?[0-9]+, 0o[0-7]+, 0x[0-9a-fA-F]+. A decimal that does
// not fit int64 becomes a double (so a schema asking for an integer still rejects it rather
// than seeing a silently truncated value); an oversized hex/octal literal is not an integer.
std::optional<Json> IntegerWord(std::string_view s) {
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'o')) {
    const int base = s[1] == 'x' ? 16 : 8;
    const std::string_view digits = s.substr(2);
    if (!AllDigits(digits, base)) return std::nullopt;
    errno = 0;
    const std::string buf(digits);
    const long long v = std::strtoll(buf.c_str(), nullptr, base);
    if (errno == ERANGE) return std::nullopt;
    return Json(static_cast<int64_t>(v));
  }
  std::string_view digits = s;
  if (!digits.empty() && (digits[0] == '-' || digits[0] == '+')) digits.remove_prefix(1);
  if (!AllDigits(digits, 10)) return std::nullopt;
  const std::string buf(s);
  errno = 0;
  const long long v = std::strtoll(buf.c_str(), nullptr, 10);
  if (errno == ERANGE) return Json(std::strtod(buf.c_str(), nullptr));
  return Json(static_cast<int64_t>(v));
}

std::optional<Json> FloatWord(std::string_view s) {
  static const std::regex kFloat(R"([-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?)");
  static const std::regex kInf(R"([-+]?\.(inf|Inf|INF))");
  static const std::regex kNan(R"(\.(nan|NaN|NAN))");
  const std::string buf(s);
  if (std::regex_match(buf, kFloat)) return Json(std::strtod(buf.c_str(), nullptr));
  if (std::regex_match(buf, kInf)) {
    const double inf = std::numeric_limits<double>::infinity();
    return Json(buf[0] == '-' ? -inf : inf);
  }
  if (std::regex_match(buf, kNan)) return Json(std::numeric_limits<double>::quiet_NaN());
  return std::nullopt;
}

// Types a plain (untagged, unquoted) scalar by the YAML 1.2 core schema.
Json TypePlain(const std::string& s) {
  if (IsNullWord(s)) return Json(nullptr);
  if (auto b = BoolWord(s)) return Json(*b);
  if (auto i = IntegerWord(s)) return *i;
  if (auto f = FloatWord(s)) return *f;
  return Json(s);
}

constexpr std::string_view kTagPrefix = "tag:yaml.org,2002:";

class Converter {
 public:
  Converter(std::string_view text, std::map<std::string, SourcePos>* positions, std::string file)
      : text_(text), positions_(positions), file_(std::move(file)) {}

  std::optional<ConvertError> Convert(const YAML::Node& node, const std::string& pointer,
                                      Json* out) {
    stack_.clear();
    return ConvertNode(node, pointer, std::nullopt, out);
  }

 private:
  void Record(const std::string& key, const YAML::Mark& mark) {
    if (positions_ == nullptr || mark.is_null() || mark.line < 0) return;
    (*positions_)[key] = SourcePos{file_, mark.line + 1, mark.column + 1};
  }

  // yaml-cpp gives an empty value (`key:` with nothing after it) the mark of the next token,
  // which is usually the next key; detect that from the source text so the null value is
  // placed at its key instead.
  bool IsExplicitNull(const YAML::Mark& mark) const {
    if (mark.is_null() || mark.pos < 0 || static_cast<size_t>(mark.pos) >= text_.size()) {
      return false;
    }
    const std::string_view rest = text_.substr(static_cast<size_t>(mark.pos));
    for (std::string_view word : {"~", "null", "Null", "NULL", "!", "&", "*"}) {
      if (rest.substr(0, word.size()) == word) return true;
    }
    return false;
  }

  std::optional<ConvertError> ConvertScalar(const YAML::Node& node, Json* out) {
    const std::string& tag = node.Tag();
    const std::string& s = node.Scalar();
    if (!IsValidUtf8(s)) return ConvertError{node.Mark(), "text is not valid UTF-8 (save the file as UTF-8)"};
    if (tag == "?") {
      *out = TypePlain(s);
      return std::nullopt;
    }
    if (tag.rfind(kTagPrefix, 0) == 0) {
      const std::string_view kind = std::string_view(tag).substr(kTagPrefix.size());
      std::optional<Json> typed;
      if (kind == "str") {
        typed = Json(s);
      } else if (kind == "int") {
        typed = IntegerWord(s);
      } else if (kind == "float") {
        typed = FloatWord(s);
        if (!typed) {
          if (auto i = IntegerWord(s)) typed = Json(i->get<double>());
        }
      } else if (kind == "bool") {
        if (auto b = BoolWord(s)) typed = Json(*b);
      } else if (kind == "null") {
        if (IsNullWord(s)) typed = Json(nullptr);
      } else {
        return ConvertError{node.Mark(), "unsupported tag '!!" + std::string(kind) + "'"};
      }
      if (!typed) {
        return ConvertError{node.Mark(), "invalid !!" + std::string(kind) + " value '" + s + "'"};
      }
      *out = std::move(*typed);
      return std::nullopt;
    }
    // "!" (quoted or non-specific) and local tags: the text itself.
    *out = Json(s);
    return std::nullopt;
  }

  std::optional<ConvertError> ConvertNode(const YAML::Node& node, const std::string& pointer,
                                          std::optional<YAML::Mark> fallback_mark, Json* out) {
    if (++values_ > kMaxValues) {
      return ConvertError{node.Mark(), "document too large (after expanding aliases)"};
    }
    if (stack_.size() >= static_cast<size_t>(kMaxDepth)) {
      return ConvertError{node.Mark(), "nesting too deep"};
    }
    for (const YAML::Node& open : stack_) {
      if (open.is(node)) return ConvertError{node.Mark(), "recursive alias"};
    }

    YAML::Mark mark = node.Mark();
    if (node.IsNull() && fallback_mark && !IsExplicitNull(mark)) mark = *fallback_mark;
    Record(pointer, mark);

    switch (node.Type()) {
      case YAML::NodeType::Undefined:
      case YAML::NodeType::Null:
        *out = Json(nullptr);
        return std::nullopt;
      case YAML::NodeType::Scalar:
        return ConvertScalar(node, out);
      case YAML::NodeType::Sequence: {
        *out = Json::array();
        stack_.push_back(node);
        size_t index = 0;
        for (const YAML::Node& item : node) {
          Json child;
          if (auto err =
                  ConvertNode(item, pointer + "/" + std::to_string(index), std::nullopt, &child)) {
            return err;
          }
          out->push_back(std::move(child));
          ++index;
        }
        stack_.pop_back();
        return std::nullopt;
      }
      case YAML::NodeType::Map: {
        *out = Json::object();
        stack_.push_back(node);
        // Key -> 1-based line of its first occurrence, for the duplicate-key message.
        std::map<std::string, int> seen;
        for (auto it = node.begin(); it != node.end(); ++it) {
          // Copies: the iterator's pair is a temporary proxy.
          const YAML::Node key = it->first;
          const YAML::Node value = it->second;
          if (!key.IsScalar()) {
            return ConvertError{
                key.Mark(), key.IsNull() ? "a mapping key must not be null"
                                         : "a mapping key must be a scalar, not a " +
                                               std::string(key.IsMap() ? "mapping" : "sequence")};
          }
          const std::string& name = key.Scalar();
          if (!IsValidUtf8(name)) return ConvertError{key.Mark(), "key is not valid UTF-8 (save the file as UTF-8)"};
          const auto [prev, inserted] = seen.emplace(name, key.Mark().line + 1);
          if (!inserted) {
            return ConvertError{key.Mark(), "duplicate key '" + name + "' (first defined at line " +
                                                std::to_string(prev->second) + ")"};
          }
          const std::string child_pointer = pointer + "/" + PointerToken(name);
          Record(child_pointer + "#key", key.Mark());
          Json child;
          if (auto err = ConvertNode(value, child_pointer, key.Mark(), &child)) return err;
          (*out)[name] = std::move(child);
        }
        stack_.pop_back();
        return std::nullopt;
      }
    }
    return std::nullopt;
  }

  std::string_view text_;
  std::map<std::string, SourcePos>* positions_;
  std::string file_;
  std::vector<YAML::Node> stack_;
  size_t values_ = 0;
};

std::string MarkPrefix(const std::string& file, const YAML::Mark& mark) {
  if (mark.is_null() || mark.line < 0) return file;
  return SourcePos{file, mark.line + 1, mark.column + 1}.ToString();
}

}  // namespace

std::string SourcePos::ToString() const {
  if (line == 0) return file;
  return file + ":" + std::to_string(line) + ":" + std::to_string(column);
}

SourcePos YamlDocument::PositionOf(std::string_view pointer) const {
  std::string p(pointer);
  for (;;) {
    if (auto it = positions.find(p); it != positions.end()) return it->second;
    if (p.empty()) break;
    const size_t slash = p.rfind('/');
    p.resize(slash == std::string::npos ? 0 : slash);
  }
  return SourcePos{file, 0, 0};
}

SourcePos YamlDocument::KeyPositionOf(std::string_view pointer) const {
  if (auto it = positions.find(std::string(pointer) + "#key"); it != positions.end()) {
    return it->second;
  }
  return PositionOf(pointer);
}

Expected<YamlDocument> ParseYamlString(std::string_view text, const std::string& display_name) {
  YamlDocument doc;
  doc.file = display_name;
  try {
    const std::vector<YAML::Node> docs = YAML::LoadAll(std::string(text));
    if (docs.empty()) {
      doc.value = nullptr;  // An empty file; the schema decides whether that is acceptable.
      return doc;
    }
    if (docs.size() > 1) {
      return Status::Invalid(MarkPrefix(display_name, docs[1].Mark()) +
                             ": expected a single YAML document, found " +
                             std::to_string(docs.size()));
    }
    Converter converter(text, &doc.positions, display_name);
    if (auto err = converter.Convert(docs[0], "", &doc.value)) {
      return Status::Invalid(MarkPrefix(display_name, err->mark) + ": " + err->message);
    }
  } catch (const YAML::Exception& e) {
    return Status::Invalid(MarkPrefix(display_name, e.mark) + ": " + e.msg);
  } catch (const std::exception& e) {
    return Status::Invalid(display_name + ": " + e.what());
  }
  return doc;
}

Expected<YamlDocument> ParseYamlFile(const std::string& path) {
  Expected<std::string> text = Env::Default()->ReadFile(path);
  if (!text.ok()) {
    // Env reports "path: open: <strerror>"; keep only the reason so the message reads
    // "path: cannot read: <strerror>".
    std::string reason = text.status().message();
    if (reason.rfind(path + ": ", 0) == 0) {
      reason.erase(0, path.size() + 2);
      if (const size_t colon = reason.find(": "); colon != std::string::npos) {
        reason.erase(0, colon + 2);
      }
    }
    return Status::Io(path + ": cannot read: " + reason);
  }
  return ParseYamlString(*text, path);
}

Expected<nlohmann::json> ParseYamlValue(std::string_view text) {
  // On a command line `--set a.b=` means the empty string, not null.
  if (text.empty()) return nlohmann::json("");
  const std::string quoted = "'" + std::string(text) + "'";
  try {
    const YAML::Node node = YAML::Load(std::string(text));
    // Only flow collections are meant to become collections: "a: b" or "- x" typed on a command
    // line is text that happens to look like block YAML.
    size_t first = text.find_first_not_of(" \t");
    const char lead = first == std::string_view::npos ? '\0' : text[first];
    if ((node.IsMap() || node.IsSequence()) && lead != '{' && lead != '[') {
      return nlohmann::json(std::string(text));
    }
    nlohmann::json out;
    Converter converter(text, nullptr, "");
    if (auto err = converter.Convert(node, "", &out)) {
      return Status::Invalid(quoted + ": " + err->message);
    }
    return out;
  } catch (const YAML::Exception& e) {
    return Status::Invalid(quoted + ": " + e.msg);
  } catch (const std::exception& e) {
    return Status::Invalid(quoted + ": " + e.what());
  }
}

std::string PointerToken(std::string_view key) {
  std::string out;
  out.reserve(key.size());
  for (char c : key) {
    if (c == '~') {
      out += "~0";
    } else if (c == '/') {
      out += "~1";
    } else {
      out += c;
    }
  }
  return out;
}

}  // namespace pb
