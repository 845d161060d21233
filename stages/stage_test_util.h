// Test doubles for running stages without the engine or child processes: a
// registry that holds stage types by id, and a StageContext that keeps
// outputs in a temporary directory and records what the stage reports
// (meta, counters, phases, progress) for the test to assert on.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "stages/geometry/core/mesh.h"
#include "stages/geometry/core/point_cloud.h"
#include "stages/geometry/testing/test_data.h"
#include "engine/stage.h"

namespace pb {

class FakeRegistry : public StageRegistry {
 public:
  Status Register(StageType type) override;
  const StageType* Find(std::string_view id) const override;
  std::vector<const StageType*> All() const override;

 private:
  std::map<std::string, StageType> types_;
};

// Outputs go to <dir>/out/<port>/<file>. Checks as the engine would that
// progress never goes back or past 1 and that phases nest.
class FakeContext : public StageContext {
 public:
  FakeContext(std::filesystem::path dir, nlohmann::json params, int threads = 1)
      : dir_(std::move(dir)), params_(std::move(params)), threads_(threads) {}

  // Connects input `port` to the one-file artifact `file` of type `type`.
  void AddInput(const std::string& port, const std::string& type, const std::string& file,
                nlohmann::json meta = nlohmann::json::object());
  // A multi-file input (e.g. synth.scan's truth: mesh.ply + scene.json).
  void AddInput(const std::string& port, const std::string& type,
                std::map<std::string, std::string> files,
                nlohmann::json meta = nlohmann::json::object());

  const nlohmann::json& params() const override { return params_; }
  nlohmann::json& mutable_params() { return params_; }  // StageTest::Run fills defaults
  bool has_input(std::string_view port) const override {
    return inputs_.count(std::string(port)) > 0;
  }
  const ArtifactView& input(std::string_view port) const override {
    return inputs_.at(std::string(port));
  }
  std::string output_path(std::string_view port, std::string_view file_name) override;
  void set_output_meta(std::string_view port, nlohmann::json meta) override {
    meta_[std::string(port)] = std::move(meta);
  }
  void progress(double fraction) override;
  void counter(std::string_view name, double value) override {
    counters_[std::string(name)] = value;
  }
  void begin_phase(std::string_view name) override;
  void end_phase(std::string_view name) override;
  int threads() const override { return threads_; }

  std::map<std::string, std::string> outputs_;  // port -> its last file
  std::map<std::string, std::string> files_;    // "port/file" -> path
  std::map<std::string, nlohmann::json> meta_;
  std::map<std::string, double> counters_;
  std::set<std::string> phases_;
  std::vector<std::string> open_phases_;
  double last_progress_ = 0;

 private:
  std::filesystem::path dir_;
  nlohmann::json params_;
  int threads_;
  std::map<std::string, ArtifactView> inputs_;
};

// A fresh temporary directory per test (removed afterwards) and a registry
// that the derived fixture fills in SetUp.
class StageTest : public testing::TempDirTest {
 protected:
  // Runs stage `id` in `ctx`; every phase it opened must be closed.
  Status Run(const std::string& id, FakeContext& ctx);
  // Writes <dir>/input/<name>/mesh.ply (points.ply) and returns its path,
  // for FakeContext::AddInput.
  std::string WriteInputMesh(const std::string& name, const Mesh& mesh);
  std::string WriteInputPoints(const std::string& name, const PointCloud& cloud);
  // The parameter schema of stage type `type`, after checking (EXPECT) what
  // every stage's schema promises: no unknown parameters
  // (additionalProperties false) and a description for each parameter (and a
  // default, when `defaults` says every parameter has one).
  static nlohmann::json CheckedSchema(const StageType& type, bool defaults = false);

  FakeRegistry registry_;
};

}  // namespace pb
