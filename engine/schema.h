// JSON Schema validation (valijson, draft 7) with errors a user can act on.
//
// Errors carry the JSON pointer of the offending value so callers can map them
// back to `file:line:column` (see yaml_json.h).
#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "base/status.h"

namespace pb {

struct SchemaError {
  // JSON pointer of the value that failed ("/stages/scan/with/points"); for a
  // missing required member, the pointer of the object that lacks it; for an
  // unknown member, the pointer of that member.
  std::string pointer;
  // E.g. "expected an integer, got the string \"abc\"",
  // "unknown key 'pointz' (expected one of: points, preset, seed)",
  // "missing required key 'uses'", "must be >= 1, got 0",
  // "must be one of: auto, ply, got \"las\"".
  std::string message;
  // The problem is the member's name itself (unknown key, a name that breaks
  // propertyNames): point at the key, not its value.
  bool about_key = false;
};

class JsonSchema {
 public:
  // `name` is used in errors about the schema itself ("schemas/workflow.json").
  static Expected<JsonSchema> Parse(const nlohmann::json& schema, const std::string& name);
  static Expected<JsonSchema> ParseFile(const std::string& path);

  // All errors, deduplicated, most specific first, in document order.
  std::vector<SchemaError> Validate(const nlohmann::json& instance) const;
  const nlohmann::json& json() const { return schema_json_; }

 private:
  std::shared_ptr<const void> schema_;  // valijson::Schema, kept out of this header
  nlohmann::json schema_json_;
};

// Returns `instance` with each missing object member that has a "default" in
// the schema's "properties" filled in, recursively for nested object schemas.
nlohmann::json ApplyDefaults(const nlohmann::json& schema, nlohmann::json instance);

}  // namespace pb
