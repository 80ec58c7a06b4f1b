// SPDX-License-Identifier: MIT
// Command-line test helpers (see cli_run.h).
#include "cli_run.h"

#include <algorithm>

namespace imps::test {

std::string sourceFile(const std::string& relative) { return std::string(IMPS_SOURCE_DIR) + "/" + relative; }

::testing::AssertionResult contains(const std::string& text, const std::string& phrase) {
  if (text.find(phrase) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << phrase << "' not found in:\n" << text;
}

size_t occurrences(const std::string& text, const std::string& phrase) {
  size_t n = 0;
  for (size_t at = text.find(phrase); at != std::string::npos; at = text.find(phrase, at + phrase.size())) ++n;
  return n;
}

std::string describe(const ProgramRun& run) {
  return "exit " + std::to_string(run.exitCode) + "\nstdout: " + run.out + "\nstderr: " + run.err;
}

void expectFailures(const std::filesystem::path& program, const std::vector<CliFailure>& table) {
  for (const CliFailure& f : table) {
    const ProgramRun run = runProgram(program, f.args);
    EXPECT_EQ(run.exitCode, f.exitCode) << f.name << "\n" << describe(run);
    EXPECT_TRUE(contains(run.err, f.stderrHas)) << f.name;
    size_t errorLines = 0;  // one cause: one line saying "error:" ("…: error: --osc-out X: osc:1:1: error: …" is one)
    for (size_t start = 0; start < run.err.size();) {
      const size_t end = std::min(run.err.find('\n', start), run.err.size());
      if (run.err.substr(start, end - start).find("error:") != std::string::npos) ++errorLines;
      start = end + 1;
    }
    EXPECT_LE(errorLines, f.exitCode == kCliInvalidInput ? 8u : 1u) << f.name << ": more than one cause:\n" << run.err;
  }
}

}  // namespace imps::test
