// Stages for testing the engine, loaded as a plugin (`plugins:`) so that every
// engine test also exercises plugin loading. They work on small text files
// stored as `table` artifacts (table.json holding {"text": ...}).
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "engine/stage.h"

namespace {

using nlohmann::json;

std::string ReadText(const pb::ArtifactView& view) {
  std::ifstream in(view.file());
  json j = json::parse(in, nullptr, false);
  return j.is_object() ? j.value("text", "") : "";
}

pb::Status WriteText(pb::StageContext& ctx, const std::string& port, const std::string& text) {
  std::ofstream out(ctx.output_path(port, "table.json"));
  out << json{{"text", text}}.dump();
  return out ? pb::Status::Ok() : pb::Status::Io("cannot write output");
}

void Sleep(pb::StageContext& ctx) {
  const int ms = ctx.params().value("sleep_ms", 0);
  for (int i = 0; i < 10; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(ms / 10));
    ctx.progress((i + 1) / 10.0);
  }
}

constexpr const char* kSleep = R"("sleep_ms": {"type": "integer", "minimum": 0, "default": 0,
    "description": "Sleep this long (ms) while reporting progress"})";

}  // namespace

extern "C" int pointbake_plugin_abi() { return pb::kPluginAbi; }

extern "C" void pointbake_register_stages(pb::StageRegistry* registry) {
  registry->Register(pb::StageType{
      .id = "test.source",
      .version = 1,
      .summary = "Writes `text` (repeated `repeat` times) as a table artifact",
      .params_schema = std::string(R"({"type":"object","additionalProperties":false,
        "required":["text"],
        "properties":{"text":{"type":"string"},
          "repeat":{"type":"integer","minimum":1,"default":1},
          "threads":{"type":"integer","default":1,"x-affects-output":false},)") +
                       kSleep + "}}",
      .outputs = {{"out", "table", "the text"}},
      .run = [](pb::StageContext& ctx) {
        PB_PHASE(ctx, "compute");
        Sleep(ctx);
        std::string text;
        for (int i = 0; i < ctx.params()["repeat"].get<int>(); ++i) text += ctx.params()["text"].get<std::string>();
        ctx.counter("chars", static_cast<double>(text.size()));
        return WriteText(ctx, "out", text);
      }});
  registry->Register(pb::StageType{
      .id = "test.concat",
      .version = 1,
      .summary = "Concatenates the texts of inputs a and b (optional) and `suffix`",
      .params_schema = std::string(R"({"type":"object","additionalProperties":false,
        "properties":{"suffix":{"type":"string","default":""},)") + kSleep + "}}",
      .inputs = {{"a", "table", ""}, {"b", "table", "", true}},
      .outputs = {{"out", "table", ""}},
      .run = [](pb::StageContext& ctx) {
        Sleep(ctx);
        std::string text = ReadText(ctx.input("a"));
        if (ctx.has_input("b")) text += ReadText(ctx.input("b"));
        return WriteText(ctx, "out", text + ctx.params()["suffix"].get<std::string>());
      }});
  registry->Register(pb::StageType{
      .id = "test.length",
      .version = 1,
      .summary = "Writes the length of its input text (same length, same bytes: early cutoff)",
      .params_schema = std::string(R"({"type":"object","additionalProperties":false,
        "properties":{)") + kSleep + "}}",
      .inputs = {{"in", "table", ""}},
      .outputs = {{"out", "table", ""}},
      .run = [](pb::StageContext& ctx) {
        Sleep(ctx);
        return WriteText(ctx, "out", std::to_string(ReadText(ctx.input("in")).size()));
      }});
  registry->Register(pb::StageType{
      .id = "test.alloc",
      .version = 1,
      .summary = "Allocates and touches `mib` MiB, holds it `hold_ms`, then writes that figure",
      .params_schema = R"({"type":"object","additionalProperties":false,
        "properties":{"mib":{"type":"integer","minimum":0,"default":64},
          "hold_ms":{"type":"integer","minimum":0,"default":0,
            "description":"keep the memory this long, so that a memory poll sees it"}}})",
      .outputs = {{"out", "table", ""}},
      .run = [](pb::StageContext& ctx) {
        const size_t bytes = ctx.params()["mib"].get<size_t>() << 20;
        std::vector<char> block(bytes);
        const long page = ::sysconf(_SC_PAGESIZE);
        for (size_t i = 0; i < bytes; i += static_cast<size_t>(page)) block[i] = static_cast<char>(i);
        volatile char sink = bytes ? block[bytes / 2] : 0;
        (void)sink;
        std::this_thread::sleep_for(std::chrono::milliseconds(ctx.params()["hold_ms"].get<int>()));
        ctx.counter("bytes", static_cast<double>(bytes));
        return WriteText(ctx, "out", std::to_string(bytes));
      }});
  registry->Register(pb::StageType{
      .id = "test.warn",
      .version = 1,
      .summary = "Passes its input text through (or writes `text`), reporting each of `warnings`",
      .params_schema = R"({"type":"object","additionalProperties":false,
        "properties":{"warnings":{"type":"array","items":{"type":"string"},"default":[]},
                      "text":{"type":"string","default":"warned"},
                      "fail":{"type":"boolean","default":false}}})",
      .inputs = {{"in", "table", "", true}},
      .outputs = {{"out", "table", ""}},
      .run = [](pb::StageContext& ctx) -> pb::Status {
        for (const auto& w : ctx.params()["warnings"]) ctx.warning(w.get<std::string>());
        if (ctx.params()["fail"].get<bool>()) return pb::Status::Invalid("failed after warning");
        return WriteText(ctx, "out",
                         ctx.has_input("in") ? ReadText(ctx.input("in"))
                                             : ctx.params()["text"].get<std::string>());
      }});
  registry->Register(pb::StageType{
      .id = "test.stamp",
      .version = 1,
      .summary = "Writes a text that differs on every run (pid and clock): not reproducible",
      .outputs = {{"out", "table", ""}},
      .run = [](pb::StageContext& ctx) {
        const auto ns = std::chrono::steady_clock::now().time_since_epoch().count();
        return WriteText(ctx, "out", std::to_string(::getpid()) + "-" + std::to_string(ns));
      }});
  registry->Register(pb::StageType{
      .id = "test.fail",
      .version = 1,
      .summary = "Fails with `message`, or crashes (abort) when `crash` is true",
      .params_schema = R"({"type":"object","additionalProperties":false,
        "properties":{"message":{"type":"string","default":"planned failure"},
                      "crash":{"type":"boolean","default":false}}})",
      .inputs = {{"in", "table", "", true}},
      .outputs = {{"out", "table", ""}},
      .run = [](pb::StageContext& ctx) -> pb::Status {
        if (ctx.params()["crash"].get<bool>()) std::abort();
        return pb::Status::Invalid(ctx.params()["message"].get<std::string>());
      }});
}
