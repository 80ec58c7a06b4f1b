// SPDX-License-Identifier: MIT
// PseudoTerminal (sim/src/pseudo_terminal.cpp): a pair whose slave end is held open in raw mode from the start, so
// bytes pass both ways unchanged (no echo, no line buffering, no CR/LF translation, no signal or EOF characters),
// bytes written before the drivers open the port wait for them, and the drivers closing the port is no hang-up for
// the master; moving hands the pair over, and the destructor closes it.
#include "sim/pseudo_terminal.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <string>

namespace imps::sim {
namespace {

// Reads until `n` bytes came or nothing more arrives within the bound (a generous one: the assertion is on the
// bytes, not on the time).
std::string readSome(int fd, size_t n, int boundMs = 5000) {
  std::string out;
  while (out.size() < n) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, boundMs) <= 0 || !(p.revents & POLLIN)) break;
    char buffer[256];
    const ssize_t got = ::read(fd, buffer, std::min(sizeof buffer, n - out.size()));
    if (got <= 0) break;
    out.append(buffer, size_t(got));
  }
  return out;
}

void writeAll(int fd, const std::string& bytes) {
  ASSERT_EQ(::write(fd, bytes.data(), bytes.size()), ssize_t(bytes.size()));
}

// The drivers' side: the slave opened by path, as a serial port is.
int openPort(const PseudoTerminal& pty) { return ::open(pty.slavePath().c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC); }

PseudoTerminal openPair() {
  auto pty = PseudoTerminal::open();
  EXPECT_TRUE(pty.has_value()) << (pty ? "" : pty.error().str());
  return std::move(*pty);
}

// Every byte value, including those a cooked terminal acts on: CR, LF, ^C, ^D, ^Z, ^S/^Q, DEL, NUL.
std::string everyByte() {
  std::string s;
  for (int b = 0; b < 256; ++b) s += char(b);
  return s;
}

TEST(PseudoTerminal, OpensAPairWhoseSlaveIsATerminalInRawMode) {
  PseudoTerminal pty = openPair();
  EXPECT_GE(pty.master(), 0);
  struct stat st {};
  ASSERT_EQ(::stat(pty.slavePath().c_str(), &st), 0) << pty.slavePath();
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  const int port = openPort(pty);
  ASSERT_GE(port, 0);
  EXPECT_TRUE(::isatty(port));
  termios tio{};
  ASSERT_EQ(::tcgetattr(port, &tio), 0);
  EXPECT_EQ(tio.c_lflag & (ICANON | ECHO | ISIG | IEXTEN), 0u) << "no line editing, echo or signals";
  EXPECT_EQ(tio.c_iflag & (ICRNL | INLCR | IGNCR | IXON | ISTRIP), 0u) << "input untranslated";
  EXPECT_EQ(tio.c_oflag & OPOST, 0u) << "output untranslated";
  EXPECT_EQ(tio.c_cflag & CSIZE, tcflag_t(CS8));
  ::close(port);
}

TEST(PseudoTerminal, EveryByteCrossesBothWaysUnchangedAndUnbuffered) {
  PseudoTerminal pty = openPair();
  const int port = openPort(pty);
  ASSERT_GE(port, 0);
  const std::string bytes = everyByte();
  writeAll(pty.master(), bytes);
  EXPECT_EQ(readSome(port, bytes.size()), bytes) << "armature -> drivers";
  writeAll(port, bytes);
  EXPECT_EQ(readSome(pty.master(), bytes.size()), bytes) << "drivers -> armature";
  // No line buffering: a partial line arrives on its own.
  writeAll(pty.master(), "HEL");
  EXPECT_EQ(readSome(port, 3), "HEL");
  // No echo: what the armature wrote does not come back to it.
  pollfd p{pty.master(), POLLIN, 0};
  EXPECT_EQ(::poll(&p, 1, 0), 0) << "nothing echoed to the master";
  ::close(port);
}

TEST(PseudoTerminal, BytesWrittenBeforeThePortOpensWaitForIt) {
  PseudoTerminal pty = openPair();
  const std::string hello = "HELLO imps-armature 1\r\n";  // a boot message, written before anyone listens
  writeAll(pty.master(), hello);
  const int port = openPort(pty);
  ASSERT_GE(port, 0);
  EXPECT_EQ(readSome(port, hello.size()), hello);
  ::close(port);
}

TEST(PseudoTerminal, ThePortClosingIsNoHangUpForTheMaster) {
  PseudoTerminal pty = openPair();
  for (int round = 0; round < 3; ++round) {
    const int port = openPort(pty);
    ASSERT_GE(port, 0);
    writeAll(pty.master(), "ping");
    EXPECT_EQ(readSome(port, 4), "ping");
    ::close(port);
    pollfd p{pty.master(), POLLIN, 0};
    ASSERT_GE(::poll(&p, 1, 0), 0);
    EXPECT_FALSE(p.revents & POLLHUP) << "round " << round;
  }
  // And the next opener still gets what was written while nobody had the port open.
  writeAll(pty.master(), "again");
  const int port = openPort(pty);
  EXPECT_EQ(readSome(port, 5), "again");
  ::close(port);
}

TEST(PseudoTerminal, MovingHandsThePairOverAndTheDestructorClosesIt) {
  PseudoTerminal a = openPair();
  const int master = a.master();
  const std::string path = a.slavePath();
  PseudoTerminal b(std::move(a));
  EXPECT_EQ(b.master(), master);
  EXPECT_EQ(b.slavePath(), path);
  EXPECT_EQ(a.master(), -1);  // NOLINT(bugprone-use-after-move): the moved-from state is the contract
  // Move-assignment closes the pair it replaces.
  PseudoTerminal c = openPair();
  const int replaced = c.master();
  c = std::move(b);
  EXPECT_EQ(c.master(), master);
  EXPECT_EQ(::fcntl(replaced, F_GETFD), -1) << "the replaced pair's master is closed";
  // The pair still works after the moves.
  const int port = openPort(c);
  ASSERT_GE(port, 0);
  writeAll(c.master(), "moved");
  EXPECT_EQ(readSome(port, 5), "moved");
  { PseudoTerminal gone = std::move(c); }
  EXPECT_EQ(::fcntl(master, F_GETFD), -1) << "the destructor closed the master";
  // With the master gone the port is hung up.
  pollfd p{port, POLLIN, 0};
  EXPECT_EQ(::poll(&p, 1, 5000), 1);
  EXPECT_TRUE(p.revents & (POLLHUP | POLLERR));
  ::close(port);
}

}  // namespace
}  // namespace imps::sim
