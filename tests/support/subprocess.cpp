// SPDX-License-Identifier: MIT
// runProgram: fork, redirect stdout/stderr to temporary files (or one), exec, wait.
#include "subprocess.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>

namespace imps::test {

namespace {

// An unnamed temporary file (deleted on close) for one stream.
int tempFd() {
  char name[] = "/tmp/imps_run_XXXXXX";
  const int fd = ::mkstemp(name);
  if (fd >= 0) ::unlink(name);
  return fd;
}

std::string readAll(int fd) {
  std::string text;
  ::lseek(fd, 0, SEEK_SET);
  char buffer[65536];
  for (ssize_t n; (n = ::read(fd, buffer, sizeof buffer)) > 0;) text.append(buffer, size_t(n));
  return text;
}

}  // namespace

ProgramRun runProgram(const std::filesystem::path& program, const std::vector<std::string>& args,
                      const ProgramOptions& options) {
  ProgramRun run;
  const int outFd = tempFd(), errFd = options.mergeOutput ? outFd : tempFd(), inFd = tempFd();
  if (outFd < 0 || errFd < 0 || inFd < 0) {
    ADD_FAILURE() << "cannot create temporary files";
    return run;
  }
  if (!options.input.empty() && ::write(inFd, options.input.data(), options.input.size()) < 0)
    ADD_FAILURE() << "cannot write the input";
  ::lseek(inFd, 0, SEEK_SET);
  std::vector<std::string> argv{program.string()};
  argv.insert(argv.end(), args.begin(), args.end());
  std::vector<char*> cargv;
  for (std::string& a : argv) cargv.push_back(a.data());
  cargv.push_back(nullptr);

  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(inFd, STDIN_FILENO);
    ::dup2(outFd, STDOUT_FILENO);
    if (!options.stderrPath.empty()) {
      const int fd = ::open(options.stderrPath.c_str(), O_WRONLY | O_NOCTTY);
      if (fd < 0) ::_exit(126);
      ::dup2(fd, STDERR_FILENO);
    } else {
      ::dup2(errFd, STDERR_FILENO);
    }
    for (const std::string& name : options.unsetEnv) ::unsetenv(name.c_str());
    for (const std::string& nv : options.setEnv) ::putenv(const_cast<char*>(nv.c_str()));
    ::execv(cargv[0], cargv.data());
    ::_exit(127);
  }
  if (pid < 0) {
    ADD_FAILURE() << "fork failed";
    return run;
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  run.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  run.out = readAll(outFd);
  if (!options.mergeOutput) run.err = readAll(errFd);
  ::close(outFd);
  if (!options.mergeOutput) ::close(errFd);
  ::close(inFd);
  return run;
}

}  // namespace imps::test
