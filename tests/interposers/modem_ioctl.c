// SPDX-License-Identifier: MIT
/* Test-only LD_PRELOAD interposer: fakes the modem-line ioctls on terminals that have none (umockdev's pty-backed
 * /dev/ttyACM0), so libserialport's sp_open() succeeds. Never linked into the app; must come before
 * libumockdev-preload.so.0 in LD_PRELOAD. Real serial ports are unaffected (their ioctls succeed first). */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <stdarg.h>
#include <sys/ioctl.h>

static int modemBits = TIOCM_DSR | TIOCM_CTS | TIOCM_CD; /* the lines a connected device drives */

int ioctl(int fd, unsigned long request, ...) {
  static int (*next)(int, unsigned long, ...);
  va_list ap;
  va_start(ap, request);
  void* arg = va_arg(ap, void*);
  va_end(ap);
  if (!next) next = (int (*)(int, unsigned long, ...))dlsym(RTLD_NEXT, "ioctl");
  const int result = next(fd, request, arg);
  if (result == 0 || (errno != ENOTTY && errno != EINVAL)) return result;
  switch (request) {
    case TIOCMGET: *(int*)arg = modemBits; return 0;
    case TIOCMSET: modemBits = *(const int*)arg; return 0;
    case TIOCMBIS: modemBits |= *(const int*)arg; return 0;
    case TIOCMBIC: modemBits &= ~*(const int*)arg; return 0;
    default: return result;
  }
}
