#include "engine/schema.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "base/testing/temp_dir.h"

namespace pb {
namespace {

using Json = nlohmann::json;

// A small workflow-like schema exercising each keyword the messages cover.
const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "required": ["uses"],
  "properties": {
    "uses": {"type": "string", "pattern": "^[a-z]+$"},
    "format": {"enum": ["auto", "ply"], "default": "auto"},
    "with": {
      "type": "object",
      "additionalProperties": false,
      "properties": {
        "points": {"type": "integer", "minimum": 1, "maximum": 1000, "default": 100},
        "preset": {"type": "string", "default": "fast"},
        "seed": {"type": "integer"},
        "ratio": {"type": "number", "exclusiveMinimum": 0},
        "nested": {
          "type": "object",
          "properties": {"depth": {"type": "integer", "default": 3}}
        }
      }
    },
    "tags": {"type": "array", "minItems": 1, "maxItems": 3, "items": {"type": "string"}},
    "name": {"type": "string", "minLength": 2}
  }
})";

JsonSchema MakeSchema(const char* text = kSchema) {
  Expected<JsonSchema> schema = JsonSchema::Parse(Json::parse(text), "test.json");
  EXPECT_TRUE(schema.ok()) << schema.status().message();
  return std::move(schema).value();
}

std::vector<SchemaError> Check(const std::string& instance) {
  return MakeSchema().Validate(Json::parse(instance));
}

std::string Format(const std::vector<SchemaError>& errors) {
  std::string out;
  for (const SchemaError& e : errors) out += "[" + e.pointer + "] " + e.message + "\n";
  return out;
}

void ExpectOnly(const std::vector<SchemaError>& errors, const std::string& pointer,
                const std::string& message) {
  ASSERT_EQ(errors.size(), 1u) << Format(errors);
  EXPECT_EQ(errors[0].pointer, pointer);
  EXPECT_EQ(errors[0].message, message);
}

TEST(SchemaTest, ValidInstanceHasNoErrors) {
  EXPECT_TRUE(Check(R"({"uses": "scan", "with": {"points": 5}, "tags": ["a"]})").empty());
}

TEST(SchemaTest, TypeMismatch) {
  ExpectOnly(Check(R"({"uses": "scan", "with": {"points": "abc"}})"), "/with/points",
             "expected an integer, got the string \"abc\"");
  ExpectOnly(Check(R"({"uses": "scan", "with": {"points": 2.5}})"), "/with/points",
             "expected an integer, got the number 2.5");
  ExpectOnly(Check(R"({"uses": 7})"), "/uses", "expected a string, got the integer 7");
  ExpectOnly(Check(R"({"uses": "scan", "with": 3})"), "/with",
             "expected an object, got the integer 3");
  ExpectOnly(Check(R"([1])"), "", "expected an object, got an array");
}

TEST(SchemaTest, TypeMismatchInArrayItem) {
  ExpectOnly(Check(R"({"uses": "scan", "tags": ["a", true]})"), "/tags/1",
             "expected a string, got the boolean true");
}

TEST(SchemaTest, UnknownKeys) {
  ExpectOnly(Check(R"({"uses": "scan", "with": {"pointz": 5}})"), "/with/pointz",
             "unknown key 'pointz' (expected one of: nested, points, preset, ratio, seed)");
  // Every unknown key is reported, not only the first one.
  const std::vector<SchemaError> errors = Check(R"({"uses": "scan", "aa": 1, "zz": 2})");
  ASSERT_EQ(errors.size(), 2u) << Format(errors);
  EXPECT_EQ(errors[0].pointer, "/aa");
  EXPECT_EQ(errors[0].message,
            "unknown key 'aa' (expected one of: format, name, tags, uses, with)");
  EXPECT_EQ(errors[1].pointer, "/zz");
}

TEST(SchemaTest, MissingRequired) {
  ExpectOnly(Check(R"({"with": {}})"), "", "missing required key 'uses'");
  const JsonSchema nested = MakeSchema(R"({
    "properties": {"stages": {"type": "object", "required": ["uses"]}}})");
  ExpectOnly(nested.Validate(Json::parse(R"({"stages": {}})")), "/stages",
             "missing required key 'uses'");
}

TEST(SchemaTest, Bounds) {
  ExpectOnly(Check(R"({"uses": "scan", "with": {"points": 0}})"), "/with/points",
             "must be >= 1, got 0");
  ExpectOnly(Check(R"({"uses": "scan", "with": {"points": 1001}})"), "/with/points",
             "must be <= 1000, got 1001");
  ExpectOnly(Check(R"({"uses": "scan", "with": {"ratio": 0}})"), "/with/ratio",
             "must be > 0, got 0");
}

TEST(SchemaTest, Enum) {
  ExpectOnly(Check(R"({"uses": "scan", "format": "las"})"), "/format",
             "must be one of: auto, ply, got \"las\"");
}

TEST(SchemaTest, Pattern) {
  ExpectOnly(Check(R"({"uses": "X"})"), "/uses", "must match pattern ^[a-z]+$, got \"X\"");
}

TEST(SchemaTest, Sizes) {
  ExpectOnly(Check(R"({"uses": "scan", "tags": []})"), "/tags", "must have at least 1 item, got 0");
  ExpectOnly(Check(R"({"uses": "scan", "tags": ["a", "b", "c", "d"]})"), "/tags",
             "must have at most 3 items, got 4");
  ExpectOnly(Check(R"({"uses": "scan", "name": "x"})"), "/name",
             "must be at least 2 characters long, got \"x\"");
}

TEST(SchemaTest, SeveralErrorsInDocumentOrder) {
  const std::vector<SchemaError> errors =
      Check(R"({"uses": "scan", "with": {"points": 0, "seed": "s"}, "format": "las"})");
  ASSERT_EQ(errors.size(), 3u) << Format(errors);
  EXPECT_EQ(errors[0].pointer, "/format");
  EXPECT_EQ(errors[1].pointer, "/with/points");
  EXPECT_EQ(errors[2].pointer, "/with/seed");
  EXPECT_EQ(errors[2].message, "expected an integer, got the string \"s\"");
}

TEST(SchemaTest, ArrayIndexVersusNumericMemberName) {
  const JsonSchema schema = MakeSchema(R"({
    "type": "object",
    "properties": {"0": {"type": "array", "items": {"type": "integer"}}}})");
  ExpectOnly(schema.Validate(Json::parse(R"({"0": [1, "x"]})")), "/0/1",
             "expected an integer, got the string \"x\"");
}

TEST(SchemaTest, AnyOfTypesAreMerged) {
  const JsonSchema schema = MakeSchema(R"({
    "properties": {"v": {"anyOf": [{"type": "string"}, {"type": "array"}]}}})");
  const std::vector<SchemaError> errors = schema.Validate(Json::parse(R"({"v": 5})"));
  ExpectOnly(errors, "/v", "expected a string or an array, got the integer 5");
}

TEST(SchemaTest, RefsAreFollowedForMessages) {
  const JsonSchema schema = MakeSchema(R"({
    "definitions": {"count": {"type": "integer", "minimum": 2}},
    "properties": {"n": {"$ref": "#/definitions/count"}}})");
  ExpectOnly(schema.Validate(Json::parse(R"({"n": 1})")), "/n", "must be >= 2, got 1");
}

TEST(SchemaTest, InvalidSchemaIsRejected) {
  Expected<JsonSchema> schema = JsonSchema::Parse(Json::parse(R"({"type": 5})"), "bad.json");
  ASSERT_FALSE(schema.ok());
  EXPECT_EQ(schema.status().message().rfind("bad.json: invalid schema: ", 0), 0u)
      << schema.status().message();
  schema = JsonSchema::Parse(Json::parse(R"({"properties": []})"), "bad.json");
  EXPECT_FALSE(schema.ok());
}

TEST(SchemaTest, BadRegexIsASchemaError) {
  Expected<JsonSchema> schema = JsonSchema::Parse(
      Json::parse(R"({"properties": {"a": {"type": "string", "pattern": "(["}}})"), "re.json");
  ASSERT_FALSE(schema.ok());
  EXPECT_EQ(schema.status().message().rfind("re.json: invalid schema: pattern '([': ", 0), 0u)
      << schema.status().message();
  // Data that merely looks like a pattern is not checked.
  EXPECT_TRUE(JsonSchema::Parse(Json::parse(R"({"default": {"pattern": "(["}})"), "d.json").ok());
}

TEST(SchemaTest, PatternPropertiesAndOneOf) {
  const JsonSchema keys = MakeSchema(R"({
    "type": "object", "additionalProperties": false, "patternProperties": {"^x_": {}}})");
  ExpectOnly(keys.Validate(Json::parse(R"({"x_a": 1, "y": 2})")), "/y",
             "unknown key 'y' (keys must match: ^x_)");
  const JsonSchema one_of = MakeSchema(R"({"oneOf": [{"type": "number"}, {"type": "integer"}]})");
  ExpectOnly(one_of.Validate(Json(1)), "",
             "must match exactly one of the schemas in 'oneOf', but matches several");
  ExpectOnly(one_of.Validate(Json("s")), "",
             "expected a number or an integer, got the string \"s\"");
}

TEST(SchemaTest, ParseFile) {
  testing::TempDir temp;
  const std::string dir = temp.path();
  const std::string good = dir + "/good.json";
  const std::string bad = dir + "/bad.json";
  std::ofstream(good) << R"({"type": "integer"})";
  std::ofstream(bad) << "{\n  \"type\": \n}";

  Expected<JsonSchema> schema = JsonSchema::ParseFile(good);
  ASSERT_TRUE(schema.ok()) << schema.status().message();
  EXPECT_EQ(schema->json(), Json::parse(R"({"type": "integer"})"));
  ExpectOnly(schema->Validate(Json("x")), "", "expected an integer, got the string \"x\"");

  Expected<JsonSchema> broken = JsonSchema::ParseFile(bad);
  ASSERT_FALSE(broken.ok());
  EXPECT_EQ(broken.status().message().rfind(bad + ": invalid JSON: parse error at line 3", 0), 0u)
      << broken.status().message();

  EXPECT_FALSE(JsonSchema::ParseFile(dir + "/missing.json").ok());
}

TEST(SchemaTest, ApplyDefaultsFillsNestedMembers) {
  const Json schema = Json::parse(kSchema);
  const Json out = ApplyDefaults(schema, Json::parse(R"({"uses": "scan", "with": {"seed": 4,
      "nested": {}}})"));
  EXPECT_EQ(out, Json::parse(R"({"uses": "scan", "format": "auto",
      "with": {"seed": 4, "points": 100, "preset": "fast", "nested": {"depth": 3}}})"));
  // Present values are kept; an absent object without a default is not invented.
  const Json kept = ApplyDefaults(schema, Json::parse(R"({"format": "ply"})"));
  EXPECT_EQ(kept, Json::parse(R"({"format": "ply"})"));
  // Non-objects pass through untouched.
  EXPECT_EQ(ApplyDefaults(schema, Json(3)), Json(3));
}

}  // namespace
}  // namespace pb
