// SPDX-License-Identifier: MIT
// A failed result as text for test messages: ASSERT_EQ(failureText(save(...)), "") passes on success and prints the
// error on failure.
#pragma once

#include <expected>
#include <string>

#include "imps/diagnostic.h"
#include "imps/io_error.h"

namespace imps::test {

// "" when `result` holds a value, else its diagnostics as printed (file:line:column: error: ...).
template <class T>
std::string failureText(const std::expected<T, Diagnostics>& result) {
  return result ? std::string() : result.error().str();
}

// "" when `result` holds a value, else "PATH: MESSAGE".
template <class T>
std::string failureText(const IoResult<T>& result) {
  return result ? std::string() : result.error().str();
}

}  // namespace imps::test
