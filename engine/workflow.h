// Workflows: YAML files describing a DAG of stages, loaded into a validated
// model before anything runs.
//
// Loading checks, and reports as `file:line:column: message` (1-based), every
// problem it can find: YAML syntax, duplicate keys, the workflow and scene
// schemas (schemas/), unknown stage types, parameters against each stage
// type's schema, `${scene.KEY}` references, `--set` overrides, unknown stages
// and ports in `in:`, artifact type mismatches between ports, missing required
// inputs and cycles. All errors of a file are reported together: schema
// errors do not hide the graph's (a value the schema rejected is not checked
// again).
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "base/status.h"
#include "engine/registry.h"
#include "engine/yaml_json.h"

namespace pb {

struct InputRef {
  std::string from_stage;
  std::string from_port;
  SourcePos pos;  // of the `in:` value
};

struct StageNode {
  std::string id;
  const StageType* type = nullptr;
  // Effective parameters: `with:` + scene substitution + --set + defaults,
  // validated; paths (x-path) absolute.
  nlohmann::json params = nlohmann::json::object();
  std::map<std::string, InputRef> inputs;  // by input port
  std::vector<std::string> deps;           // distinct upstream stage ids, sorted
  SourcePos pos;                           // of the stage's key
  std::string group;                       // `group:` (report grouping), or empty
};

struct Workflow {
  std::string name;  // `name:`, else DefaultWorkflowName(file)
  std::string file;  // absolute path of the workflow file
  std::string scene_file;
  nlohmann::json scene;  // null when there is none
  std::vector<std::string> plugins;  // absolute paths
  std::string salt;
  std::map<std::string, StageNode> stages;
  // Stages left out because their `when:` was false (not in `stages`).
  std::vector<std::string> disabled;
  std::vector<std::string> order;  // topological; ties broken by name
  // name -> (stage, port) copied to the output folder.
  std::map<std::string, std::pair<std::string, std::string>> outputs;

  // Stage ids that consume an output of `id`.
  std::vector<std::string> Dependents(const std::string& id) const;
};

struct LoadOptions {
  std::string scene_file;          // --scene, overrides `scene:`
  std::vector<std::string> sets;   // --set STAGE.PARAM[.SUB]=VALUE
};

// Loads plugins into `registry` as the workflow asks.
Expected<Workflow> LoadWorkflow(const std::string& path, const LoadOptions& options,
                                Registry& registry);

// " (did you mean 'X'?)" for the candidate closest to `word` within a few
// edits, else "".
std::string DidYouMean(const std::string& word, const std::vector<std::string>& candidates);

// A workflow without `name:` is named after its file: the stem, with
// characters a name may not hold replaced by '_' ("my flow.yaml" -> "my_flow").
std::string DefaultWorkflowName(const std::string& path);

// Validates a scene file on its own and applies its defaults and `units`
// (base/units.h): a scene in other units than meters gets its viewpoints' eye
// and target in meters, and an io.read_points source reads its file in those
// units (its `with: units`, which the scene sets).
Expected<nlohmann::json> LoadScene(const std::string& path);

// The embedded schemas (schemas/*.json, compiled into the binary).
const nlohmann::json& WorkflowSchemaJson();
const nlohmann::json& SceneSchemaJson();

// Fails, as `<command line>: FLAG ID: ...` with a "did you mean", unless every
// id names a stage of the workflow (a stage its `when:` leaves out is named
// as such).
Status CheckStageIds(const Workflow& workflow, const std::vector<std::string>& ids,
                     const std::string& flag);

// `run --until`: keeps only `targets` and the stages they need (upstream,
// transitively). Named outputs of stages left out are dropped; each target's
// outputs are added as `<stage>.<port>` unless an output names them already.
Status KeepUpstreamOf(Workflow& workflow, const std::vector<std::string>& targets);

// Graphviz DOT of the DAG: one node per stage (id and type), one edge per
// input, labeled port -> port.
std::string WorkflowToDot(const Workflow& workflow);

}  // namespace pb
