#include "stages/geometry/core/table.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>

#include "base/env.h"

namespace pb {

size_t Table::column_index(std::string_view name) const {
  for (size_t i = 0; i < columns.size(); ++i) {
    if (columns[i] == name) return i;
  }
  return npos;
}

TableValue Table::get(size_t row, std::string_view name) const {
  assert(row < rows.size());
  const size_t column = column_index(name);
  if (column == npos || column >= rows[row].size()) return std::monostate{};
  return rows[row][column];
}

double TableNumber(const TableValue& value) {
  if (const auto* integer = std::get_if<int64_t>(&value)) return static_cast<double>(*integer);
  if (const auto* number = std::get_if<double>(&value)) return *number;
  return std::numeric_limits<double>::quiet_NaN();
}

Status Validate(const Table& table) {
  std::set<std::string_view> seen;
  for (const std::string& column : table.columns) {
    if (!seen.insert(column).second) return Status::Invalid("table: duplicate column '" + column + "'");
  }
  for (size_t r = 0; r < table.rows.size(); ++r) {
    if (table.rows[r].size() != table.columns.size()) {
      return Status::Invalid("table: row " + std::to_string(r) + " has " +
                             std::to_string(table.rows[r].size()) + " values for " +
                             std::to_string(table.columns.size()) + " columns");
    }
  }
  return Status::Ok();
}

namespace {

nlohmann::json ToJson(const TableValue& value) {
  struct Visitor {
    nlohmann::json operator()(std::monostate) const { return nullptr; }
    nlohmann::json operator()(bool b) const { return b; }
    nlohmann::json operator()(int64_t i) const { return i; }
    nlohmann::json operator()(double d) const {
      if (!std::isfinite(d)) return nullptr;
      return d;
    }
    nlohmann::json operator()(const std::string& s) const { return s; }
  };
  return std::visit(Visitor{}, value);
}

}  // namespace

std::string TableToJson(const Table& table) {
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& row : table.rows) {
    nlohmann::json values = nlohmann::json::array();
    for (const TableValue& value : row) values.push_back(ToJson(value));
    rows.push_back(std::move(values));
  }
  nlohmann::json document = nlohmann::json::object();
  document["pointbake_table"] = kTableVersion;
  document["columns"] = table.columns;
  document["rows"] = std::move(rows);
  return document.dump(1) + "\n";
}

Expected<Table> TableFromJson(std::string_view json_text, const std::string& source) {
  nlohmann::json document =
      nlohmann::json::parse(json_text.begin(), json_text.end(), nullptr, /*allow_exceptions=*/false);
  if (document.is_discarded()) return Status::Corrupt(source + ": not valid JSON");
  if (!document.is_object() || !document.contains("pointbake_table")) {
    return Status::Corrupt(source + ": not a pointbake table (no \"pointbake_table\" key)");
  }
  const nlohmann::json& version = document["pointbake_table"];
  if (!version.is_number_integer()) {
    return Status::Corrupt(source + ": \"pointbake_table\" must be an integer version");
  }
  if (version.get<int64_t>() != kTableVersion) {
    return Status::Unsupported(source + ": table format version " + version.dump() +
                               "; this build reads version " + std::to_string(kTableVersion));
  }
  Table table;
  const nlohmann::json& columns = document.value("columns", nlohmann::json());
  if (!columns.is_array()) return Status::Corrupt(source + ": \"columns\" must be an array of strings");
  for (const nlohmann::json& column : columns) {
    if (!column.is_string()) return Status::Corrupt(source + ": \"columns\" must be an array of strings");
    table.columns.push_back(column.get<std::string>());
  }
  const nlohmann::json& rows = document.value("rows", nlohmann::json());
  if (!rows.is_array()) return Status::Corrupt(source + ": \"rows\" must be an array of arrays");
  for (size_t r = 0; r < rows.size(); ++r) {
    const nlohmann::json& row = rows[r];
    if (!row.is_array()) return Status::Corrupt(source + ": row " + std::to_string(r) + " is not an array");
    std::vector<TableValue> values;
    for (const nlohmann::json& cell : row) {
      if (cell.is_null()) {
        values.emplace_back(std::monostate{});
      } else if (cell.is_boolean()) {
        values.emplace_back(cell.get<bool>());
      } else if (cell.is_number_integer() &&
                 !(cell.is_number_unsigned() &&
                   cell.get<uint64_t>() > uint64_t(std::numeric_limits<int64_t>::max()))) {
        values.emplace_back(cell.get<int64_t>());
      } else if (cell.is_number()) {
        values.emplace_back(cell.get<double>());
      } else if (cell.is_string()) {
        values.emplace_back(cell.get<std::string>());
      } else {
        return Status::Corrupt(source + ": row " + std::to_string(r) +
                               " holds a nested value; cells are null, bool, number or string");
      }
    }
    table.rows.push_back(std::move(values));
  }
  PB_RETURN_IF_ERROR(Validate(table).WithContext(source));
  return table;
}

Status WriteTable(const std::string& path, const Table& table, Env* env) {
  PB_RETURN_IF_ERROR(Validate(table).WithContext("writing " + path));
  return env->WriteFileAtomic(path, TableToJson(table));
}

Expected<Table> ReadTable(const std::string& path) {
  PB_ASSIGN_OR_RETURN(std::string text, Env::Default()->ReadFile(path));
  return TableFromJson(text, path);
}

}  // namespace pb
