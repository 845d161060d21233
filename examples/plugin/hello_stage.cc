// An out-of-tree stage: build it as a shared library and name it under
// `plugins:` in a workflow (see examples/plugin/hello.yaml). It needs only
// engine/stage.h (and nlohmann-json) at build time, no pointbake library.
#include <fstream>

#include "engine/stage.h"

extern "C" int pointbake_plugin_abi() { return pb::kPluginAbi; }

extern "C" void pointbake_register_stages(pb::StageRegistry* registry) {
  registry->Register(pb::StageType{
      .id = "hello.greet",
      .version = 1,
      .summary = "Writes a greeting table: an example of a plugin stage",
      .doc = "Writes {\"greeting\": \"Hello, <name>!\", \"times\": N} as a table artifact.",
      .params_schema = R"({"type": "object", "additionalProperties": false,
        "required": ["name"],
        "properties": {
          "name": {"type": "string", "description": "Whom to greet"},
          "times": {"type": "integer", "minimum": 1, "default": 1, "description": "How often"}}})",
      .outputs = {{"greeting", "table", "the greeting"}},
      .run = [](pb::StageContext& ctx) -> pb::Status {
        PB_PHASE(ctx, "compute");
        const std::string text = "Hello, " + ctx.params()["name"].get<std::string>() + "!";
        std::ofstream out(ctx.output_path("greeting", "table.json"));
        out << nlohmann::json{{"greeting", text}, {"times", ctx.params()["times"]}}.dump(2) << "\n";
        if (!out) return pb::Status::Io("cannot write the greeting");
        ctx.counter("greetings", ctx.params()["times"].get<double>());
        return pb::Status::Ok();
      }});
}
