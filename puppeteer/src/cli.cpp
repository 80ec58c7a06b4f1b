// SPDX-License-Identifier: MIT
// The command line: `puppeteer <command> …`. Commands live in cli_<topic>.cpp and register themselves here.
#include "cli.h"

#include <CLI/CLI.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "imps/diagnostic.h"
#include "imps/scene_reader.h"

namespace imps::app {

namespace {

// Input files named on the command line that do not exist (or cannot be read), in order: see inputFile().
std::vector<std::string>& missingInputs() {
  static std::vector<std::string> missing;
  return missing;
}

std::string whyUnreadable(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return "no such file";
  if (std::filesystem::is_directory(path, ec)) return "is a directory, not a file";
  if (::access(path.c_str(), R_OK) != 0) return "cannot be read (permission denied)";
  return "";
}

CLI::Validator numberCheck(const char* name, bool allowZero) {
  return CLI::Validator(
      [allowZero](std::string& text) -> std::string {
        double value = 0;
        const bool converted = CLI::detail::lexical_cast(text, value);
        if (converted && std::isfinite(value) && (value > 0 || (allowZero && value == 0))) return "";
        return std::string("expected a number ") + (allowZero ? ">= 0" : "> 0") + ", got '" + text + "'";
      },
      name);
}

}  // namespace

const CLI::Validator& inputFile() {
  static const CLI::Validator v(
      [](std::string& path) {
        if (!whyUnreadable(path).empty()) missingInputs().push_back(path);
        return std::string();
      },
      "FILE");
  return v;
}

const CLI::Validator& positiveNumber() {
  static const CLI::Validator v = numberCheck("POSITIVE", false);
  return v;
}

const CLI::Validator& nonNegativeNumber() {
  static const CLI::Validator v = numberCheck("NONNEGATIVE", true);
  return v;
}

std::string extensionOf(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

int checkOutputPath(std::string_view command, std::string_view option, const std::string& path,
                    std::initializer_list<std::string_view> extensions) {
  const std::string ext = extensionOf(path);
  if (extensions.size() > 0 && std::find(extensions.begin(), extensions.end(), ext) == extensions.end()) {
    std::string known;  // ".obj, .ply or .glb"
    size_t i = 0;
    for (std::string_view e : extensions) {
      if (i > 0) known += i + 1 == extensions.size() ? " or " : ", ";
      known += e;
      ++i;
    }
    std::fprintf(stderr, "puppeteer %.*s: error: %.*s %s: expected a %s file, not %s\n", int(command.size()),
                 command.data(), int(option.size()), option.data(), path.c_str(), known.c_str(),
                 ext.empty() ? "a name without an extension" : ("'" + ext + "'").c_str());
    return kExitUsage;
  }
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    std::fprintf(stderr, "puppeteer %.*s: error: %.*s %s: the directory %s does not exist\n", int(command.size()),
                 command.data(), int(option.size()), option.data(), path.c_str(), dir.string().c_str());
    return kExitIoError;
  }
  return kExitOk;
}

std::string suggestionFor(const CLI::App& app, int argc, char** argv) {
  // ---- The subcommand: the first argument that is not an option.
  const CLI::App* command = nullptr;
  int i = 1;
  for (; i < argc && !command; ++i) {
    const std::string word = argv[i];
    if (word.starts_with("-")) continue;
    std::vector<std::string> names;
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
      if (sub->get_name() == word) command = sub;
      names.push_back(sub->get_name());
    }
    if (command) break;
    const std::string guess = closestMatch(word, names);
    std::string known;
    for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
    return "unknown command '" + word + "'" + (guess.empty() ? " (commands: " + known + ")"
                                                             : "; did you mean '" + guess + "'?");
  }
  if (!command) return "";
  // ---- Its options: the first --name it does not know.
  std::vector<std::string> options;
  for (const CLI::Option* o : command->get_options([](const CLI::Option*) { return true; }))
    for (const std::string& n : o->get_lnames()) options.push_back("--" + n);
  for (++i; i < argc; ++i) {
    const std::string word = argv[i];
    if (!word.starts_with("--") || word == "--") continue;
    const std::string name = word.substr(0, word.find('='));
    if (std::find(options.begin(), options.end(), name) != options.end()) continue;
    const std::string guess = closestMatch(name, options);
    return "unknown option '" + name + "' for " + command->get_name() +
           (guess.empty() ? " (see puppeteer " + command->get_name() + " --help)" : "; did you mean '" + guess + "'?");
  }
  return "";
}

std::optional<LoadedScene> loadScene(const std::string& path) {
  Diagnostics warnings;
  auto read = readSceneFile(path, &warnings);
  if (!read) {
    std::fputs(read.error().str().c_str(), stderr);  // every diagnostic, its warnings included, in file order
    return std::nullopt;
  }
  std::fputs(warnings.str().c_str(), stderr);
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
  missingInputs().clear();
  Commands commands;
  addSceneCommands(app, commands);
  addDeviceCommands(app, commands);
  addTesselatorCommands(app, commands);
  addStretchCommands(app, commands);
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
    // A misspelt command or option gets advice, as the scene reader gives for a misspelt field.
    if (const std::string advice = suggestionFor(app, argc, argv); !advice.empty())
      std::fprintf(stderr, "puppeteer: error: %s\n", advice.c_str());
    else
      app.exit(e);
    return kExitUsage;
  }
  for (const Command& c : commands) {
    if (!c.app->parsed()) continue;
    if (!missingInputs().empty()) {
      for (const std::string& path : missingInputs())
        std::fprintf(stderr, "puppeteer %s: error: %s: %s\n", c.app->get_name().c_str(), path.c_str(),
                     whyUnreadable(path).c_str());
      return kExitInvalidInput;
    }
    return c.run();
  }
  return kExitUsage;
}

}  // namespace imps::app
