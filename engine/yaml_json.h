// YAML files as JSON values that remember where each value came from.
//
// Workflow, scene and campaign files are YAML (yaml-cpp). The engine works on
// their JSON form (nlohmann::json, validated with valijson) and maps every
// error back to `file:line:column` through `positions`. Scalars are typed by
// the YAML 1.2 core schema: plain `7` is an integer, `7.5` and `1e3` numbers,
// `true`/`false` booleans, `null`/`~`/empty null; quoted scalars and explicit
// `!!str` stay strings.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "base/status.h"

namespace pb {

// A place in a source file, 1-based. line == 0 means "the file as a whole".
struct SourcePos {
  std::string file;
  int line = 0;
  int column = 0;
  // "file:line:column", or "file" when line == 0.
  std::string ToString() const;
};

struct YamlDocument {
  std::string file;  // as given to the parser (display name)
  nlohmann::json value;
  // JSON pointer (RFC 6901: "" is the root, "/stages/scan/with/points") ->
  // position of that value. For each object member, "<pointer>#key" -> the
  // position of the member's key.
  std::map<std::string, SourcePos> positions;

  // Position of `pointer`, else of its nearest ancestor that has one.
  SourcePos PositionOf(std::string_view pointer) const;
  // Position of the key of member `pointer` (falls back to PositionOf).
  SourcePos KeyPositionOf(std::string_view pointer) const;
};

// Parses one YAML document. Errors (as `file:line:column: message`): file not
// readable, syntax errors, a duplicate key in a mapping (naming the key and
// the line of its first occurrence), a non-scalar key, more than one document.
Expected<YamlDocument> ParseYamlFile(const std::string& path);
Expected<YamlDocument> ParseYamlString(std::string_view text, const std::string& display_name);

// Types one command-line value the way a plain YAML scalar or flow collection
// would be: "7" -> 7, "0.5" -> 0.5, "true" -> true, "abc" -> "abc",
// "[1, 2]" -> [1,2], "{a: 1}" -> {"a":1}. Malformed flow syntax is an error.
Expected<nlohmann::json> ParseYamlValue(std::string_view text);

// Escapes one JSON-pointer reference token ("a/b" -> "a~1b", "~" -> "~0").
std::string PointerToken(std::string_view key);

}  // namespace pb
