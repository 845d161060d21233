#include "stages/geometry/core/text_parse.h"

#include <cctype>

#include <charconv>
#include <cstdio>
#include <system_error>

namespace pb {

std::vector<std::string_view> SplitWords(std::string_view line) {
  std::vector<std::string_view> words;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && IsBlankChar(line[i])) ++i;
    const size_t start = i;
    while (i < line.size() && !IsBlankChar(line[i])) ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

size_t SplitWords(std::string_view line, std::string_view* words, size_t max_words) {
  size_t count = 0;
  size_t i = 0;
  while (true) {
    while (i < line.size() && IsBlankChar(line[i])) ++i;
    if (i == line.size()) return count;
    const size_t start = i;
    while (i < line.size() && !IsBlankChar(line[i])) ++i;
    if (count == max_words) return max_words + 1;
    words[count++] = line.substr(start, i - start);
  }
}

bool ParseDouble(std::string_view text, double* value) {
  // from_chars takes no '+' (C++17 [charconv.from.chars]); files written by
  // printf("%+g") or by hand have one. Only one sign, though.
  if (!text.empty() && text[0] == '+') {
    text.remove_prefix(1);
    if (!text.empty() && (text[0] == '+' || text[0] == '-')) return false;
  }
  const char* end = text.data() + text.size();
  const auto result = std::from_chars(text.data(), end, *value);
  return result.ec == std::errc() && result.ptr == end;
}

bool ParseUint(std::string_view text, uint64_t* value) {
  // from_chars for unsigned types already takes neither '-' nor '+'.
  const char* end = text.data() + text.size();
  const auto result = std::from_chars(text.data(), end, *value);
  return result.ec == std::errc() && result.ptr == end;
}

std::string FormatDouble(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

std::string LowerExtension(std::string_view path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string_view::npos || (slash != std::string_view::npos && dot < slash)) return "";
  std::string extension(path.substr(dot));
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

}  // namespace pb
