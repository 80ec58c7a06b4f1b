// SPDX-License-Identifier: MIT
// The check macros (imps/base/include/imps/check.h): the always-on tier, and the debug tier as a Debug build has it.
// check_release_tier_test.cpp checks the debug tier as a Release build has it (compiled out).
#define IMPS_DEBUG_CHECKS 1
#include "imps/check.h"

#include <gtest/gtest.h>

namespace {

TEST(CheckDeathTest, AlwaysOnChecksAbortWithFileLineAndOperands) {
  const int a = 3, b = 4;
  EXPECT_DEATH(IMPS_CHECK(a == b), "check_test.cpp:[0-9]+: internal error: check failed: a == b");
  EXPECT_DEATH(IMPS_CHECK_LT(b, a), "check failed: b < a \\(4 vs 3\\)");
  IMPS_CHECK_LE(a, b);  // passes quietly
}

TEST(CheckDeathTest, DebugTierChecksLikeTheAlwaysOnOneInDebugBuilds) {
  const int a = 3, b = 4;
  EXPECT_DEATH(IMPS_DCHECK(a == b), "check_test.cpp:[0-9]+: internal error: check failed: a == b");
  EXPECT_DEATH(IMPS_DCHECK_GE(a, b), "check failed: a >= b \\(3 vs 4\\)");
  int evaluated = 0;
  IMPS_DCHECK(++evaluated == 1);
  EXPECT_EQ(evaluated, 1) << "the operands are evaluated once";
}

}  // namespace
