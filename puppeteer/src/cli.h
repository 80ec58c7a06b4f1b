// SPDX-License-Identifier: MIT
// The command line: every `puppeteer` command registers itself here. Exit codes are documented in docs/cli.md.
#pragma once

#include <functional>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "imps/character.h"
#include "imps/scene.h"

namespace CLI {
class App;
class Validator;
}

namespace imps::app {

// Exit codes of every command.
enum ExitCode : int {
  kExitOk = 0,
  kExitInvalidInput = 1,  // an input file (scene, session, rig map …) has errors; printed as file:line:column
  kExitUsage = 2,         // bad command line
  kExitIoError = 3,       // an output could not be written (nothing was overwritten), or a device failed
  kExitCheckFailed = 4,   // a requested check failed: `mesh --check` found the mesh not a closed 2-manifold
};

// ---- Checks every command shares, so that the same mistake gets the same message and exit code everywhere.

// An input file named on the command line (`->check(inputFile())`). A missing or unreadable input is an input
// error (kExitInvalidInput) for every command, not a usage error: the validator only records the path, and runCli
// reports every missing one after parsing ("puppeteer CMD: error: PATH: no such file"), before the command runs.
const CLI::Validator& inputFile();
// Number checks with readable messages ("--cell: expected a number > 0, got '0'"; CLI11's own print the double
// range's 309-digit bounds).
const CLI::Validator& positiveNumber();
const CLI::Validator& nonNegativeNumber();
// The lower-case extension of `path` with its dot (".png"), "" when it has none.
std::string extensionOf(const std::string& path);
// An output file named on the command line, checked before any work is done. Its extension must be one of
// `extensions` (lower case, with the dot; empty list: any), else a usage error (kExitUsage); its directory must
// exist, else kExitIoError. Prints "puppeteer COMMAND: error: OPTION PATH: …" and returns the exit code, or kExitOk.
int checkOutputPath(std::string_view command, std::string_view option, const std::string& path,
                    std::initializer_list<std::string_view> extensions = {});
// The closest known name to a misspelt subcommand or option in argv, as "did you mean '…'?" advice; "" if none.
std::string suggestionFor(const CLI::App& app, int argc, char** argv);

// A scene file read and compiled into its character.
struct LoadedScene {
  Scene scene;
  Character character;
};
// Reads and compiles `path`, printing its diagnostics (warnings, then the error) to stderr; nullopt on errors
// (the command then exits with kExitInvalidInput).
std::optional<LoadedScene> loadScene(const std::string& path);

// A registered subcommand and what runs it once its arguments are parsed.
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};
using Commands = std::vector<Command>;

// Each command file adds its subcommands to `app` (cli_<topic>.cpp).
void addSceneCommands(CLI::App& app, Commands& commands);  // mesh, check
void addDeviceCommands(CLI::App& app, Commands& commands);  // devices, sim, record
void addTesselatorCommands(CLI::App& app, Commands& commands);  // bench
void addStretchCommands(CLI::App& app, Commands& commands);     // stretch
void addCalibrationCommands(CLI::App& app, Commands& commands);  // calibrate
void addSessionCommands(CLI::App& app, Commands& commands);      // info, convert
void addLiveCommands(CLI::App& app, Commands& commands);         // view, replay, live
void addExportCommands(CLI::App& app, Commands& commands);       // export

int runCli(int argc, char** argv);

}  // namespace imps::app
