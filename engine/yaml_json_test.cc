#include "engine/yaml_json.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>

#include "base/testing/temp_dir.h"

namespace pb {
namespace {

using Json = nlohmann::json;

Json ParseOk(const std::string& text) {
  Expected<YamlDocument> doc = ParseYamlString(text, "t.yaml");
  EXPECT_TRUE(doc.ok()) << doc.status().message();
  return doc.ok() ? doc->value : Json();
}

Json ValueOk(const std::string& text) {
  Expected<Json> v = ParseYamlValue(text);
  EXPECT_TRUE(v.ok()) << v.status().message();
  return v.ok() ? *v : Json("<error>");
}

TEST(YamlJsonTest, TypesNullAndBool) {
  const Json v = ParseOk("a: null\nb: Null\nc: NULL\nd: ~\ne:\nf: true\ng: True\nh: FALSE\n");
  for (const char* k : {"a", "b", "c", "d", "e"}) EXPECT_TRUE(v[k].is_null()) << k;
  EXPECT_EQ(v["f"], Json(true));
  EXPECT_EQ(v["g"], Json(true));
  EXPECT_EQ(v["h"], Json(false));
  // YAML 1.1 words are plain strings under the 1.2 core schema.
  EXPECT_EQ(ParseOk("a: yes")["a"], Json("yes"));
}

TEST(YamlJsonTest, TypesIntegers) {
  const Json v = ParseOk("a: 7\nb: -12\nc: +3\nd: 0x1F\ne: 0o17\nf: 99999999999999999999\n");
  EXPECT_TRUE(v["a"].is_number_integer());
  EXPECT_EQ(v["a"].get<int64_t>(), 7);
  EXPECT_EQ(v["b"].get<int64_t>(), -12);
  EXPECT_EQ(v["c"].get<int64_t>(), 3);
  EXPECT_EQ(v["d"].get<int64_t>(), 31);
  EXPECT_EQ(v["e"].get<int64_t>(), 15);
  // Too large for int64: kept as a double.
  EXPECT_TRUE(v["f"].is_number_float());
  EXPECT_DOUBLE_EQ(v["f"].get<double>(), 1e20);
}

TEST(YamlJsonTest, TypesFloats) {
  const Json v = ParseOk("a: 7.5\nb: 1e3\nc: -.5\nd: .inf\ne: -.inf\nf: .nan\ng: 3.\n");
  EXPECT_TRUE(v["a"].is_number_float());
  EXPECT_DOUBLE_EQ(v["a"].get<double>(), 7.5);
  EXPECT_TRUE(v["b"].is_number_float());
  EXPECT_DOUBLE_EQ(v["b"].get<double>(), 1000.0);
  EXPECT_DOUBLE_EQ(v["c"].get<double>(), -0.5);
  EXPECT_TRUE(std::isinf(v["d"].get<double>()) && v["d"].get<double>() > 0);
  EXPECT_TRUE(std::isinf(v["e"].get<double>()) && v["e"].get<double>() < 0);
  EXPECT_TRUE(std::isnan(v["f"].get<double>()));
  EXPECT_DOUBLE_EQ(v["g"].get<double>(), 3.0);
}

TEST(YamlJsonTest, TypesStringsAndTags) {
  const Json v = ParseOk(
      "a: \"7\"\nb: '7'\nc: hello world\nd: !!str 7\ne: !!str true\nf: ''\ng: 1.2.3\n"
      "h: !!int \"42\"\ni: !!float 3\nj: 0x\n");
  EXPECT_EQ(v["a"], Json("7"));
  EXPECT_EQ(v["b"], Json("7"));
  EXPECT_EQ(v["c"], Json("hello world"));
  EXPECT_EQ(v["d"], Json("7"));
  EXPECT_EQ(v["e"], Json("true"));
  EXPECT_EQ(v["f"], Json(""));
  EXPECT_EQ(v["g"], Json("1.2.3"));
  EXPECT_EQ(v["h"], Json(42));
  EXPECT_TRUE(v["i"].is_number_float());
  EXPECT_EQ(v["j"], Json("0x"));

  Expected<YamlDocument> bad = ParseYamlString("a: !!int abc\n", "t.yaml");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().message(), "t.yaml:1:4: invalid !!int value 'abc'");
}

TEST(YamlJsonTest, CollectionsAndKeys) {
  const Json v = ParseOk("list: [1, two, 3.5]\nmap: {x: 1}\n1: numeric key\n");
  EXPECT_EQ(v["list"], Json::parse(R"([1, "two", 3.5])"));
  EXPECT_EQ(v["map"], Json::parse(R"({"x": 1})"));
  EXPECT_EQ(v["1"], Json("numeric key"));
}

TEST(YamlJsonTest, PositionsOfValuesAndKeys) {
  Expected<YamlDocument> doc = ParseYamlString(
      "name: demo\n"         // 1
      "stages:\n"            // 2
      "  scan:\n"            // 3
      "    with:\n"          // 4
      "      points: 100\n"  // 5
      "      list:\n"        // 6
      "        - a\n"        // 7
      "        - {b: 2}\n"   // 8
      "  empty:\n"           // 9
      "  a/b: 1\n",          // 10
      "wf.yaml");
  ASSERT_TRUE(doc.ok()) << doc.status().message();
  auto pos = [&](const std::string& p) { return doc->PositionOf(p).ToString(); };
  auto key = [&](const std::string& p) { return doc->KeyPositionOf(p).ToString(); };
  EXPECT_EQ(pos(""), "wf.yaml:1:1");
  EXPECT_EQ(pos("/name"), "wf.yaml:1:7");
  EXPECT_EQ(key("/name"), "wf.yaml:1:1");
  EXPECT_EQ(pos("/stages"), "wf.yaml:3:3");
  EXPECT_EQ(key("/stages/scan"), "wf.yaml:3:3");
  EXPECT_EQ(pos("/stages/scan/with/points"), "wf.yaml:5:15");
  EXPECT_EQ(key("/stages/scan/with/points"), "wf.yaml:5:7");
  EXPECT_EQ(pos("/stages/scan/with/list/0"), "wf.yaml:7:11");
  EXPECT_EQ(pos("/stages/scan/with/list/1/b"), "wf.yaml:8:15");
  EXPECT_EQ(key("/stages/scan/with/list/1/b"), "wf.yaml:8:12");
  // An empty value is placed at its key, not at the next token.
  EXPECT_EQ(pos("/stages/empty"), "wf.yaml:9:3");
  EXPECT_TRUE(doc->value["stages"]["empty"].is_null());
  // Keys are escaped into pointer tokens.
  EXPECT_EQ(key("/stages/a~1b"), "wf.yaml:10:3");
  EXPECT_EQ(doc->value["stages"]["a/b"], Json(1));
}

TEST(YamlJsonTest, PositionOfFallsBackToAncestors) {
  Expected<YamlDocument> doc = ParseYamlString("a:\n  b: 1\n", "f.yaml");
  ASSERT_TRUE(doc.ok());
  EXPECT_EQ(doc->PositionOf("/a/b/c/d").ToString(), "f.yaml:2:6");
  EXPECT_EQ(doc->PositionOf("/a/missing").ToString(), "f.yaml:2:3");
  EXPECT_EQ(doc->KeyPositionOf("/a/missing").ToString(), "f.yaml:2:3");
  EXPECT_EQ(doc->PositionOf("/zzz").ToString(), "f.yaml:1:1");

  YamlDocument empty;
  empty.file = "e.yaml";
  const SourcePos p = empty.PositionOf("/x/y");
  EXPECT_EQ(p.file, "e.yaml");
  EXPECT_EQ(p.line, 0);
  EXPECT_EQ(p.column, 0);
  EXPECT_EQ(p.ToString(), "e.yaml");
}

TEST(YamlJsonTest, DuplicateKeyIsAnError) {
  Expected<YamlDocument> doc = ParseYamlString("a: 1\nb:\n  c: 2\n  c: 3\n", "d.yaml");
  ASSERT_FALSE(doc.ok());
  EXPECT_EQ(doc.status().message(), "d.yaml:4:3: duplicate key 'c' (first defined at line 3)");

  doc = ParseYamlString("x: 1\ny: 2\nx: 3\n", "d.yaml");
  ASSERT_FALSE(doc.ok());
  EXPECT_NE(doc.status().message().find(":3:"), std::string::npos);
  EXPECT_NE(doc.status().message().find("'x'"), std::string::npos);
  EXPECT_NE(doc.status().message().find("line 1"), std::string::npos);
}

TEST(YamlJsonTest, NonScalarKeyIsAnError) {
  Expected<YamlDocument> doc = ParseYamlString("a: 1\n? [1, 2]\n: 3\n", "k.yaml");
  ASSERT_FALSE(doc.ok());
  EXPECT_EQ(doc.status().message(), "k.yaml:2:3: a mapping key must be a scalar, not a sequence");
}

TEST(YamlJsonTest, SyntaxErrorHasPosition) {
  Expected<YamlDocument> doc = ParseYamlString("a: 1\nb: [1, 2\n", "s.yaml");
  ASSERT_FALSE(doc.ok());
  EXPECT_EQ(doc.status().message().rfind("s.yaml:", 0), 0u) << doc.status().message();
  EXPECT_NE(doc.status().message().find("end of sequence flow not found"), std::string::npos);

  doc = ParseYamlString("a: 1\n  b: 2\n", "s.yaml");
  ASSERT_FALSE(doc.ok());
  EXPECT_EQ(doc.status().message(), "s.yaml:2:4: illegal map value");
}

TEST(YamlJsonTest, MultipleDocumentsAreAnError) {
  Expected<YamlDocument> doc = ParseYamlString("a: 1\n---\nb: 2\n", "m.yaml");
  ASSERT_FALSE(doc.ok());
  EXPECT_EQ(doc.status().message(), "m.yaml:3:1: expected a single YAML document, found 2");
}

TEST(YamlJsonTest, EmptyDocumentIsNull) {
  EXPECT_TRUE(ParseOk("").is_null());
  EXPECT_TRUE(ParseOk("# only a comment\n").is_null());
}

TEST(YamlJsonTest, RecursiveAliasIsAnError) {
  Expected<YamlDocument> doc = ParseYamlString("x: &a [1, *a]\n", "r.yaml");
  ASSERT_FALSE(doc.ok());
  EXPECT_NE(doc.status().message().find("recursive alias"), std::string::npos);
  // Plain aliases are expanded.
  const Json v = ParseOk("base: &b {n: 1}\nuse: *b\n");
  EXPECT_EQ(v["use"], Json::parse(R"({"n": 1})"));
}

TEST(YamlJsonTest, ParseYamlValue) {
  EXPECT_EQ(ValueOk("7"), Json(7));
  EXPECT_TRUE(ValueOk("7").is_number_integer());
  EXPECT_EQ(ValueOk("0.5"), Json(0.5));
  EXPECT_EQ(ValueOk("true"), Json(true));
  EXPECT_EQ(ValueOk("abc"), Json("abc"));
  EXPECT_EQ(ValueOk("hello world"), Json("hello world"));
  EXPECT_EQ(ValueOk("\"7\""), Json("7"));
  EXPECT_EQ(ValueOk(""), Json(""));
  EXPECT_TRUE(ValueOk("null").is_null());
  EXPECT_EQ(ValueOk("[1, 2]"), Json::parse("[1, 2]"));
  EXPECT_EQ(ValueOk("{a: 1, b: [x]}"), Json::parse(R"({"a": 1, "b": ["x"]})"));
  // Block-looking text is a string, not a mapping.
  EXPECT_EQ(ValueOk("a: b"), Json("a: b"));

  Expected<Json> bad = ParseYamlValue("[1, 2");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().message().rfind("'[1, 2': ", 0), 0u) << bad.status().message();
  bad = ParseYamlValue("{a: 1, a: 2}");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().message(), "'{a: 1, a: 2}': duplicate key 'a' (first defined at line 1)");
}

TEST(YamlJsonTest, PointerToken) {
  EXPECT_EQ(PointerToken("plain"), "plain");
  EXPECT_EQ(PointerToken("a/b"), "a~1b");
  EXPECT_EQ(PointerToken("~"), "~0");
  EXPECT_EQ(PointerToken("~1/"), "~01~1");
  EXPECT_EQ(PointerToken(""), "");
}

TEST(YamlJsonTest, ReadsFilesAndReportsMissingOnes) {
  testing::TempDir temp;
  const std::string dir = temp.path();
  const std::string path = dir + "/wf.yaml";
  {
    std::ofstream out(path);
    out << "stages:\n  scan:\n    points: 5\n";
  }
  Expected<YamlDocument> doc = ParseYamlFile(path);
  ASSERT_TRUE(doc.ok()) << doc.status().message();
  EXPECT_EQ(doc->file, path);
  EXPECT_EQ(doc->value["stages"]["scan"]["points"], Json(5));
  EXPECT_EQ(doc->PositionOf("/stages/scan/points").ToString(), path + ":3:13");

  const std::string missing = dir + "/missing.yaml";
  Expected<YamlDocument> gone = ParseYamlFile(missing);
  ASSERT_FALSE(gone.ok());
  EXPECT_EQ(gone.status().message(), missing + ": cannot read: No such file or directory");
}

TEST(YamlJsonTest, SourcePosToString) {
  EXPECT_EQ((SourcePos{"a.yaml", 3, 7}).ToString(), "a.yaml:3:7");
  EXPECT_EQ((SourcePos{"a.yaml", 0, 0}).ToString(), "a.yaml");
}

}  // namespace
}  // namespace pb
