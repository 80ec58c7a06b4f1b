// SPDX-License-Identifier: MIT
// Tests that need an X display and an OpenGL 3.3 context (the live app's renderer and window). CTest runs them
// under xvfb-run with IMPS_REQUIRE_GL=1 (tests/CMakeLists.txt's puppeteer_gl), where a missing display fails them;
// run anywhere else without a display they are skipped.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <string_view>

namespace imps::test {

// Whether a display is there to open windows on.
inline bool haveDisplay() {
  const char* display = std::getenv("DISPLAY");
  return display && *display;
}

// Whether a missing display is a failure (IMPS_REQUIRE_GL set and not "0").
inline bool displayRequired() {
  const char* required = std::getenv("IMPS_REQUIRE_GL");
  return required && *required && std::string_view(required) != "0";
}

}  // namespace imps::test

// Skips the calling test when there is no display, or fails it when one is required.
#define IMPS_NEED_DISPLAY()                                                                    \
  do {                                                                                         \
    if (!::imps::test::haveDisplay()) {                                                        \
      if (::imps::test::displayRequired()) FAIL() << "no DISPLAY, but IMPS_REQUIRE_GL is set"; \
      GTEST_SKIP() << "no DISPLAY (run under xvfb-run; ctest -R puppeteer_gl does)";           \
    }                                                                                          \
  } while (false)
