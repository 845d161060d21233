// Table: the `table` artifact (metrics, statistics), a small typed table
// stored as JSON that any tool reads:
//
//   {
//     "pointbake_table": 1,                 <- signature + format version
//     "columns": ["points", "min_x_m", ...], <- unique names; units in names
//     "rows": [[35947, -0.0947, ...], ...]   <- one array per row, one value
//   }                                           per column
//
// Values are null, booleans, integers (int64), floating point numbers
// (double; NaN and infinities are written as null because JSON has no such
// numbers) or strings. Readers ignore unknown top-level keys, so later
// versions may add some ("units", "title") without bumping the version.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "base/env.h"
#include "base/status.h"

namespace pb {

inline constexpr int kTableVersion = 1;

using TableValue = std::variant<std::monostate, bool, int64_t, double, std::string>;

struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<TableValue>> rows;  // each row has columns.size() values

  static constexpr size_t npos = static_cast<size_t>(-1);
  // Index of a column by name, or npos.
  size_t column_index(std::string_view name) const;
  // The value in `row` under column `name`; monostate if there is no such column.
  TableValue get(size_t row, std::string_view name) const;
};

// The value as a double if it is a number (int64 or double), else NaN.
double TableNumber(const TableValue& value);

// Status::Invalid for duplicate column names or rows of the wrong width.
Status Validate(const Table& table);

std::string TableToJson(const Table& table);
// `source` names the text in errors (a path).
Expected<Table> TableFromJson(std::string_view json_text, const std::string& source);

// Writes durably (env->WriteFileAtomic): on failure `path` keeps what it held.
Status WriteTable(const std::string& path, const Table& table, Env* env = Env::Default());
Expected<Table> ReadTable(const std::string& path);

}  // namespace pb
