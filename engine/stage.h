// Stage types: what a stage is, how it is registered, and the context a stage
// runs in. This header is the whole interface for stage authors, built-in or
// out of tree (plugins): a plugin needs no pointbake symbol at link time, only
// this header, because the registry and the context are reached through
// virtual calls.
//
// A stage is a pure function of (typed input artifacts, validated parameters)
// to typed output artifacts. Its cache key covers its type id, `version`, the
// parameters that affect its output, and the content digests of its inputs,
// so bump `version` whenever the bytes a stage writes change.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "base/status.h"

namespace pb {

// Artifact types and their on-disk form (one directory per artifact):
//   points -> points.ply  (binary little-endian PLY, see stages/geometry/io/ply.h)
//   mesh   -> mesh.ply    (binary PLY with optional UVs, colors, tangents)
//   image  -> image.png (8/16-bit) or image.exr (float)
//   frames -> frames.json + one PNG per viewpoint (stages/geometry/io/frames.h)
//   table  -> table.json
//   model  -> an exported model: model.glb, model.obj + model.mtl + PNGs, or
//             model.vtp + PNGs; error maps (errors.vtp + errors.ply)
//   any    -> accepted by inputs that take every type (tests, exports)
inline constexpr const char* kArtifactTypes[] = {"points", "mesh",  "image", "frames",
                                                 "table",  "model", "any"};

struct PortSpec {
  std::string name;
  std::string type;  // one of kArtifactTypes
  std::string doc;
  bool optional = false;
};

// An input artifact as a stage sees it: its files (name -> absolute path, read
// only) and its metadata (e.g. point spacing, origin offset).
struct ArtifactView {
  std::string type;
  std::map<std::string, std::string> files;
  nlohmann::json meta = nlohmann::json::object();
  // The single file of a one-file artifact (points, mesh, image, table).
  const std::string& file() const { return files.begin()->second; }
};

// What a running stage may do. Implemented by the engine.
class StageContext {
 public:
  virtual ~StageContext() = default;
  // Effective parameters: the workflow's `with:` after defaults from the
  // stage's schema, validated.
  virtual const nlohmann::json& params() const = 0;
  virtual bool has_input(std::string_view port) const = 0;
  virtual const ArtifactView& input(std::string_view port) const = 0;
  // Path where the stage writes file `file_name` of output `port`; the engine
  // creates the directory. Write every declared output before returning Ok.
  virtual std::string output_path(std::string_view port, std::string_view file_name) = 0;
  virtual void set_output_meta(std::string_view port, nlohmann::json meta) = 0;
  // Fraction done in [0,1] for the progress line; cheap to call often.
  virtual void progress(double fraction) = 0;
  // Stage-reported counts written to the run record (points, faces, texels).
  virtual void counter(std::string_view name, double value) = 0;
  // Named phases (io, compute, ...). Prefer PB_PHASE below.
  virtual void begin_phase(std::string_view name) = 0;
  virtual void end_phase(std::string_view name) = 0;
  // Threads the stage may use (--threads; default: all cores).
  virtual int threads() const = 0;
  // A warning for the user, one line: the result exists but may not be what
  // the workflow meant (a reader dropped colors, a budget above the input
  // left the mesh unchanged). Warnings reach the run record (run.json), the
  // progress line and the campaign report, and are kept with the cache entry,
  // so a cache hit shows them again. The engine keeps the first
  // kMaxStageWarnings and counts the rest. Use it instead of stderr, which
  // only reaches the stage's log. Safe to call from the stage's threads. (Declared last: plugins
  // built against an earlier header, which never call it, keep working.)
  virtual void warning(std::string_view message) = 0;
};

inline constexpr int kMaxStageWarnings = 50;

// Records a named phase for the enclosing scope: PB_PHASE(ctx, "io");
class ScopedPhase {
 public:
  ScopedPhase(StageContext& ctx, std::string_view name) : ctx_(ctx), name_(name) {
    ctx_.begin_phase(name_);
  }
  ~ScopedPhase() { ctx_.end_phase(name_); }
  ScopedPhase(const ScopedPhase&) = delete;
  ScopedPhase& operator=(const ScopedPhase&) = delete;

 private:
  StageContext& ctx_;
  std::string name_;
};
#define PB_PHASE_CAT2(a, b) a##b
#define PB_PHASE_CAT(a, b) PB_PHASE_CAT2(a, b)
#define PB_PHASE(ctx, name) ::pb::ScopedPhase PB_PHASE_CAT(pb_phase_, __LINE__)((ctx), (name))

struct StageType {
  std::string id;       // "family.name", e.g. "points.downsample"
  int version = 1;      // bump when output bytes change
  std::string summary;  // one line for `pointbake stages`
  std::string doc;      // paragraphs for `pointbake stages ID`
  // JSON Schema (draft 7) of `with:`, an object schema. Per property:
  // "default" fills missing values; "description" documents it;
  // "x-affects-output": false keeps it out of the cache key (threads, log
  // level); "x-path": true marks a file path, resolved against the file that
  // names it and keyed by the file's content digest, never its name.
  std::string params_schema = R"({"type":"object","additionalProperties":false})";
  std::vector<PortSpec> inputs;
  std::vector<PortSpec> outputs;
  // Declared peak memory in bytes (0: unknown), for the --mem budget until
  // the engine has learned the real figure from earlier runs.
  uint64_t declared_peak_bytes = 0;
  std::function<Status(StageContext&)> run;
};

// The registry of stage types, looked up by id.
class StageRegistry {
 public:
  virtual ~StageRegistry() = default;
  // Fails on a duplicate id, a malformed id or schema, or an unknown port type.
  virtual Status Register(StageType type) = 0;
  virtual const StageType* Find(std::string_view id) const = 0;
  virtual std::vector<const StageType*> All() const = 0;
};

// A plugin is a shared library exporting these two C functions:
//   extern "C" int pointbake_plugin_abi() { return pb::kPluginAbi; }
//   extern "C" void pointbake_register_stages(pb::StageRegistry* r);
// Registration failures are collected by the registry and reported by the
// plugin loader with the library's path.
inline constexpr int kPluginAbi = 1;

}  // namespace pb
