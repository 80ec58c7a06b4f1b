// SPDX-License-Identifier: MIT
// A pseudo-terminal pair for serving a simulated armature by path (sim/pseudo_terminal.h).
#include "sim/pseudo_terminal.h"

#include <fcntl.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace imps::sim {

IoResult<PseudoTerminal> PseudoTerminal::open() {
  PseudoTerminal pty;
  auto fail = [](const char* step) { return std::unexpected(IoError::fromErrno("", step, errno)); };
  pty.master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (pty.master_ < 0) return fail("cannot create a pseudo-terminal");
  if (::grantpt(pty.master_) != 0 || ::unlockpt(pty.master_) != 0) return fail("cannot unlock the pseudo-terminal");
  char name[128];
  if (::ptsname_r(pty.master_, name, sizeof name) != 0) return fail("cannot name the pseudo-terminal");
  pty.slavePath_ = name;
  pty.holder_ = ::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (pty.holder_ < 0) return fail("cannot open the pseudo-terminal's slave end");
  termios tio{};
  if (::tcgetattr(pty.holder_, &tio) != 0) return fail("cannot read the pseudo-terminal's settings");
  ::cfmakeraw(&tio);
  if (::tcsetattr(pty.holder_, TCSANOW, &tio) != 0) return fail("cannot set the pseudo-terminal to raw mode");
  return pty;
}

PseudoTerminal::PseudoTerminal(PseudoTerminal&& other) noexcept
    : master_(std::exchange(other.master_, -1)),
      holder_(std::exchange(other.holder_, -1)),
      slavePath_(std::move(other.slavePath_)) {}

PseudoTerminal& PseudoTerminal::operator=(PseudoTerminal&& other) noexcept {
  if (this != &other) {
    close();
    master_ = std::exchange(other.master_, -1);
    holder_ = std::exchange(other.holder_, -1);
    slavePath_ = std::move(other.slavePath_);
  }
  return *this;
}

PseudoTerminal::~PseudoTerminal() { close(); }

void PseudoTerminal::close() {
  if (holder_ >= 0) ::close(holder_);
  if (master_ >= 0) ::close(master_);
  holder_ = master_ = -1;
}

}  // namespace imps::sim
