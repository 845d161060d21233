#include "cli/executor_config.h"

#include <limits.h>
#include <unistd.h>

#include <CLI/CLI.hpp>

#include "base/env.h"
#include "engine/schema.h"
#include "engine/slurm_executor.h"
#include "engine/yaml_json.h"

namespace pb {
namespace {

// The user config file's schema; the defaults live in SlurmOptions.
constexpr const char* kConfigSchema = R"({
  "type": "object", "additionalProperties": false,
  "properties": {
    "executor": {"enum": ["local", "slurm"]},
    "slurm": {
      "type": "object", "additionalProperties": false,
      "properties": {
        "partition": {"type": "string"},
        "account": {"type": "string"},
        "qos": {"type": "string"},
        "time": {"type": "string"},
        "default_mem": {"type": "string"},
        "sbatch_args": {"type": "array", "items": {"type": "string"}}
      }
    }
  }
})";

std::string DefaultConfigPath() {
  if (const char* env = std::getenv("POINTBAKE_CONFIG"); env && *env) return env;
  if (const char* xdg = std::getenv("XDG_CONFIG_HOME"); xdg && *xdg)
    return std::string(xdg) + "/pointbake/config.yaml";
  if (const char* home = std::getenv("HOME"); home && *home)
    return std::string(home) + "/.config/pointbake/config.yaml";
  return "";
}

// The binary the compute nodes run: this one, by its real path.
std::string RealSelfExe() {
  char buf[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n <= 0) return "/proc/self/exe";
  buf[n] = '\0';
  return buf;
}

}  // namespace

void AddExecutorOptions(CLI::App* cmd, ExecutorFlags& f) {
  cmd->add_option("--executor", f.executor, "Where stages run: local (default) or slurm (docs/cluster.md)")
      ->check(CLI::IsMember({"local", "slurm"}));
  cmd->add_option("--config", f.config,
                  "User config file (default $POINTBAKE_CONFIG or ~/.config/pointbake/config.yaml)");
  cmd->add_option("--partition", f.partition, "Slurm partition of the stage jobs");
  cmd->add_option("--account", f.account, "Slurm account of the stage jobs");
  cmd->add_option("--qos", f.qos, "Slurm QOS of the stage jobs");
  cmd->add_option("--time", f.time, "Slurm time limit of every stage job (default: from the last run)");
  cmd->add_option("--default-mem", f.default_mem,
                  "Slurm --mem of a stage that never ran and declares no peak, e.g. 4G");
  cmd->add_option("--sbatch-arg", f.sbatch_args, "An extra sbatch argument (repeatable), e.g. --constraint=avx2");
}

Expected<std::unique_ptr<Executor>> MakeExecutor(const ExecutorFlags& f) {
  std::string executor = "local";
  SlurmOptions slurm;
  std::string default_mem;
  const std::string config_path = f.config.empty() ? DefaultConfigPath() : f.config;
  if (!config_path.empty() && (!f.config.empty() || Env::Default()->Exists(config_path))) {
    PB_ASSIGN_OR_RETURN(YamlDocument doc, ParseYamlFile(config_path));
    if (!doc.value.is_null()) {
      PB_ASSIGN_OR_RETURN(JsonSchema schema,
                          JsonSchema::Parse(nlohmann::json::parse(kConfigSchema), "user config schema"));
      std::vector<SchemaError> errors = schema.Validate(doc.value);
      if (!errors.empty()) {
        std::string msg;
        for (const SchemaError& e : errors)
          msg += (msg.empty() ? "" : "\n") +
                 (e.about_key ? doc.KeyPositionOf(e.pointer) : doc.PositionOf(e.pointer)).ToString() + ": " +
                 e.message;
        return Status::Invalid(msg);
      }
      const nlohmann::json& c = doc.value;
      executor = c.value("executor", executor);
      const nlohmann::json s = c.value("slurm", nlohmann::json::object());
      slurm.partition = s.value("partition", "");
      slurm.account = s.value("account", "");
      slurm.qos = s.value("qos", "");
      slurm.time = s.value("time", "");
      slurm.sbatch_args = s.value("sbatch_args", std::vector<std::string>{});
      if (s.contains("default_mem")) {
        Expected<uint64_t> bytes = ParseByteSize(s["default_mem"].get<std::string>());
        if (!bytes.ok())
          return Status::Invalid(doc.PositionOf("/slurm/default_mem").ToString() + ": " +
                                 bytes.status().message());
        slurm.default_mem_bytes = *bytes;
      }
    }
  }
  if (!f.executor.empty()) executor = f.executor;
  if (!f.partition.empty()) slurm.partition = f.partition;
  if (!f.account.empty()) slurm.account = f.account;
  if (!f.qos.empty()) slurm.qos = f.qos;
  if (!f.time.empty()) slurm.time = f.time;
  if (!f.default_mem.empty()) {
    Expected<uint64_t> bytes = ParseByteSize(f.default_mem);
    if (!bytes.ok()) return bytes.status().WithContext("--default-mem");
    slurm.default_mem_bytes = *bytes;
  }
  for (const std::string& a : f.sbatch_args) slurm.sbatch_args.push_back(a);
  if (executor == "local") return std::unique_ptr<Executor>();
  return std::unique_ptr<Executor>(new SlurmExecutor(RealSelfExe(), slurm));
}

}  // namespace pb
