#include "engine/test_util.h"

#include <algorithm>
#include <sstream>

namespace pb::testing {
namespace {

std::string Read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Status Write(StageContext& ctx, const std::string& text) {
  std::ofstream(ctx.output_path("out", "table.json")) << text;
  return Status::Ok();
}

}  // namespace

void RegisterTestStages(Registry& r) {
  r.Register(StageType{.id = "t.text",
                       .summary = "text",
                       .params_schema = R"({"type":"object","additionalProperties":false,
      "properties":{"text":{"type":"string","default":"hello"},
                    "count":{"type":"integer","minimum":1,"default":1},
                    "threads":{"type":"integer","default":0,"x-affects-output":false}}})",
                       .outputs = {{"out", "table"}},
                       .run = [](StageContext& ctx) {
                         std::string t;
                         for (int i = 0; i < ctx.params()["count"].get<int>(); ++i)
                           t += ctx.params()["text"].get<std::string>();
                         return Write(ctx, t);
                       }});
  r.Register(StageType{.id = "t.upper",
                       .summary = "upper",
                       .inputs = {{"in", "table"}},
                       .outputs = {{"out", "table"}},
                       .run = [](StageContext& ctx) {
                         std::string t = Read(ctx.input("in").file());
                         std::transform(t.begin(), t.end(), t.begin(), ::toupper);
                         return Write(ctx, t);
                       }});
  r.Register(StageType{.id = "t.len",
                       .summary = "len",
                       .inputs = {{"in", "table"}},
                       .outputs = {{"out", "table"}},
                       .run = [](StageContext& ctx) {
                         return Write(ctx, std::to_string(Read(ctx.input("in").file()).size()));
                       }});
  r.Register(StageType{.id = "t.pair",
                       .summary = "pair",
                       .inputs = {{"a", "table"}, {"b", "table", "", true}},
                       .outputs = {{"out", "table"}},
                       .run = [](StageContext& ctx) {
                         std::string t = Read(ctx.input("a").file());
                         if (ctx.has_input("b")) t += "+" + Read(ctx.input("b").file());
                         return Write(ctx, t);
                       }});
  r.Register(StageType{.id = "t.file",
                       .summary = "file",
                       .params_schema = R"({"type":"object","additionalProperties":false,
      "required":["path"],"properties":{"path":{"type":"string","x-path":true}}})",
                       .outputs = {{"out", "table"}},
                       .run = [](StageContext& ctx) {
                         return Write(ctx, Read(ctx.params()["path"].get<std::string>()));
                       }});
  r.Register(StageType{.id = "t.mesh",
                       .summary = "emits a mesh-typed artifact",
                       .outputs = {{"mesh", "mesh"}},
                       .run = [](StageContext& ctx) {
                         std::ofstream(ctx.output_path("mesh", "mesh.ply")) << "ply";
                         return Status::Ok();
                       }});
}

}  // namespace pb::testing
