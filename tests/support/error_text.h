// SPDX-License-Identifier: MIT
// The text of a failed result, whatever its error type (a message string, imps::IoError, Diagnostics: anything with
// str()), for failure messages in tests: `ASSERT_TRUE(r) << test::errorOf(r);`.
#pragma once

#include <string>
#include <type_traits>

namespace imps::test {

template <class E>
std::string errorText(const E& error) {
  if constexpr (requires { error.str(); })
    return error.str();
  else if constexpr (std::is_convertible_v<const E&, std::string>)
    return error;
  else
    return "(an error without text)";
}

// "" for a result holding a value, else its error's text.
template <class R>
std::string errorOf(const R& result) {
  return result ? std::string() : errorText(result.error());
}

}  // namespace imps::test
