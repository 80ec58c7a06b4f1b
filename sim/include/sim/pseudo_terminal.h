// SPDX-License-Identifier: MIT
// A pseudo-terminal pair for serving a simulated armature where the drivers open it by path, like a real serial
// port (`puppeteer sim --pty`, the pty-backed tests and the soak benchmark).
#pragma once

#include <expected>
#include <string>

#include "imps/io_error.h"

namespace imps::sim {

// Owns both ends. The simulator writes and reads `master()`; the drivers open `slavePath()`. The slave end is also
// held open here, in raw mode, from the start: in a new terminal's default cooked mode the bytes the armature
// writes before the drivers open the port (its boot HELLO) would be mangled by the line discipline, and the master
// would see a hang-up each time the drivers close the port. Move-only; closing happens in the destructor.
class PseudoTerminal {
 public:
  // Creates the pair. The error (no path: the pair has none yet) says which step failed, with the OS's reason.
  static IoResult<PseudoTerminal> open();

  PseudoTerminal(PseudoTerminal&& other) noexcept;
  PseudoTerminal& operator=(PseudoTerminal&& other) noexcept;
  PseudoTerminal(const PseudoTerminal&) = delete;
  PseudoTerminal& operator=(const PseudoTerminal&) = delete;
  ~PseudoTerminal();

  int master() const { return master_; }
  const std::string& slavePath() const { return slavePath_; }

 private:
  PseudoTerminal() = default;
  void close();

  int master_ = -1;
  int holder_ = -1;  // the slave end, kept open in raw mode
  std::string slavePath_;
};

}  // namespace imps::sim
