// SPDX-License-Identifier: MIT
// The progress line: drawn on stderr with a carriage return and erase-to-end-of-line when enabled, redrawn by its
// ticker, erased by done() (and by the destructor), silent when disabled; IMPS_NO_PROGRESS turns the default off.
#include "progress.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <thread>

namespace imps::app {
namespace {

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(Progress, DrawsThePhaseAndErasesItWhenDone) {
  testing::internal::CaptureStderr();
  {
    Progress progress("mesh", true);
    EXPECT_TRUE(progress.enabled());
    progress.phase("polygonizing");
    progress.done();
  }
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(err.rfind("\r\033[Kpuppeteer mesh: polygonizing … ", 0), 0u) << err;
  EXPECT_NE(err.find(" s"), std::string::npos);
  // The line is erased at the end: nothing but the erase follows the last drawing.
  ASSERT_GE(err.size(), 4u);
  EXPECT_EQ(err.substr(err.size() - 4), "\r\033[K");
  EXPECT_EQ(err.find('\n'), std::string::npos) << "a progress line never scrolls";
}

TEST(Progress, TheTickerRedrawsWithTheTimeSpent) {
  testing::internal::CaptureStderr();
  {
    Progress progress("render", true);
    progress.phase("frame 1/3");
    std::this_thread::sleep_for(std::chrono::milliseconds(700));
  }  // the destructor erases the line and stops the ticker
  const std::string err = testing::internal::GetCapturedStderr();
  // Drawn at once, then every 200 ms: at least two redraws in 0.7 s (a loaded machine may skip one).
  EXPECT_GE(count(err, "puppeteer render: frame 1/3 … "), 3u) << err;
  EXPECT_EQ(err.substr(err.size() - 4), "\r\033[K");
}

TEST(Progress, APhaseAfterDoneShowsTheLineAgain) {
  testing::internal::CaptureStderr();
  {
    Progress progress("export", true);
    progress.phase("writing a.ply");
    progress.done();
    progress.phase("writing b.ply");
    progress.done();
    progress.done();  // a second done() draws nothing
  }
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(count(err, "writing a.ply"), 1u) << err;
  EXPECT_EQ(count(err, "writing b.ply"), 1u) << err;
  EXPECT_EQ(count(err, "\r\033[K"), 4u) << "two drawings, two erasures";
}

TEST(Progress, DisabledPrintsNothing) {
  testing::internal::CaptureStderr();
  {
    Progress progress("mesh", false);
    EXPECT_FALSE(progress.enabled());
    progress.phase("polygonizing");
    progress.done();
  }
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

TEST(Progress, NoProgressVariableTurnsTheDefaultOff) {
  const char* old = std::getenv("IMPS_NO_PROGRESS");
  const std::string saved = old ? old : "";
  ::setenv("IMPS_NO_PROGRESS", "1", 1);
  EXPECT_FALSE(Progress::stderrIsTerminal());
  EXPECT_FALSE(Progress("mesh").enabled());
  if (old) {
    ::setenv("IMPS_NO_PROGRESS", saved.c_str(), 1);
  } else {
    ::unsetenv("IMPS_NO_PROGRESS");
  }
}

}  // namespace
}  // namespace imps::app
