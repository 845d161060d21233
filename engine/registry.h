// The stage registry: built-in stage types plus those loaded from plugins.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "engine/schema.h"
#include "engine/stage.h"

namespace pb {

class Registry : public StageRegistry {
 public:
  Status Register(StageType type) override;
  const StageType* Find(std::string_view id) const override;
  std::vector<const StageType*> All() const override;

  // The parsed parameter schema of a registered type.
  const JsonSchema& ParamsSchema(std::string_view id) const;
  // Errors from Register calls made by code that ignored the returned Status
  // (plugins); cleared by TakeErrors.
  std::vector<std::string> TakeErrors();

  // dlopen()s a plugin and registers its stages; idempotent per path.
  Status LoadPlugin(const std::string& path);

 private:
  struct Entry {
    StageType type;
    JsonSchema schema;
  };
  std::map<std::string, std::unique_ptr<Entry>, std::less<>> entries_;
  std::vector<std::string> errors_;
  std::vector<std::string> loaded_plugins_;
};

// Markdown-ish documentation of one stage type for `pointbake stages ID`.
std::string DescribeStage(const StageType& type);

}  // namespace pb
