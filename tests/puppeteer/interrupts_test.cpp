// SPDX-License-Identifier: MIT
// Ctrl-C and SIGTERM become a flag the long-running loops poll: raised signals set it instead of killing the
// process, and catchInterrupts() clears it for the next command.
#include "interrupts.h"

#include <gtest/gtest.h>

#include <csignal>

namespace imps::app {
namespace {

// Puts the default handlers back, so Ctrl-C still stops the test binary after these tests.
struct DefaultHandlersAfterwards {
  ~DefaultHandlersAfterwards() {
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
  }
};

TEST(Interrupts, SigintSetsTheFlagInsteadOfKilling) {
  DefaultHandlersAfterwards restore;
  catchInterrupts();
  EXPECT_FALSE(interruptRequested());
  ASSERT_EQ(std::raise(SIGINT), 0);
  EXPECT_TRUE(interruptRequested());
  EXPECT_TRUE(interruptRequested()) << "reading the flag does not clear it";
  catchInterrupts();
  EXPECT_FALSE(interruptRequested()) << "catchInterrupts() starts afresh";
}

TEST(Interrupts, SigtermToo) {
  DefaultHandlersAfterwards restore;
  catchInterrupts();
  ASSERT_EQ(std::raise(SIGTERM), 0);
  EXPECT_TRUE(interruptRequested());
  catchInterrupts();
  EXPECT_FALSE(interruptRequested());
}

}  // namespace
}  // namespace imps::app
