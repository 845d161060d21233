#include "stages/stage_test_util.h"

#include <stdlib.h>

#include "stages/geometry/io/ply.h"

namespace pb {

Status FakeRegistry::Register(StageType type) {
  const std::string id = type.id;
  if (!types_.emplace(id, std::move(type)).second) return Status::Invalid("duplicate " + id);
  return Status::Ok();
}

const StageType* FakeRegistry::Find(std::string_view id) const {
  auto it = types_.find(std::string(id));
  return it == types_.end() ? nullptr : &it->second;
}

std::vector<const StageType*> FakeRegistry::All() const {
  std::vector<const StageType*> all;
  for (const auto& [id, type] : types_) all.push_back(&type);
  return all;
}

void FakeContext::AddInput(const std::string& port, const std::string& type,
                           const std::string& file, nlohmann::json meta) {
  ArtifactView view;
  view.type = type;
  view.meta = std::move(meta);
  view.files[std::filesystem::path(file).filename().string()] = file;
  inputs_[port] = view;
}

void FakeContext::AddInput(const std::string& port, const std::string& type,
                           std::map<std::string, std::string> files, nlohmann::json meta) {
  ArtifactView view;
  view.type = type;
  view.meta = std::move(meta);
  view.files = std::move(files);
  inputs_[port] = view;
}

std::string FakeContext::output_path(std::string_view port, std::string_view file_name) {
  const std::filesystem::path dir = dir_ / "out" / std::string(port);
  std::filesystem::create_directories(dir);
  const std::string path = (dir / std::string(file_name)).string();
  outputs_[std::string(port)] = path;
  files_[std::string(port) + "/" + std::string(file_name)] = path;
  return path;
}

void FakeContext::progress(double fraction) {
  EXPECT_GE(fraction, last_progress_);
  EXPECT_LE(fraction, 1.0);
  last_progress_ = fraction;
}

void FakeContext::begin_phase(std::string_view name) {
  open_phases_.push_back(std::string(name));
  phases_.insert(std::string(name));
}

void FakeContext::end_phase(std::string_view name) {
  ASSERT_FALSE(open_phases_.empty());
  EXPECT_EQ(open_phases_.back(), name);
  open_phases_.pop_back();
}

Status StageTest::Run(const std::string& id, FakeContext& ctx) {
  const StageType* type = registry_.Find(id);
  if (!type) return Status::NotFound(id);
  // As the engine does: the schema's top-level defaults for parameters not given.
  if (ctx.mutable_params().is_object() && !type->params_schema.empty()) {
    const nlohmann::json schema = nlohmann::json::parse(type->params_schema, nullptr, false);
    if (schema.is_object() && schema.contains("properties")) {
      for (const auto& [name, property] : schema["properties"].items()) {
        if (property.contains("default") && !ctx.mutable_params().contains(name)) ctx.mutable_params()[name] = property["default"];
      }
    }
  }
  const Status status = type->run(ctx);
  EXPECT_TRUE(ctx.open_phases_.empty());
  return status;
}

std::string StageTest::WriteInputMesh(const std::string& name, const Mesh& mesh) {
  const std::filesystem::path dir = dir_ / "input" / name;
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "mesh.ply").string();
  EXPECT_TRUE(WritePlyMesh(path, mesh).ok());
  return path;
}

std::string StageTest::WriteInputPoints(const std::string& name, const PointCloud& cloud) {
  const std::filesystem::path dir = dir_ / "input" / name;
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "points.ply").string();
  EXPECT_TRUE(WritePlyPoints(path, cloud).ok());
  return path;
}

nlohmann::json StageTest::CheckedSchema(const StageType& type, bool defaults) {
  const nlohmann::json schema = nlohmann::json::parse(type.params_schema);
  EXPECT_EQ(schema["additionalProperties"], false) << type.id;
  for (const auto& [name, property] : schema["properties"].items()) {
    EXPECT_TRUE(property.contains("description")) << type.id << " " << name;
    if (defaults) {
      EXPECT_TRUE(property.contains("default")) << type.id << " " << name;
    }
  }
  return schema;
}

}  // namespace pb
