#include "engine/workflow.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace pb
