// SPDX-License-Identifier: MIT
// Small text helpers for messages in drivers/ (private; g++ 12 has no <format>).
#pragma once

#include <cstdio>
#include <sstream>
#include <string>

namespace imps::drivers {

// Concatenates the operands' stream output.
template <class... Args>
std::string cat(const Args&... args) {
  std::ostringstream out;
  (out << ... << args);
  return out.str();
}

// Four lower-case hex digits (USB vendor and product ids).
inline std::string hex4(unsigned v) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "%04x", v & 0xFFFFu);
  return buf;
}

}  // namespace imps::drivers
