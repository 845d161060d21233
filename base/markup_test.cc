#include "base/markup.h"

#include <gtest/gtest.h>

namespace pb {
namespace {

TEST(MarkupTest, EscapesTheFiveSpecialCharactersAndNothingElse) {
  EXPECT_EQ(EscapeMarkup("a <b> & \"c\" 'd' é"), "a &lt;b&gt; &amp; &quot;c&quot; &#39;d&#39; é");
  EXPECT_EQ(EscapeMarkup(""), "");
  EXPECT_EQ(EscapeMarkup("&amp;"), "&amp;amp;");
}

}  // namespace
}  // namespace pb
