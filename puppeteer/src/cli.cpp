// The command line: `puppeteer <command> …`. Commands live in cli_<topic>.cpp and register themselves here.
#include "cli.h"

#include <CLI/CLI.hpp>

#include <cstdio>

#include "imps/diagnostic.h"
#include "imps/scene_reader.h"

namespace imps::app {

std::optional<LoadedScene> loadScene(const std::string& path) {
  Diagnostics warnings;
  auto read = readSceneFile(path, &warnings);
  std::fputs(warnings.str().c_str(), stderr);
  if (!read) {
    std::fputs(read.error().str().c_str(), stderr);
    return std::nullopt;
  }
  auto compiled = Character::fromScene(*read);
  if (!compiled) {
    std::fputs(compiled.error().str().c_str(), stderr);
    return std::nullopt;
  }
  return LoadedScene{std::move(*read), std::move(*compiled)};
}

int runCli(int argc, char** argv) {
  CLI::App app{"IMPS Puppeteer: implicit-surface characters driven by joint-encoder armatures"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "puppeteer 0.1.0");
  Commands commands;
  addSceneCommands(app, commands);
  addDeviceCommands(app, commands);
  addTesselatorCommands(app, commands);
  addCalibrationCommands(app, commands);
  addSessionCommands(app, commands);
  addLiveCommands(app, commands);
  addExportCommands(app, commands);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitUsage;
  }
  for (const Command& c : commands)
    if (c.app->parsed()) return c.run();
  return kExitUsage;
}

}  // namespace imps::app
