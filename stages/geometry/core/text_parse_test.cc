#include "stages/geometry/core/text_parse.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace pb {
namespace {

using Words = std::vector<std::string_view>;

TEST(TextParseTest, SplitWordsOnSpacesTabsAndCr) {
  EXPECT_EQ(SplitWords("  element\tvertex  12 \r"), (Words{"element", "vertex", "12"}));
  EXPECT_EQ(SplitWords("a\rb"), (Words{"a", "b"}));
  EXPECT_EQ(SplitWords("one"), (Words{"one"}));
  EXPECT_TRUE(SplitWords("").empty());
  EXPECT_TRUE(SplitWords(" \t\r ").empty());
  // Other characters, commas included, belong to words.
  EXPECT_EQ(SplitWords("1,2 x\fy"), (Words{"1,2", "x\fy"}));
}

TEST(TextParseTest, SplitWordsIntoABoundedArray) {
  std::string_view words[3];
  EXPECT_EQ(SplitWords(" 1 2\t3 ", words, 3), 3u);
  EXPECT_EQ(words[0], "1");
  EXPECT_EQ(words[1], "2");
  EXPECT_EQ(words[2], "3");
  EXPECT_EQ(SplitWords("a b", words, 3), 2u);
  EXPECT_EQ(SplitWords("", words, 3), 0u);
  EXPECT_EQ(SplitWords("a b c d e", words, 3), 4u);  // more than max_words
  EXPECT_EQ(words[2], "c");
  EXPECT_EQ(SplitWords("a", words, 0), 1u);
  EXPECT_EQ(SplitWords("  ", words, 0), 0u);
}

TEST(TextParseTest, ParseDoubleAcceptsWholeNumbers) {
  double value = 0;
  const std::pair<std::string_view, double> accepted[] = {
      {"1", 1},        {"-2.5", -2.5},  {"+3", 3},         {".5", 0.5},
      {"5.", 5},       {"1e-3", 1e-3},  {"1E+3", 1000},    {"-0", -0.0},
      {"007", 7},      {"0.1", 0.1},    {"652341.0625", 652341.0625},
      {"1.7976931348623157e308", std::numeric_limits<double>::max()},
  };
  for (const auto& [text, expected] : accepted) {
    EXPECT_TRUE(ParseDouble(text, &value)) << text;
    EXPECT_EQ(value, expected) << text;
  }
  EXPECT_TRUE(std::signbit((ParseDouble("-0", &value), value)));
}

TEST(TextParseTest, ParseDoubleReturnsNonFiniteValues) {
  double value = 0;
  for (std::string_view text : {"inf", "INF", "infinity", "+inf", "+Infinity"}) {
    ASSERT_TRUE(ParseDouble(text, &value)) << text;
    EXPECT_EQ(value, std::numeric_limits<double>::infinity()) << text;
  }
  ASSERT_TRUE(ParseDouble("-inf", &value));
  EXPECT_EQ(value, -std::numeric_limits<double>::infinity());
  for (std::string_view text : {"nan", "NaN", "-nan", "+nan", "nan(123)"}) {
    ASSERT_TRUE(ParseDouble(text, &value)) << text;
    EXPECT_TRUE(std::isnan(value)) << text;
  }
}

TEST(TextParseTest, ParseDoubleRejectsPartsAndJunk) {
  double value = 0;
  for (std::string_view text : {"", " 1", "1 ", "1,5", "1e", "0x10", "+-1", "++1", "+", "-",
                                "1.2.3", "e5", "12abc", "1e400", "-1e400", "1e-400", "inf5",
                                "na"}) {
    EXPECT_FALSE(ParseDouble(text, &value)) << "'" << text << "'";
  }
}

TEST(TextParseTest, ParseUintTakesDigitsOnly) {
  uint64_t value = 0;
  ASSERT_TRUE(ParseUint("0", &value));
  EXPECT_EQ(value, 0u);
  ASSERT_TRUE(ParseUint("0012", &value));
  EXPECT_EQ(value, 12u);
  ASSERT_TRUE(ParseUint("18446744073709551615", &value));
  EXPECT_EQ(value, std::numeric_limits<uint64_t>::max());
  for (std::string_view text : {"", "-1", "+1", " 1", "1 ", "1.0", "1e3", "0x1",
                                "18446744073709551616", "12abc"}) {
    EXPECT_FALSE(ParseUint(text, &value)) << "'" << text << "'";
  }
}

TEST(TextParseTest, FormatDoubleRoundTrips) {
  EXPECT_EQ(FormatDouble(1.5), "1.5");
  EXPECT_EQ(FormatDouble(-3), "-3");
  EXPECT_EQ(FormatDouble(0.1), "0.10000000000000001");
  EXPECT_EQ(FormatDouble(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(FormatDouble(-std::numeric_limits<double>::infinity()), "-inf");
  EXPECT_EQ(FormatDouble(std::numeric_limits<double>::quiet_NaN()), "nan");
  for (double v : {652341.0625, 1e-300, 123456789.123456789, -0.3}) {
    double back = 0;
    ASSERT_TRUE(ParseDouble(FormatDouble(v), &back));
    EXPECT_EQ(back, v);
  }
}

TEST(TextParseTest, LowerExtensionOfTheLastComponentOnly) {
  EXPECT_EQ(LowerExtension("scans/Room.E57"), ".e57");
  EXPECT_EQ(LowerExtension("a.b/scan"), "");
  EXPECT_EQ(LowerExtension("archive.tar.GZ"), ".gz");
  EXPECT_EQ(LowerExtension("noext"), "");
}

}  // namespace
}  // namespace pb
