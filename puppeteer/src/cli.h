// The command line: every `puppeteer` command registers itself here. Exit codes are documented in docs/cli.md.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "imps/character.h"
#include "imps/scene.h"

namespace CLI {
class App;
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
void addCalibrationCommands(CLI::App& app, Commands& commands);  // calibrate
void addSessionCommands(CLI::App& app, Commands& commands);      // info, convert
void addLiveCommands(CLI::App& app, Commands& commands);         // view, replay, live

int runCli(int argc, char** argv);

}  // namespace imps::app
