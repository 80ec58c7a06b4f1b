// SPDX-License-Identifier: MIT
// --json reports.
#include "json_output.h"

#include <cstdio>

namespace imps::app {

void printJson(const Json& report) {
  const std::string text = report.dump(2, ' ', false, Json::error_handler_t::replace);
  std::fwrite(text.data(), 1, text.size(), stdout);
  std::fputc('\n', stdout);
  std::fflush(stdout);
}

}  // namespace imps::app
