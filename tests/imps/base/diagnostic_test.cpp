// SPDX-License-Identifier: MIT
// Diagnostics (imps/base/include/imps/diagnostic.h): `file:line:column: severity: message`, error counting, the cap
// on printed diagnostics, and "did you mean" suggestions.
#include "imps/diagnostic.h"

#include <gtest/gtest.h>

#include <string>

namespace imps {
namespace {

Diagnostic at(Severity severity, SourceLoc loc, std::string message) {
  return {severity, std::move(loc), std::move(message)};
}

TEST(Diagnostic, PrintsThePositionThatIsKnown) {
  EXPECT_EQ(at(Severity::Error, {"a.wrl", 3, 7}, "expected '{'").str(), "a.wrl:3:7: error: expected '{'");
  EXPECT_EQ(at(Severity::Warning, {"a.wrl", 3, 0}, "unused").str(), "a.wrl:3: warning: unused");
  EXPECT_EQ(at(Severity::Note, {"a.wrl", 0, 0}, "defined here").str(), "a.wrl: note: defined here");
  EXPECT_EQ(at(Severity::Error, {"", 0, 0}, "no input").str(), "error: no input");
}

TEST(Diagnostic, AColumnWithoutALineIsNotPrinted) {
  EXPECT_EQ(at(Severity::Error, {"a.wrl", 0, 5}, "m").str(), "a.wrl: error: m");
}

TEST(Diagnostics, CountsErrorsButNotWarningsOrNotes) {
  Diagnostics d;
  EXPECT_FALSE(d.hasErrors());
  d.warning({"f", 1, 1}, "w");
  d.note({"f", 1, 2}, "n");
  EXPECT_FALSE(d.hasErrors());
  EXPECT_EQ(d.errorCount(), 0);
  d.error({"f", 2, 1}, "e1");
  d.error({"f", 3, 1}, "e2");
  EXPECT_TRUE(d.hasErrors());
  EXPECT_EQ(d.errorCount(), 2);
  ASSERT_EQ(d.all().size(), 4u);
  EXPECT_EQ(d.all()[0].severity, Severity::Warning);
  EXPECT_EQ(d.all()[1].severity, Severity::Note);
  EXPECT_EQ(d.all()[3].message, "e2");
  EXPECT_EQ(d.all()[3].loc.line, 3);
}

TEST(Diagnostics, PrintsOnePerLineInTheOrderReported) {
  Diagnostics d;
  d.error({"s.json", 4, 2}, "expected a number");
  d.warning({"s.json", 1, 1}, "unknown key 'raduis'");
  d.note({"s.json", 1, 1}, "did you mean 'radius'?");
  EXPECT_EQ(d.str(),
            "s.json:4:2: error: expected a number\n"
            "s.json:1:1: warning: unknown key 'raduis'\n"
            "s.json:1:1: note: did you mean 'radius'?\n");
  EXPECT_EQ(Diagnostics().str(), "");
}

TEST(Diagnostics, PrintsAtMostTheCapThenCountsTheRest) {
  Diagnostics d;
  const int total = int(Diagnostics::kMaxPrinted) + 50;
  for (int i = 1; i <= total; ++i) d.error({"big.wrl", i, 1}, "bad entry");
  const std::string text = d.str();
  size_t lines = 0;
  for (char c : text) lines += c == '\n';
  EXPECT_EQ(lines, Diagnostics::kMaxPrinted + 1);
  const std::string lastShown = "big.wrl:" + std::to_string(Diagnostics::kMaxPrinted) + ":1: error: bad entry\n";
  EXPECT_NE(text.find(lastShown), std::string::npos);
  EXPECT_EQ(text.find("big.wrl:" + std::to_string(Diagnostics::kMaxPrinted + 1) + ":"), std::string::npos);
  EXPECT_TRUE(text.ends_with(lastShown + "... and 50 more (" + std::to_string(total) +
                             " errors in all; only the first " + std::to_string(Diagnostics::kMaxPrinted) +
                             " are shown)\n"))
      << text.substr(text.size() - 200);
  EXPECT_EQ(d.all().size(), size_t(total));  // nothing is dropped, only not printed
}

TEST(Diagnostics, ExactlyTheCapIsPrintedWithoutASummary) {
  Diagnostics d;
  for (size_t i = 0; i < Diagnostics::kMaxPrinted; ++i) d.warning({"w", 1, 1}, "x");
  EXPECT_EQ(d.str().find("more"), std::string::npos);
}

TEST(Diagnostics, TheSummaryCountsErrorsAmongAllDiagnostics) {
  Diagnostics d;
  for (size_t i = 0; i < Diagnostics::kMaxPrinted; ++i) d.warning({"w", 1, 1}, "x");
  for (int i = 0; i < 3; ++i) d.error({"w", 2, 1}, "y");
  EXPECT_TRUE(d.str().ends_with("... and 3 more (3 errors in all; only the first 100 are shown)\n")) << d.str();
}

TEST(Diagnostics, AppendKeepsOrderAndAddsErrorCounts) {
  Diagnostics a, b;
  a.error({"a", 1, 1}, "first");
  b.warning({"b", 1, 1}, "second");
  b.error({"b", 2, 1}, "third");
  a.append(b);
  EXPECT_EQ(a.errorCount(), 2);
  EXPECT_EQ(a.str(), "a:1:1: error: first\nb:1:1: warning: second\nb:2:1: error: third\n");
  EXPECT_EQ(b.all().size(), 2u);  // the source is unchanged
}

TEST(Diagnostics, FirstErrorIsTheFirstErrorOnOneLineSkippingWarnings) {
  Diagnostics d;
  EXPECT_EQ(d.firstError(), "");
  d.warning({"a.wrl", 1, 2}, "only a warning");
  EXPECT_EQ(d.firstError(), "");
  d.error({"a.wrl", 3, 4}, "first");
  d.error({"b.wrl"}, "second");
  EXPECT_EQ(d.firstError(), "a.wrl:3:4: error: first");
}

TEST(Diagnostics, SingleErrorHoldsOneError) {
  const Diagnostics d = singleError({"out.session"}, "cannot create session file: File exists");
  EXPECT_EQ(d.errorCount(), 1);
  ASSERT_EQ(d.all().size(), 1u);
  EXPECT_EQ(d.str(), "out.session: error: cannot create session file: File exists\n");
  EXPECT_EQ(singleError({}, "no place").firstError(), "error: no place");
}

TEST(ClosestMatch, SuggestsATypoFixIgnoringCase) {
  const std::vector<std::string> keys = {"radius", "center", "strength", "blendGroup"};
  EXPECT_EQ(closestMatch("raduis", keys), "radius");
  EXPECT_EQ(closestMatch("RADIUS", keys), "radius");
  EXPECT_EQ(closestMatch("centre", keys), "center");
  EXPECT_EQ(closestMatch("blendgroup", keys), "blendGroup");
}

TEST(ClosestMatch, SuggestsNothingWhenNoCandidateIsClose) {
  const std::vector<std::string> keys = {"radius", "center"};
  EXPECT_EQ(closestMatch("transparency", keys), "");
  EXPECT_EQ(closestMatch("x", {}), "");
}

}  // namespace
}  // namespace imps
