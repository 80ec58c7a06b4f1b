// SPDX-License-Identifier: MIT
// Always-on invariant checks for programming errors (not for bad input: that gets a Diagnostic).
#pragma once

#include <cstdio>
#include <cstdlib>

// IMPS_CHECK(cond): aborts with file:line and the condition text when cond is false.
#define IMPS_CHECK(cond)                                                                      \
  do {                                                                                        \
    if (!(cond)) {                                                                            \
      std::fprintf(stderr, "%s:%d: internal error: check failed: %s\n", __FILE__, __LINE__, #cond); \
      std::abort();                                                                           \
    }                                                                                         \
  } while (0)

// IMPS_CHECK_OP(a, op, b): like IMPS_CHECK(a op b) but also prints both operand values.
#define IMPS_CHECK_OP(a, op, b)                                                               \
  do {                                                                                        \
    const auto imps_check_a_ = (a);                                                           \
    const auto imps_check_b_ = (b);                                                           \
    if (!(imps_check_a_ op imps_check_b_)) {                                                  \
      std::fprintf(stderr, "%s:%d: internal error: check failed: %s %s %s (%g vs %g)\n",      \
                   __FILE__, __LINE__, #a, #op, #b, static_cast<double>(imps_check_a_),       \
                   static_cast<double>(imps_check_b_));                                       \
      std::abort();                                                                           \
    }                                                                                         \
  } while (0)
#define IMPS_CHECK_EQ(a, b) IMPS_CHECK_OP(a, ==, b)
#define IMPS_CHECK_LT(a, b) IMPS_CHECK_OP(a, <, b)
#define IMPS_CHECK_LE(a, b) IMPS_CHECK_OP(a, <=, b)
#define IMPS_CHECK_GE(a, b) IMPS_CHECK_OP(a, >=, b)

// The debug tier, for the innermost loops (per cell, per particle, per half-edge) where an always-on check would
// cost: IMPS_DCHECK and IMPS_DCHECK_EQ/LT/LE/GE check like the macros above when IMPS_DEBUG_CHECKS is 1, which it is
// by default in builds without NDEBUG (Debug); otherwise they compile to nothing and do not evaluate their operands.
#ifndef IMPS_DEBUG_CHECKS
#ifdef NDEBUG
#define IMPS_DEBUG_CHECKS 0
#else
#define IMPS_DEBUG_CHECKS 1
#endif
#endif
#if IMPS_DEBUG_CHECKS
#define IMPS_DCHECK(cond) IMPS_CHECK(cond)
#define IMPS_DCHECK_OP(a, op, b) IMPS_CHECK_OP(a, op, b)
#else
#define IMPS_DCHECK(cond)        \
  do {                           \
    if (false) (void)(cond);     \
  } while (0)
#define IMPS_DCHECK_OP(a, op, b) \
  do {                           \
    if (false) (void)((a)op(b)); \
  } while (0)
#endif
#define IMPS_DCHECK_EQ(a, b) IMPS_DCHECK_OP(a, ==, b)
#define IMPS_DCHECK_LT(a, b) IMPS_DCHECK_OP(a, <, b)
#define IMPS_DCHECK_LE(a, b) IMPS_DCHECK_OP(a, <=, b)
#define IMPS_DCHECK_GE(a, b) IMPS_DCHECK_OP(a, >=, b)
