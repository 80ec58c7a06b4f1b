// SPDX-License-Identifier: MIT
// The `puppeteer` program's dispatcher (puppeteer/src/main.cpp with runCli): help, version, every command's help,
// the exit code of a missing or unknown command with its suggestion, and the same behaviour whether or not the
// program re-executes itself for huge pages.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cli_run.h"

namespace imps::app {
namespace {

using test::contains;
using test::describe;
using test::kCliOk;
using test::kCliUsage;
using test::runPuppeteer;

const std::vector<std::string> kCommands = {"mesh",    "check", "render",  "devices",   "sim",
                                            "record",  "bench", "stretch", "calibrate", "info",
                                            "convert", "view",  "replay",  "live",      "export"};

// --help lists every command, exit 0; every command has its own --help, exit 0, with its usage line.
TEST(Main, HelpListsEveryCommandAndEachHasItsOwn) {
  const test::ProgramRun help = runPuppeteer({"--help"});
  ASSERT_EQ(help.exitCode, kCliOk) << describe(help);
  for (const std::string& command : kCommands) {
    EXPECT_TRUE(contains(help.out, "  " + command + " ")) << command;
    const test::ProgramRun own = runPuppeteer({command, "--help"});
    EXPECT_EQ(own.exitCode, kCliOk) << command << "\n" << describe(own);
    EXPECT_TRUE(contains(own.out, command)) << command;
    EXPECT_TRUE(contains(own.out, "--help")) << command;
  }
}

TEST(Main, VersionIsOneLine) {
  const test::ProgramRun run = runPuppeteer({"--version"});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  EXPECT_EQ(run.out.rfind("puppeteer ", 0), 0u) << run.out;
  EXPECT_EQ(test::occurrences(run.out, "\n"), 1u) << run.out;
}

// No command, an unknown one (with a suggestion when one is close, else the list), an unknown global option: exit 2.
TEST(Main, AMissingOrUnknownCommandIsAUsageError) {
  test::expectFailures({
      {"no command", {}, kCliUsage, "A subcommand is required"},
      {"close", {"rendr"}, kCliUsage, "unknown command 'rendr'; did you mean 'render'?"},
      {"close too", {"calibarte"}, kCliUsage, "did you mean 'calibrate'?"},
      {"nothing close", {"xyzzyplugh"}, kCliUsage, "(commands: mesh, check, render"},
      {"global option", {"--frobnicate"}, kCliUsage, "A subcommand is required"},
  });
}

// The program re-executes itself once with glibc's huge-page tunables unless IMPS_NO_HUGEPAGES is set: its
// arguments, output and exit code are the same either way.
TEST(Main, HugePagesReexecutionKeepsArgumentsAndExitCodes) {
  test::ProgramOptions withHugePages;
  withHugePages.setEnv = {};
  for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
           {"--version"}, {"check", test::sourceFile("examples/beanito.wrl")}, {"rendr"}}) {
    const test::ProgramRun plain = runPuppeteer(args);
    const test::ProgramRun huge = runPuppeteer(args, withHugePages);
    EXPECT_EQ(huge.exitCode, plain.exitCode) << args[0];
    EXPECT_EQ(huge.out, plain.out) << args[0];
    EXPECT_EQ(huge.err, plain.err) << args[0];
  }
}

}  // namespace
}  // namespace imps::app
