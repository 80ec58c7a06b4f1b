// SPDX-License-Identifier: MIT
// UTF-8 well-formedness (imps/base/include/imps/utf8.h): where the first ill-formed byte is, and repair with U+FFFD.
#include "imps/utf8.h"

#include <gtest/gtest.h>

#include <string>
#include <string_view>

namespace imps {
namespace {

using namespace std::string_view_literals;

constexpr std::string_view kReplacement = "\xEF\xBF\xBD";  // U+FFFD

TEST(FirstInvalidUtf8, WellFormedTextIsValidToTheEnd) {
  for (std::string_view s : {""sv, "plain ASCII"sv, "caf\xC3\xA9"sv, "\xE2\x82\xAC 5"sv, "\xF0\x9F\x98\x80"sv,
                             "nul\0inside"sv})
    EXPECT_EQ(firstInvalidUtf8(s), s.size()) << s;
}

TEST(FirstInvalidUtf8, TheBoundariesOfEachLengthAreValid) {
  for (std::string_view s : {"\x7F"sv, "\xC2\x80"sv, "\xDF\xBF"sv, "\xE0\xA0\x80"sv, "\xED\x9F\xBF"sv /* U+D7FF */,
                             "\xEE\x80\x80"sv /* U+E000 */, "\xEF\xBF\xBF"sv, "\xF0\x90\x80\x80"sv,
                             "\xF4\x8F\xBF\xBF"sv /* U+10FFFF */})
    EXPECT_EQ(firstInvalidUtf8(s), s.size()) << testing::PrintToString(s);
}

TEST(FirstInvalidUtf8, FindsTheFirstIllFormedByte) {
  struct Case {
    std::string_view text;
    size_t offset;
    const char* why;
  };
  for (const Case& c : {Case{"ab\xFF" "cd", 2, "a byte that never occurs"},
                        Case{"\x80", 0, "a stray continuation byte"},
                        Case{"ok\xC0\xAF", 2, "overlong '/' in two bytes"},
                        Case{"\xC1\xBF", 0, "overlong in two bytes"},
                        Case{"\xE0\x80\xAF", 0, "overlong in three bytes"},
                        Case{"\xF0\x8F\xBF\xBF", 0, "overlong in four bytes"},
                        Case{"x\xED\xA0\x80", 1, "a surrogate (U+D800)"},
                        Case{"\xED\xBF\xBF", 0, "a surrogate (U+DFFF)"},
                        Case{"\xF4\x90\x80\x80", 0, "above U+10FFFF"},
                        Case{"\xF8\x88\x80\x80\x80", 0, "a five-byte form"},
                        Case{"\xC3\xA9\xE2\x82", 2, "a sequence cut short by the end"},
                        Case{"\xE2\x82" "A", 0, "a sequence cut short by ASCII"}})
    EXPECT_EQ(firstInvalidUtf8(c.text), c.offset) << c.why;
}

TEST(ToValidUtf8, WellFormedTextIsUnchanged) {
  const std::string_view text = "Gr\xC3\xBC\xC3\x9F" "e \xE2\x82\xAC \xF0\x9F\x98\x80";
  EXPECT_EQ(toValidUtf8(text), text);
  EXPECT_EQ(toValidUtf8(""), "");
}

TEST(ToValidUtf8, EachIllFormedSequenceBecomesOneReplacementCharacter) {
  const std::string r(kReplacement);
  EXPECT_EQ(toValidUtf8("a\xFF" "b"), "a" + r + "b");
  EXPECT_EQ(toValidUtf8("a\xE2\x82"), "a" + r);                 // a lead byte and its continuation bytes, cut short
  EXPECT_EQ(toValidUtf8("\xE2\x82" "b"), r + "b");
  EXPECT_EQ(toValidUtf8("x\xED\xA0\x80y"), "x" + r + "y");      // a surrogate is one sequence
  EXPECT_EQ(toValidUtf8("\x80\x80"), r + r);                    // stray bytes, one each
  EXPECT_EQ(toValidUtf8("\xC3\xA9\xFF\xC3\xA9"), "\xC3\xA9" + r + "\xC3\xA9");  // neighbours are kept
}

TEST(ToValidUtf8, EveryTwoByteInputComesOutWellFormed) {
  // The repair's own promise: whatever goes in, valid UTF-8 comes out, and valid input is kept as it is.
  for (int a = 0; a < 256; ++a)
    for (int b = 0; b < 256; ++b) {
      const char bytes[] = {char(a), char(b), 'z'};
      const std::string_view in(bytes, 3);
      const std::string out = toValidUtf8(in);
      ASSERT_EQ(firstInvalidUtf8(out), out.size()) << a << " " << b;
      ASSERT_TRUE(out.ends_with('z')) << a << " " << b;  // nothing after the bad bytes is swallowed
      if (firstInvalidUtf8(in) == in.size()) {
        ASSERT_EQ(out, in) << a << " " << b;
      }
      ASSERT_EQ(toValidUtf8(out), out) << "not idempotent at " << a << " " << b;
    }
}

}  // namespace
}  // namespace imps
