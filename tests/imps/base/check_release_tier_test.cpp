// SPDX-License-Identifier: MIT
// The debug tier of imps/base/include/imps/check.h as Release builds have it: compiled out, operands never
// evaluated, so the innermost loops pay nothing. (check_test.cpp checks it as Debug builds have it.)
#define IMPS_DEBUG_CHECKS 0
#include "imps/check.h"

#include <gtest/gtest.h>

namespace {

TEST(CheckReleaseTier, DebugChecksAreCompiledOutAndDoNotEvaluateTheirOperands) {
  int evaluated = 0;
  IMPS_DCHECK(++evaluated == 42);
  IMPS_DCHECK_EQ(++evaluated, 42);
  IMPS_DCHECK_LT(++evaluated, 0);
  EXPECT_EQ(evaluated, 0);
}

}  // namespace
