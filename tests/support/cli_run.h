// SPDX-License-Identifier: MIT
// Command-line tests: the real `puppeteer` program run as a user would, and tables of failures checked against the
// exit codes and messages docs/cli.md promises.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "subprocess.h"

namespace imps::test {

// docs/cli.md, "Exit codes".
inline constexpr int kCliOk = 0, kCliInvalidInput = 1, kCliUsage = 2, kCliIo = 3, kCliCheckFailed = 4;

// A file of the source tree (examples/…, tests/data/…) as an absolute path.
std::string sourceFile(const std::string& relative);

// Whether `text` contains `phrase`; the failure message shows both.
::testing::AssertionResult contains(const std::string& text, const std::string& phrase);
// How many times `phrase` occurs in `text` (non-overlapping).
size_t occurrences(const std::string& text, const std::string& phrase);
// A run's exit code and both streams, for failure messages.
std::string describe(const ProgramRun& run);

// One command line that must fail: its exit code and a phrase its message must contain.
struct CliFailure {
  std::string name;
  std::vector<std::string> args;
  int exitCode;
  std::string stderrHas;
};

// Runs every row through `program` and checks its exit code, its message and that it reports one cause: at most one
// line of stderr saying "error:" (an input error may print a file's several diagnostics: at most 8).
void expectFailures(const std::filesystem::path& program, const std::vector<CliFailure>& table);

// The program under test, for binaries built with IMPS_PUPPETEER_BINARY (tests/CMakeLists.txt).
#ifdef IMPS_PUPPETEER_BINARY
inline std::filesystem::path puppeteerProgram() { return IMPS_PUPPETEER_BINARY; }
inline ProgramRun runPuppeteer(const std::vector<std::string>& args, const ProgramOptions& options = {}) {
  return runProgram(puppeteerProgram(), args, options);
}
inline void expectFailures(const std::vector<CliFailure>& table) { expectFailures(puppeteerProgram(), table); }
#endif

}  // namespace imps::test
