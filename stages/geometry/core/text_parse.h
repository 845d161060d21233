// Small text helpers shared by the text-format scan readers (PLY headers and
// ascii bodies, PCD, XYZ/PTS, PTX): splitting a line into words and strict
// number parsing on std::from_chars (locale-independent, no allocation).
//
// Blanks: ' ', '\t' and '\r' separate words. '\r' counts so that a stray CR
// (old Mac OS line ends, which BufferedInput leaves inside a line) reads as
// a blank.
//
// Numbers: the whole text must be the number: no leading or trailing blanks,
// nothing after it. Callers split first, then parse each word.
#ifndef PB_STAGES_GEOMETRY_TEXT_PARSE_H_
#define PB_STAGES_GEOMETRY_TEXT_PARSE_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace pb {

// True for ' ', '\t' and '\r'.
inline bool IsBlankChar(char c) { return c == ' ' || c == '\t' || c == '\r'; }

// The blank-separated words of `line`, as views into it; none for a blank line.
std::vector<std::string_view> SplitWords(std::string_view line);

// The same into `words[0 .. max_words)`, without allocating. Returns the word
// count, or max_words + 1 if the line has more words (the first max_words are
// stored).
size_t SplitWords(std::string_view line, std::string_view* words, size_t max_words);

// Parses a whole decimal floating-point number, as std::from_chars with
// chars_format::general does, plus one optional leading '+':
//   accepted: "1", "-2.5", "+3", ".5", "5.", "1e-3", "1E+3", "inf", "-Infinity",
//             "nan", "NAN", "nan(123)" (non-finite values are returned: callers
//             decide whether a NaN or infinity is an error);
//   rejected: "", " 1", "1 ", "1,5", "1e", "0x10", "+-1", "++1", and values
//             outside the range of double ("1e400"; also "1e-400", which
//             libstdc++ reports as out of range rather than rounding to 0).
// On failure *value is unspecified.
bool ParseDouble(std::string_view text, double* value);

// Parses a whole unsigned decimal integer: digits only (no sign, no '+', no
// blanks, no "0x"), leading zeros allowed, at most 2^64 - 1.
bool ParseUint(std::string_view text, uint64_t* value);

// `value` with 17 significant digits (printf "%.17g"): reads back exactly;
// "nan", "inf" and "-inf" for the non-finite values.
std::string FormatDouble(double value);

// The extension of a file name, lower case, with its dot ("scan.E57" ->
// ".e57"); empty when the last path component has none.
std::string LowerExtension(std::string_view path);

}  // namespace pb

#endif  // PB_STAGES_GEOMETRY_TEXT_PARSE_H_
