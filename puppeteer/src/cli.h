// The command line: parses arguments and runs one command. Exit codes are documented in docs/cli.md.
#pragma once

namespace imps::app {

// Exit codes of every command.
enum ExitCode : int {
  kExitOk = 0,
  kExitInvalidInput = 1,  // a scene (or other input file) has errors; they were printed as file:line:column
  kExitUsage = 2,         // bad command line
  kExitIoError = 3,       // an output could not be written (nothing was overwritten)
};

int runCli(int argc, char** argv);

}  // namespace imps::app
