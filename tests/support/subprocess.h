// SPDX-License-Identifier: MIT
// Running a program as a user would, for command-line tests: its exit code and what it printed.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace imps::test {

struct ProgramRun {
  int exitCode = -1;   // the process's exit status; 128 + N when killed by signal N
  std::string out;     // stdout (with mergeOutput: stdout and stderr, in the order written to one pipe)
  std::string err;     // stderr (empty with mergeOutput)
};

struct ProgramOptions {
  std::vector<std::string> unsetEnv = {"DISPLAY", "WAYLAND_DISPLAY"};  // headless unless a test says otherwise
  std::vector<std::string> setEnv = {"IMPS_NO_HUGEPAGES=1"};           // NAME=VALUE
  bool mergeOutput = false;  // stdout and stderr into the same pipe (as `cmd 2>&1 | less`)
  std::string input;         // written to stdin, then closed
  std::string stderrPath;    // open this file (e.g. a pseudo-terminal's slave) as stderr instead of capturing it
};

// Runs `program` with `args` (argv[1..]) and waits for it. Fails the calling test when it cannot be started.
ProgramRun runProgram(const std::filesystem::path& program, const std::vector<std::string>& args,
                      const ProgramOptions& options = {});

}  // namespace imps::test
