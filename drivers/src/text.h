// SPDX-License-Identifier: MIT
// Small text helpers for messages in drivers/ (private; g++ 12 has no <format>).
#pragma once

#include <cstdio>
#include <expected>
#include <sstream>
#include <string>
#include <utility>

#include "imps/diagnostic.h"

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

// A result holding one error at `loc` (an empty loc for a value that is not from a file: "error: MESSAGE").
inline std::unexpected<Diagnostics> diagnosticError(SourceLoc loc, std::string message) {
  Diagnostics d;
  d.error(std::move(loc), std::move(message));
  return std::unexpected(std::move(d));
}

// The first diagnostic's message alone (no position, no "error: "), to wrap into a message about something else.
inline std::string firstMessage(const Diagnostics& d) {
  return d.all().empty() ? std::string() : d.all().front().message;
}
// The first diagnostic as printed ("report descriptor:12: error: …"), without a newline.
inline std::string firstError(const Diagnostics& d) { return d.all().empty() ? std::string() : d.all().front().str(); }

}  // namespace imps::drivers
