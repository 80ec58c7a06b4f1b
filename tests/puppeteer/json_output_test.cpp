// SPDX-License-Identifier: MIT
// `--json` output: one indented document on stdout that reads back equal, keys in insertion order, a final newline,
// and bytes that are not UTF-8 written as U+FFFD instead of throwing.
#include "json_output.h"

#include <gtest/gtest.h>

#include <string>

namespace imps::app {
namespace {

std::string printed(const Json& report) {
  testing::internal::CaptureStdout();
  printJson(report);
  return testing::internal::GetCapturedStdout();
}

TEST(JsonOutput, OneIndentedDocumentThatReadsBack) {
  Json report;
  report["scene"] = "examples/simple_biped.wrl";
  report["triangles"] = 5268;
  report["bounds"] = {{"min", {-0.5, 0.0, -0.25}}, {"max", {0.5, 1.8, 0.25}}};
  report["ok"] = true;
  const std::string out = printed(report);
  ASSERT_FALSE(out.empty());
  EXPECT_EQ(out.back(), '\n');
  EXPECT_EQ(out.find("\n\n"), std::string::npos);
  EXPECT_NE(out.find("\n  \"triangles\": 5268"), std::string::npos) << "two-space indent:\n" << out;
  // Keys stay in the order the command added them (ordered_json), so reports read top to bottom.
  EXPECT_LT(out.find("\"scene\""), out.find("\"triangles\""));
  EXPECT_LT(out.find("\"triangles\""), out.find("\"bounds\""));
  EXPECT_EQ(Json::parse(out), report);
}

TEST(JsonOutput, BytesThatAreNotUtf8BecomeReplacementCharacters) {
  Json report;
  report["device"] = std::string("arm\xff\xfe") + "ature";  // a device's name with stray bytes
  std::string out;
  ASSERT_NO_THROW(out = printed(report));
  const Json back = Json::parse(out);
  EXPECT_EQ(back["device"].get<std::string>(),
            "arm\xEF\xBF\xBD\xEF\xBF\xBD"
            "ature");
}

TEST(JsonOutput, ScalarsAndEmptyDocuments) {
  EXPECT_EQ(printed(Json::object()), "{}\n");
  EXPECT_EQ(printed(Json::array()), "[]\n");
  EXPECT_EQ(printed(Json(3)), "3\n");
}

}  // namespace
}  // namespace imps::app
