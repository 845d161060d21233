#include "stages/geometry/core/table.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "base/testing/durable_write_check.h"
#include "base/testing/temp_dir.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

TEST(TableTest, RoundTripThroughFile) {
  Table table;
  table.columns = {"scene", "points", "psnr_db", "ok", "note"};
  table.rows.push_back({std::string("d11v3"), int64_t{35947}, 31.25, true, std::monostate{}});
  table.rows.push_back({std::string("synthetic"), int64_t{-1}, 1.0, false, std::string("x")});
  testing::TempDir dir;
  const std::string path = dir.Path("table.json");
  ASSERT_TRUE(WriteTable(path, table).ok());
  auto read = ReadTable(path);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->columns, table.columns);
  EXPECT_EQ(read->rows, table.rows);  // 1.0 stays a double, -1 an integer
  EXPECT_EQ(std::get<int64_t>(read->get(0, "points")), 35947);
  EXPECT_DOUBLE_EQ(TableNumber(read->get(0, "psnr_db")), 31.25);
  EXPECT_TRUE(std::isnan(TableNumber(read->get(0, "scene"))));
  EXPECT_TRUE(std::holds_alternative<std::monostate>(read->get(0, "missing")));
}

TEST(TableTest, FailedWritesKeepTheEarlierFile) {
  Table older, newer;
  older.columns = {"points"};
  older.rows = {{int64_t{1}}};
  newer.columns = {"points", "faces"};
  newer.rows = {{int64_t{2}, int64_t{3}}};
  testing::TempDir dir;
  ASSERT_TRUE(WriteTable(dir.Path("table.json"), older).ok());
  EXPECT_EQ(testing::ExpectFailedWritesKeepEarlierFiles(dir.path(), [&](Env* env) {
              return WriteTable(dir.Path("table.json"), newer, env);
            }),
            1);
}

TEST(TableTest, JsonShape) {
  Table table;
  table.columns = {"a"};
  table.rows.push_back({std::nan("")});
  const std::string json = TableToJson(table);
  EXPECT_THAT(json, HasSubstr("\"pointbake_table\": 1"));
  auto back = TableFromJson(json, "t.json");
  ASSERT_TRUE(back.ok());
  EXPECT_TRUE(std::holds_alternative<std::monostate>(back->rows[0][0]));  // NaN -> null
}

TEST(TableTest, Errors) {
  EXPECT_THAT(TableFromJson("{", "t.json").status().message(), HasSubstr("t.json: not valid JSON"));
  EXPECT_THAT(TableFromJson("{\"columns\": []}", "t.json").status().message(),
              HasSubstr("not a pointbake table"));
  auto newer = TableFromJson(R"({"pointbake_table": 2, "columns": [], "rows": []})", "t.json");
  EXPECT_EQ(newer.status().code(), Status::Code::kUnsupported);
  EXPECT_THAT(TableFromJson(R"({"pointbake_table": 1, "columns": ["a","b"], "rows": [[1]]})", "t.json")
                  .status()
                  .message(),
              HasSubstr("row 0 has 1 values for 2 columns"));
  EXPECT_THAT(TableFromJson(R"({"pointbake_table": 1, "columns": ["a"], "rows": [[[1]]]})", "t.json")
                  .status()
                  .message(),
              HasSubstr("nested value"));
  Table duplicate;
  duplicate.columns = {"a", "a"};
  EXPECT_EQ(Validate(duplicate).code(), Status::Code::kInvalid);
}

}  // namespace
}  // namespace pb
