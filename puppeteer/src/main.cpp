// SPDX-License-Identifier: MIT
// The `puppeteer` program: every command of the product's command line.
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "cli.h"

namespace {

// Large meshes touch hundreds of megabytes; with 4 KiB pages that is tens of thousands of page faults, which on a
// virtual machine cost several microseconds each (the 1000-ball benchmark: 0.85 s instead of 0.26 s). glibc backs
// malloc with transparent huge pages only when GLIBC_TUNABLES says so at process start, so the program re-executes
// itself once with glibc.malloc.hugetlb=1 added, and a 256 MiB heap growth step so the heap grows in huge pages
// (address space only; untouched pages cost nothing). About 5 ms. IMPS_NO_HUGEPAGES=1 turns this off; tunables the
// user set are kept.
void useHugePages(char** argv) {
  if (std::getenv("IMPS_NO_HUGEPAGES") || std::getenv("IMPS_HUGEPAGES_SET")) return;
  const char* existing = std::getenv("GLIBC_TUNABLES");
  std::string tunables = existing ? existing : "";
  if (tunables.find("glibc.malloc.hugetlb") != std::string::npos) return;
  tunables += std::string(tunables.empty() ? "" : ":") + "glibc.malloc.hugetlb=1:glibc.malloc.top_pad=268435456";
  setenv("GLIBC_TUNABLES", tunables.c_str(), 1);
  setenv("IMPS_HUGEPAGES_SET", "1", 1);
  execv("/proc/self/exe", argv);
  // Not re-executed (no /proc?): carry on with normal pages.
}

}  // namespace

int main(int argc, char** argv) {
  useHugePages(argv);
  // A file-size limit (ulimit -f) must fail a write like a full disk does (EFBIG: a message, the I/O exit code, the
  // temporary file removed), not kill the process mid-save with SIGXFSZ.
  std::signal(SIGXFSZ, SIG_IGN);
  // Line-buffered stdout even into a pipe: a report line and a following stderr message (`cmd 2>&1 | less`) then
  // arrive in the order they were printed, not stdout's block at exit after every message.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  return imps::app::runCli(argc, argv);
}
