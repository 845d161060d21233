#include "engine/workflow.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "base/units.h"
#include "engine/test_util.h"

namespace pb {
namespace {

using testing::TempDir;

class WorkflowTest : public ::testing::Test {
 protected:
  void SetUp() override { testing::RegisterTestStages(registry_); }
  Expected<Workflow> Load(const std::string& text, LoadOptions opts = {}) {
    return LoadWorkflow(dir_.Write("wf.yaml", text), opts, registry_);
  }
  Registry registry_;
  TempDir dir_;
};

TEST_F(WorkflowTest, LoadsStagesInputsAndTopologicalOrder) {
  auto wf = Load(R"(name: demo
stages:
  up: { uses: t.upper, in: { in: src.out } }
  src: { uses: t.text, with: { text: abc } }
  pair: { uses: t.pair, in: { a: up.out, b: src.out } }
)");
  ASSERT_TRUE(wf.ok()) << wf.status().message();
  EXPECT_EQ(wf->name, "demo");
  EXPECT_EQ(wf->order, (std::vector<std::string>{"src", "up", "pair"}));
  EXPECT_EQ(wf->stages["pair"].deps, (std::vector<std::string>{"src", "up"}));
  EXPECT_EQ(wf->stages["src"].params["count"], 1);  // default applied
  EXPECT_EQ(wf->stages["src"].params["text"], "abc");
  // Default outputs: outputs of stages nothing consumes.
  ASSERT_EQ(wf->outputs.size(), 1u);
  EXPECT_EQ(wf->outputs.begin()->second.first, "pair");
  EXPECT_NE(WorkflowToDot(*wf).find("\"up\" -> \"pair\""), std::string::npos);
}

TEST_F(WorkflowTest, SceneValuesKeepTheirTypeAndPathsResolveAgainstTheirFile) {
  dir_.Write("scenes/room.yaml", "name: room\npoints: data/scan.txt\nparams: { n: 3, word: hi }\n");
  dir_.Write("scenes/data/scan.txt", "x");
  auto wf = Load(R"(name: demo
scene: scenes/room.yaml
stages:
  src: { uses: t.text, with: { text: "${scene.params.word}-${scene.params.n}", count: "${scene.params.n}" } }
  file: { uses: t.file, with: { path: "${scene.points}" } }
)");
  ASSERT_TRUE(wf.ok()) << wf.status().message();
  EXPECT_EQ(wf->stages["src"].params["count"], 3);
  EXPECT_EQ(wf->stages["src"].params["text"], "hi-3");
  EXPECT_EQ(wf->stages["file"].params["path"], dir_.path() + "/scenes/data/scan.txt");
}

TEST_F(WorkflowTest, SetOverridesAreTypedAndValidated) {
  const std::string text = "name: demo\nstages:\n  src: { uses: t.text }\n";
  auto wf = Load(text, LoadOptions{"", {"src.count=4", "src.text=zz"}});
  ASSERT_TRUE(wf.ok()) << wf.status().message();
  EXPECT_EQ(wf->stages["src"].params["count"], 4);
  EXPECT_EQ(wf->stages["src"].params["text"], "zz");

  auto bad = Load(text, LoadOptions{"", {"src.count=many"}});
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("<command line> --set src.count=many"), std::string::npos)
      << bad.status().message();
  auto unknown = Load(text, LoadOptions{"", {"sorce.count=2"}});
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.status().message().find("did you mean 'src'"), std::string::npos)
      << unknown.status().message();
}

TEST_F(WorkflowTest, ReportsEveryErrorWithItsPosition) {
  auto wf = Load(R"(name: demo
stages:
  src: { uses: t.text, with: { count: 0 } }
  up: { uses: t.uper, in: { in: src.out } }
  len: { uses: t.len, in: { in: src.nope } }
  m: { uses: t.mesh }
  u2: { uses: t.upper, in: { in: m.mesh } }
)");
  ASSERT_FALSE(wf.ok());
  const std::string msg = wf.status().message();
  EXPECT_NE(msg.find("wf.yaml:3:39: stage 'src' (t.text): must be >= 1"), std::string::npos) << msg;
  EXPECT_NE(msg.find("wf.yaml:4:15: unknown stage type 't.uper' (did you mean 't.upper'?)"),
            std::string::npos) << msg;
  EXPECT_NE(msg.find("wf.yaml:5:33: stage 'src' (t.text) has no output port 'nope'"),
            std::string::npos) << msg;
  EXPECT_NE(msg.find("wf.yaml:7:34: type mismatch: input 'in' of stage 'u2' takes table, but m.mesh is mesh"),
            std::string::npos) << msg;
}

TEST_F(WorkflowTest, RejectsNonFiniteNumbersBadUtf8AndEscapingOutputNames) {
  const std::string text = "name: demo\nstages:\n  src: { uses: t.text }\n";
  for (const char* value : {".inf", "-.inf", ".nan"}) {
    auto wf = Load(text, LoadOptions{"", {std::string("src.threads=") + value}});
    ASSERT_FALSE(wf.ok()) << value;
    EXPECT_NE(wf.status().message().find("must be a finite number"), std::string::npos)
        << wf.status().message();
  }
  auto utf8 = Load("name: demo\nstages:\n  src: { uses: t.text, with: { text: \"caf\xe9\" } }\n");
  ASSERT_FALSE(utf8.ok());
  EXPECT_NE(utf8.status().message().find("wf.yaml:3:38: text is not valid UTF-8"), std::string::npos)
      << utf8.status().message();
  auto escape = Load(text + "outputs: { ../../escape: src.out }\n");
  ASSERT_FALSE(escape.ok());
  EXPECT_NE(escape.status().message().find("wf.yaml:4:12:"), std::string::npos)
      << escape.status().message();
}

TEST_F(WorkflowTest, ASceneWithoutViewpointsOrParamsSaysHowToGetThem) {
  dir_.Write("scene.yaml", "name: s\nparams: { depth_high: 9 }\n");
  for (const char* ref : {"viewpoints", "params.faces_low"}) {
    auto wf = Load(std::string("name: demo\nscene: scene.yaml\nstages:\n  src: { uses: t.text, with: { text: \"${scene.") +
                   ref + "}\" } }\n");
    ASSERT_FALSE(wf.ok()) << ref;
    EXPECT_NE(wf.status().message().find(std::string("has no key '") + ref + "'"), std::string::npos)
        << wf.status().message();
    EXPECT_NE(wf.status().message().find("`pointbake scene SCAN -o FILE`"), std::string::npos)
        << wf.status().message();
  }
  auto other = Load("name: demo\nscene: scene.yaml\nstages:\n  src: { uses: t.text, with: { text: \"${scene.nokey}\" } }\n");
  ASSERT_FALSE(other.ok());
  EXPECT_EQ(other.status().message().find("pointbake scene"), std::string::npos) << other.status().message();
}

TEST_F(WorkflowTest, SceneReferencesNeverCrashOnOddIndices) {
  dir_.Write("scene.yaml", "name: s\nviewpoints: [{ eye: [0, 0, 0], target: [1, 0, 0] }]\n");
  auto wf = Load(R"(name: demo
scene: scene.yaml
stages:
  src: { uses: t.text, with: { text: "${scene.viewpoints.99999999999999999999999}" } }
)");
  ASSERT_FALSE(wf.ok());
  EXPECT_NE(wf.status().message().find("has no key 'viewpoints.99999999999999999999999'"),
            std::string::npos) << wf.status().message();
  auto ok = Load(R"(name: demo
scene: scene.yaml
stages:
  src: { uses: t.text, with: { text: "eye=${scene.viewpoints.0.eye}" } }
)");
  ASSERT_TRUE(ok.ok()) << ok.status().message();
  EXPECT_EQ(ok->stages["src"].params["text"], "eye=[0,0,0]");
}

TEST_F(WorkflowTest, TheSceneNamesTheSourceStageAndWhenLeavesStagesOut) {
  dir_.Write("scenes/synthetic.yaml", R"(name: synthetic
truth: true
source: { uses: t.text, with: { text: made, count: 2 } }
)");
  dir_.Write("scenes/scanned.yaml", R"(name: scanned
truth: false
data_note: "Ask the archive for scan.txt."
source: { uses: t.file, with: { path: data/scan.txt } }
)");
  dir_.Write("scenes/data/scan.txt", "x");
  const std::string text = R"(name: demo
stages:
  src: { uses: "${scene.source.uses}", with: "${scene.source.with}", group: input }
  up: { uses: t.upper, in: { in: src.out }, group: bake }
  truth: { uses: t.text, with: { text: truth }, when: "${scene.truth}", group: evaluation }
  both: { uses: t.pair, in: { a: up.out, b: truth.out }, when: "${scene.truth}" }
outputs: { result: up.out, truth: both.out }
)";
  auto synthetic = Load(text, LoadOptions{dir_.path() + "/scenes/synthetic.yaml", {}});
  ASSERT_TRUE(synthetic.ok()) << synthetic.status().message();
  EXPECT_EQ(synthetic->stages["src"].type->id, "t.text");
  EXPECT_EQ(synthetic->stages["src"].params["count"], 2);
  EXPECT_EQ(synthetic->stages["src"].group, "input");
  EXPECT_EQ(synthetic->stages.size(), 4u);
  EXPECT_TRUE(synthetic->disabled.empty());
  EXPECT_EQ(synthetic->outputs.size(), 2u);

  // --set reaches parameters that came from the scene as a whole mapping.
  auto set = Load(text, LoadOptions{dir_.path() + "/scenes/synthetic.yaml", {"src.count=5"}});
  ASSERT_TRUE(set.ok()) << set.status().message();
  EXPECT_EQ(set->stages["src"].params["count"], 5);

  auto scanned = Load(text, LoadOptions{dir_.path() + "/scenes/scanned.yaml", {}});
  ASSERT_TRUE(scanned.ok()) << scanned.status().message();
  EXPECT_EQ(scanned->stages["src"].type->id, "t.file");
  // The scene's path is relative to the scene file.
  EXPECT_EQ(scanned->stages["src"].params["path"], dir_.path() + "/scenes/data/scan.txt");
  EXPECT_EQ(scanned->disabled, (std::vector<std::string>{"both", "truth"}));
  EXPECT_EQ(scanned->stages.size(), 2u);
  ASSERT_EQ(scanned->outputs.size(), 1u);
  EXPECT_EQ(scanned->outputs.begin()->first, "result");

  // A missing scan file: the error names the scene and repeats its note.
  std::filesystem::remove(dir_.path() + "/scenes/data/scan.txt");
  auto missing = Load(text, LoadOptions{dir_.path() + "/scenes/scanned.yaml", {}});
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("wf.yaml:3:"), std::string::npos) << missing.status().message();
  EXPECT_NE(missing.status().message().find("file not found: " + dir_.path() + "/scenes/data/scan.txt"),
            std::string::npos) << missing.status().message();
  EXPECT_NE(missing.status().message().find("The scene says: Ask the archive for scan.txt."),
            std::string::npos) << missing.status().message();
}

TEST_F(WorkflowTest, SceneUnitsConvertTheViewpointsAndReachTheScanReader) {
  // The schema's names are the table's (base/units.h).
  std::vector<std::string> names;
  for (const auto& [name, meters] : kLengthUnits) names.emplace_back(name);
  EXPECT_EQ(SceneSchemaJson()["properties"]["units"]["enum"].get<std::vector<std::string>>(), names);

  const std::string mm = dir_.Write("mm.yaml", R"(name: statue
units: mm
source: { uses: io.read_points, with: { path: statue.ply } }
viewpoints:
  - { name: front, eye: [1500, -250, 400], target: [0, 0, 900], up: [0, 0, 1], fov_deg: 40 }
)");
  auto scene = LoadScene(mm);
  ASSERT_TRUE(scene.ok()) << scene.status().message();
  EXPECT_EQ((*scene)["source"]["with"]["units"], "mm");
  EXPECT_EQ((*scene)["viewpoints"][0]["eye"], nlohmann::json::parse("[1.5, -0.25, 0.4]"));
  EXPECT_EQ((*scene)["viewpoints"][0]["target"], nlohmann::json::parse("[0.0, 0.0, 0.9]"));
  EXPECT_EQ((*scene)["viewpoints"][0]["up"], nlohmann::json::parse("[0, 0, 1]"));  // a direction
  EXPECT_EQ((*scene)["viewpoints"][0]["fov_deg"], 40);

  // Meters (the default) leave the viewpoints and say so to the reader.
  auto meters = LoadScene(dir_.Write("m.yaml", R"(name: pump
source: { uses: io.read_points, with: { path: pump.e57 } }
viewpoints: [{ eye: [1.5, -1, 0.5], target: [0, 0, 0] }]
)"));
  ASSERT_TRUE(meters.ok()) << meters.status().message();
  EXPECT_EQ((*meters)["source"]["with"]["units"], "m");
  EXPECT_EQ((*meters)["viewpoints"][0]["eye"], nlohmann::json::parse("[1.5, -1, 0.5]"));

  // Units given only to the reader are the scene's: the viewpoints follow.
  auto reader = LoadScene(dir_.Write("cm.yaml", R"(name: s
source: { uses: io.read_points, with: { path: s.ply, units: cm } }
viewpoints: [{ eye: [100, 0, 0], target: [0, 0, 0] }]
)"));
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  EXPECT_EQ((*reader)["units"], "cm");
  EXPECT_EQ((*reader)["viewpoints"][0]["eye"], nlohmann::json::parse("[1.0, 0.0, 0.0]"));

  // Two different units, or units a source cannot apply: errors at the place.
  auto both = LoadScene(dir_.Write("both.yaml", R"(name: s
units: mm
source: { uses: io.read_points, with: { path: s.ply, units: cm } }
)"));
  ASSERT_FALSE(both.ok());
  EXPECT_NE(both.status().message().find("both.yaml:3:"), std::string::npos) << both.status().message();
  EXPECT_NE(both.status().message().find("reads its file in \"cm\" but the scene's units are \"mm\""),
            std::string::npos) << both.status().message();
  auto synthetic = LoadScene(dir_.Write("synth.yaml", "name: s\nunits: ft\nsource: { uses: synth.scan }\n"));
  ASSERT_FALSE(synthetic.ok());
  EXPECT_NE(synthetic.status().message().find("synth.yaml:2:"), std::string::npos)
      << synthetic.status().message();
  EXPECT_NE(synthetic.status().message().find("synth.scan makes its points in meters"), std::string::npos)
      << synthetic.status().message();
  EXPECT_FALSE(LoadScene(dir_.Write("bad.yaml", "name: s\nunits: yd\n")).ok());
}

TEST_F(WorkflowTest, WhenAndSceneNamedStagesReportBadValues) {
  dir_.Write("scene.yaml", "name: s\nparams: { flag: 3, kind: t.nope, with: 7 }\n");
  auto not_bool = Load(R"(name: demo
scene: scene.yaml
stages:
  src: { uses: t.text, when: "${scene.params.flag}" }
)");
  ASSERT_FALSE(not_bool.ok());
  EXPECT_NE(not_bool.status().message().find("wf.yaml:4:"), std::string::npos) << not_bool.status().message();
  EXPECT_NE(not_bool.status().message().find("when: must be true or false, got 3"), std::string::npos)
      << not_bool.status().message();
  auto unknown = Load(R"(name: demo
scene: scene.yaml
stages:
  src: { uses: "${scene.params.kind}", with: "${scene.params.with}" }
)");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.status().message().find("unknown stage type 't.nope'"), std::string::npos)
      << unknown.status().message();
  auto not_map = Load(R"(name: demo
scene: scene.yaml
stages:
  src: { uses: t.text, with: "${scene.params.with}" }
)");
  ASSERT_FALSE(not_map.ok());
  EXPECT_NE(not_map.status().message().find("with: the scene gives 7, not a mapping"), std::string::npos)
      << not_map.status().message();
  // A stage that consumes a disabled stage must be disabled too.
  auto dangling = Load(R"(name: demo
stages:
  src: { uses: t.text, when: false }
  up: { uses: t.upper, in: { in: src.out } }
)");
  ASSERT_FALSE(dangling.ok());
  EXPECT_NE(dangling.status().message().find("wf.yaml:4:"), std::string::npos) << dangling.status().message();
  EXPECT_NE(dangling.status().message().find("which its `when:` leaves out"), std::string::npos)
      << dangling.status().message();
  auto bad_group = Load("name: demo\nstages:\n  src: { uses: t.text, group: baking }\n");
  ASSERT_FALSE(bad_group.ok());
  EXPECT_NE(bad_group.status().message().find("wf.yaml:3:"), std::string::npos) << bad_group.status().message();
}

TEST_F(WorkflowTest, PathsFromTheCommandLineAreRelativeToTheWorkingDirectory) {
  dir_.Write("sub/data.txt", "x");
  const std::string text = "name: demo\nstages:\n  f: { uses: t.file, with: { path: sub/data.txt } }\n";
  auto from_file = Load(text);
  ASSERT_TRUE(from_file.ok()) << from_file.status().message();
  EXPECT_EQ(from_file->stages["f"].params["path"], dir_.path() + "/sub/data.txt");
  const std::string cwd = std::filesystem::current_path();
  std::filesystem::current_path(dir_.path() + "/sub");
  auto from_cli = Load(text, LoadOptions{"", {"f.path=data.txt"}});
  std::filesystem::current_path(cwd);
  ASSERT_TRUE(from_cli.ok()) << from_cli.status().message();
  EXPECT_EQ(from_cli->stages["f"].params["path"], dir_.path() + "/sub/data.txt");
}

TEST_F(WorkflowTest, DetectsCyclesAndMissingInputs) {
  auto cyc = Load(R"(name: demo
stages:
  a: { uses: t.upper, in: { in: b.out } }
  b: { uses: t.upper, in: { in: a.out } }
)");
  ASSERT_FALSE(cyc.ok());
  EXPECT_NE(cyc.status().message().find("cycle: "), std::string::npos) << cyc.status().message();
  auto missing = Load("name: demo\nstages:\n  a: { uses: t.upper }\n");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("wf.yaml:3:3: stage 'a' (t.upper) is missing required input 'in'"),
            std::string::npos)
      << missing.status().message();
}

TEST_F(WorkflowTest, NameDefaultsToTheFileStem) {
  auto wf = LoadWorkflow(dir_.Write("my flow.v2.yaml", "stages:\n  src: { uses: t.text }\n"), {},
                         registry_);
  ASSERT_TRUE(wf.ok()) << wf.status().message();
  EXPECT_EQ(wf->name, "my_flow.v2");
  EXPECT_EQ(DefaultWorkflowName("/a/b/quickstart.yaml"), "quickstart");
  EXPECT_EQ(DefaultWorkflowName("/a/.hidden.yml"), "hidden");
  EXPECT_EQ(DefaultWorkflowName("/a/__.yaml"), "workflow");
  // A name given wins.
  auto named = Load("name: given\nstages:\n  src: { uses: t.text }\n");
  ASSERT_TRUE(named.ok()) << named.status().message();
  EXPECT_EQ(named->name, "given");
}

// Schema errors used to stop loading; now the graph is checked too, and a
// value the schema rejected is not reported a second time.
TEST_F(WorkflowTest, SchemaAndGraphErrorsAreReportedTogether) {
  auto wf = Load(R"(name: "bad name!"
output: { x: src.out }
stages:
  src: { uses: t.text, with: { txt: a } }
  typo: { uses: t.uper, in: { in: src.out } }
  a: { uses: t.upper, in: { in: b.out } }
  b: { uses: t.upper, in: { in: a.out } }
  lost: { uses: t.upper, in: { in: nowhere.out } }
  badref: { uses: t.upper, in: { in: "no dot" } }
  badwith: { uses: t.text, with: [1, 2] }
  Bad-Uses: { uses: T.Text }
)");
  ASSERT_FALSE(wf.ok());
  const std::string m = wf.status().message();
  const std::string f = dir_.path() + "/wf.yaml:";
  for (const std::string& expected : {
           f + "1:7: must match pattern",                        // schema: name
           f + "2:1: unknown key 'output'",                      // schema: top level
           f + "4:32: stage 'src' (t.text): unknown key 'txt'",  // parameters
           f + "5:17: unknown stage type 't.uper' (did you mean 't.upper'?)",
           f + "6:33: cycle: b -> a -> b",  // graph
           f + "8:36: input 'in' of stage 'lost' names unknown stage 'nowhere'",
           f + "9:38: must match pattern",  // schema: the reference
           f + "10:34: expected an object or a string, got an array",
           f + "11:21: must match pattern",  // schema: uses
       })
    EXPECT_NE(m.find(expected), std::string::npos) << "missing: " << expected << "\n" << m;
  // Each problem once: no "missing required input" for the rejected
  // reference, no type error for the rejected `with:`, no "unknown stage
  // type" for the rejected `uses:`.
  EXPECT_EQ(m.find("missing required input"), std::string::npos) << m;
  EXPECT_EQ(m.find("unknown stage type 'T.Text'"), std::string::npos) << m;
  EXPECT_EQ(std::count(m.begin(), m.end(), '\n') + 1, 9) << m;
  // In the order of the file.
  EXPECT_EQ(m.rfind(f + "1:7:", 0), 0u) << m;
  EXPECT_LT(m.find(f + "5:17:"), m.find(f + "6:33:")) << m;
  EXPECT_LT(m.find(f + "10:34:"), m.find(f + "11:21:")) << m;
}

TEST_F(WorkflowTest, KeepUpstreamOfCutsTheWorkflowForUntil) {
  auto wf = Load(R"(name: demo
stages:
  src: { uses: t.text, with: { text: abc } }
  up: { uses: t.upper, in: { in: src.out } }
  len: { uses: t.len, in: { in: up.out } }
  side: { uses: t.text }
outputs: { length: len.out, other: side.out }
)");
  ASSERT_TRUE(wf.ok()) << wf.status().message();
  ASSERT_TRUE(KeepUpstreamOf(*wf, {"up"}).ok());
  EXPECT_EQ(wf->order, (std::vector<std::string>{"src", "up"}));
  EXPECT_EQ(wf->stages.size(), 2u);
  // The target's output is copied; outputs of stages left out are not.
  ASSERT_EQ(wf->outputs.size(), 1u);
  EXPECT_EQ(wf->outputs.at("up.out"), (std::pair<std::string, std::string>{"up", "out"}));

  const Status bad = KeepUpstreamOf(*wf, {"uq"});
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find(
                "<command line>: --until uq: no stage 'uq' in workflow demo (did you mean 'up'?)"),
            std::string::npos)
      << bad.message();
  const Status force = CheckStageIds(*wf, {"src", "len"}, "--force");
  EXPECT_NE(force.message().find("--force len: no stage 'len'"), std::string::npos)
      << force.message();
  EXPECT_TRUE(CheckStageIds(*wf, {"src"}, "--force").ok());
}

}  // namespace
}  // namespace pb
