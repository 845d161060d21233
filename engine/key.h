// Cache keys: what a stage's result depends on, and what changed since the
// last run (`pointbake explain`).
//
// Key components (a JSON object; the key is XXH3-128 of its compact dump,
// whose members nlohmann sorts):
//   engine_format  kEngineFormatVersion, bumped when the engine's layout of
//                  artifacts changes
//   type, version  the stage type and its implementation version
//   params         effective parameters minus those marked
//                  "x-affects-output": false; x-path values are replaced by
//                  {"file_digest": ...}; integral floats become integers
//   inputs         input port -> artifact digest (content, not upstream keys:
//                  this is what gives early cutoff)
//   salt           the workflow's salt
// Absolute paths never enter a key, so moving the cache or the project keeps
// hits.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "engine/cache.h"
#include "engine/workflow.h"

namespace pb {

inline constexpr int kEngineFormatVersion = 1;

// `input_digests`: port -> artifact digest hex.
Expected<nlohmann::json> KeyComponents(const StageNode& node, const std::string& salt,
                                       const std::map<std::string, std::string>& input_digests,
                                       Cache& cache);

// Human-readable differences between two component sets, e.g.
// "parameter 'voxel' changed: 0.01 -> 0.02", "input 'points' changed",
// "implementation version 1 -> 2", "file 'path' changed (content)".
std::vector<std::string> DiffComponents(const nlohmann::json& before, const nlohmann::json& after);

// What `run --dry-run` and `explain` print for each stage.
struct PlanLine {
  std::string stage;
  std::string type;
  // kHit: in the cache. kMiss: runs. kDependsOnUpstream: runs unless the
  // stages before it re-run and write the same bytes (early cutoff); its key
  // is known only then. kEarlierRun: an earlier run of the same campaign
  // computes this key, so this run finds it in the cache.
  enum class State { kHit, kMiss, kDependsOnUpstream, kEarlierRun } state = State::kMiss;
  std::string key;  // hex, empty when not yet computable
  std::vector<std::string> reasons;
};

struct PlanOptions {
  std::set<std::string> force;  // stage ids that run whatever the cache holds (--force)
  // Campaigns: keys the runs planned so far will compute. Read (a key in it
  // is kEarlierRun) and extended (with this plan's kMiss keys); may be null.
  std::set<std::string>* planned_keys = nullptr;
};

Expected<std::vector<PlanLine>> PlanWorkflow(const Workflow& workflow, Cache& cache,
                                             const PlanOptions& options = {});

}  // namespace pb
