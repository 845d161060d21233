// Malformed workflows (tests/workflows/bad/*.yaml): `validate` and `run` both
// exit 2, name the offending token as FILE:LINE:COLUMN (FILE as passed on the
// command line), say what is wrong, and execute nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "tests/cli_test_util.h"

namespace pbtest {
namespace {

namespace fs = std::filesystem;

struct BadCase {
  std::string file;    // under tests/workflows/bad/
  int line = 0;        // 0: the error is about the command line
  int column = 0;
  std::string phrase;  // part of the message
  std::vector<std::string> sets = {};
};

std::ostream& operator<<(std::ostream& os, const BadCase& c) { return os << c.file; }

const std::vector<BadCase>& Cases() {
  static const std::vector<BadCase> cases = {
      {"syntax_error.yaml", 6, 28, "illegal flow end"},
      {"duplicate_key.yaml", 6, 5, "duplicate key 'uses' (first defined at line 5"},
      {"missing_stages.yaml", 2, 1, "missing required key 'stages'"},
      {"unknown_top_level_key.yaml", 7, 1, "unknown key 'output'"},
      {"unknown_stage_type.yaml", 8, 11,
       "unknown stage type 'points.downsampel' (did you mean 'points.downsample'?)"},
      {"input_unknown_stage.yaml", 8, 19, "names unknown stage 'raed' (did you mean 'read'?)"},
      {"unknown_output_port.yaml", 10, 15, "has no output port 'pts'"},
      {"unknown_input_port.yaml", 10, 7, "has no input port 'pointz'"},
      {"type_mismatch.yaml", 13, 15, "type mismatch: input 'points' of stage 'down' takes points"},
      {"cycle.yaml", 6, 19, "cycle: b -> a -> b"},
      {"missing_required_input.yaml", 4, 3, "missing required input 'points'"},
      {"wrong_param_type.yaml", 10, 20,
       "stage 'down' (points.downsample): expected a number, got the string \"coarse\""},
      {"unknown_parameter.yaml", 6, 29, "unknown key 'colour'"},
      {"param_out_of_range.yaml", 11, 14,
       "stage 'down' (points.downsample): must be > 0, got -0.5"},
      {"scene_missing_key.yaml", 12, 14, "has no key 'nokey'"},
      {"scene_without_scene.yaml", 11, 14, "the workflow names no scene"},
      {"with_is_list.yaml", 6, 11, "expected an object or a string, got an array"},
      {"bad_set.yaml",
       0,
       0,
       "--set nosuch.voxel=0.1: no stage 'nosuch' in the workflow",
       {"--set", "nosuch.voxel=0.1"}},
      {"several_errors.yaml", 2, 1, "unknown key 'output'"},
  };
  return cases;
}

const std::string kBadDir = "tests/workflows/bad/";

class MalformedWorkflow : public ::testing::TestWithParam<BadCase> {
 protected:
  std::string Where(const BadCase& c) const {
    if (c.line == 0) return "<command line>: ";
    return kBadDir + c.file + ":" + std::to_string(c.line) + ":" + std::to_string(c.column) + ": ";
  }
  void ExpectError(const RunResult& r, const BadCase& c) {
    EXPECT_EQ(r.exit_code, 2) << r.Describe();
    EXPECT_NE(r.err.find(Where(c)), std::string::npos) << "expected '" << Where(c) << "'\n" << r.Describe();
    EXPECT_NE(r.err.find(c.phrase), std::string::npos) << "expected '" << c.phrase << "'\n" << r.Describe();
  }
  TempDir tmp_;
};

TEST_P(MalformedWorkflow, ValidateAndRunReportPositionAndRunNothing) {
  const BadCase& c = GetParam();
  const std::string rel = kBadDir + c.file;
  ASSERT_TRUE(Exists(SourceDir() + "/" + rel)) << rel;

  // validate: the file on its own (it takes no --set).
  const RunResult v = pbtest::Run({"validate", rel}, {}, SourceDir());
  if (c.sets.empty()) {
    ExpectError(v, c);
  } else {
    EXPECT_EQ(v.exit_code, 0) << "the file itself is valid\n" << v.Describe();
    std::vector<std::string> args = {"explain", rel, "--cache", tmp_ / "cache"};
    args.insert(args.end(), c.sets.begin(), c.sets.end());
    ExpectError(pbtest::Run(args, {}, SourceDir()), c);
  }

  std::vector<std::string> args = {"run", rel, "--cache", tmp_ / "cache", "--out", tmp_ / "out"};
  args.insert(args.end(), c.sets.begin(), c.sets.end());
  const RunResult r = pbtest::Run(args, {}, SourceDir());
  ExpectError(r, c);
  EXPECT_TRUE(ListFiles(tmp_ / "cache/entries").empty()) << "something was executed";
  EXPECT_TRUE(ListFiles(tmp_ / "cache/objects").empty()) << "something was executed";
  EXPECT_FALSE(Exists(tmp_ / "out/run.json"));
}

INSTANTIATE_TEST_SUITE_P(Bad, MalformedWorkflow, ::testing::ValuesIn(Cases()),
                         [](const ::testing::TestParamInfo<BadCase>& info) {
                           std::string name = info.param.file.substr(0, info.param.file.find('.'));
                           for (char& ch : name)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return name;
                         });

// Every committed bad workflow has a case, and its first line states the
// position the case expects.
TEST(MalformedWorkflowFiles, EveryFileHasACaseAndDocumentsItsPosition) {
  std::set<std::string> files;
  for (const auto& e : fs::directory_iterator(SourceDir() + "/" + kBadDir))
    if (e.path().extension() == ".yaml") files.insert(e.path().filename().string());
  std::set<std::string> covered;
  for (const BadCase& c : Cases()) {
    covered.insert(c.file);
    const std::string text = ReadFile(SourceDir() + "/" + kBadDir + c.file);
    const std::string first = text.substr(0, text.find('\n'));
    ASSERT_EQ(first.rfind("# ", 0), 0u) << c.file << ": first line must be a comment";
    const std::string expect = c.line == 0 ? "expect <command line>"
                                           : "expect " + std::to_string(c.line) + ":" +
                                                 std::to_string(c.column);
    EXPECT_NE(first.find(expect), std::string::npos) << c.file << ": " << first;
  }
  EXPECT_EQ(files, covered);
  EXPECT_GE(covered.size(), 14u);
}

// A file without `name:` and with mistakes of every kind: schema, parameter,
// stage type, reference and cycle errors come together, in file order, each
// once (validate and run alike).
TEST(MalformedWorkflowFiles, SeveralErrorsAreReportedTogetherInFileOrder) {
  const std::string rel = kBadDir + "several_errors.yaml";
  const std::vector<std::string> expected = {
      rel + ":2:1: unknown key 'output'",
      rel + ":6:29: stage 'read' (io.read_points): unknown key 'colour'",
      rel + ":8:11: unknown stage type 'points.downsampel' (did you mean 'points.downsample'?)",
      rel + ":12:19: cycle: b -> a -> b",
      rel +
          ":18:19: input 'points' of stage 'stats' names unknown stage 'raed' (did you mean "
          "'read'?)",
  };
  TempDir tmp;
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"validate", rel},
        {"run", rel, "--cache", tmp / "cache", "--out", tmp / "out"}}) {
    const RunResult r = pbtest::Run(args, {}, SourceDir());
    EXPECT_EQ(r.exit_code, 2) << r.Describe();
    size_t at = 0;
    for (const std::string& line : expected) {
      const size_t found = r.err.find(line, at);
      EXPECT_NE(found, std::string::npos) << "missing or out of order: " << line << "\n"
                                          << r.Describe();
      if (found != std::string::npos) at = found;
    }
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 5) << r.Describe();
    EXPECT_EQ(r.err.find("missing required key 'name'"), std::string::npos) << r.Describe();
  }
  EXPECT_TRUE(ListFiles(tmp / "cache/entries").empty());
}

// The good neighbours of the bad files are good: the committed PLY reads.
TEST(MalformedWorkflowFiles, TinyPlyAndSceneAreValid) {
  TempDir tmp;
  const std::string wf = WriteWorkflow(tmp / "ok.yaml", "name: ok\nscene: " + SourceDir() + "/" +
                                                            kBadDir + "data/scene.yaml\nstages:\n"
                                                            "  read: { uses: io.read_points, with: { path: " +
                                                            SourceDir() + "/" + kBadDir + "tiny.ply } }\n"
                                                            "  down: { uses: points.downsample, in: { points: read.points }, with: { voxel: \"${scene.params.voxel}\" } }\n");
  const RunResult r = pbtest::Run({"run", wf, "--cache", tmp / "cache", "--out", tmp / "out"});
  EXPECT_EQ(r.exit_code, 0) << r.Describe();
}

}  // namespace
}  // namespace pbtest
