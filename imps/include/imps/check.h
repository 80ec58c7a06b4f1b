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
