// SPDX-License-Identifier: MIT
/* Test-only LD_PRELOAD interposer: turns umockdev-mocked /dev/hidrawN nodes into something that behaves like
 * hidraw for hidapi (tests/support/umockdev_hid.h). Never linked into the app; must come before
 * libumockdev-preload.so.0 in LD_PRELOAD.
 *
 * Why: umockdev backs a non-tty device node with a plain file, and a pty (its only other choice) merges writes,
 * so report boundaries would not survive. Here open("/dev/hidrawN") connects a SOCK_SEQPACKET socket to
 * $UMOCKDEV_DIR/imps-hidraw/hidrawN (served by the test's fake armature) when the mocked node exists: one
 * message per read, like hidraw, and POLLHUP when the fake device closes its end (unplug), like hidraw.
 * The hidraw ioctls a socket lacks are answered from the testbed: HIDIOCGRDESCSIZE/HIDIOCGRDESC from sysfs
 * report_descriptor, HIDIOCGRAWINFO from the hid device's HID_ID, HIDIOCGFEATURE(n) from the file
 * imps-hidraw/hidrawN.feature-<ID> (the report, ID byte first), HIDIOCSFEATURE(n) appended to
 * imps-hidraw/hidrawN.sent-features. Every other path and descriptor goes to the next library untouched. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <linux/hidraw.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#define SOCKET_DIR "/imps-hidraw/"

/* The hidraw node name ("hidraw0") a descriptor of ours is connected to, or 0 when it is not ours. */
static int ourNode(int fd, char* name, size_t size) {
  struct sockaddr_un peer;
  socklen_t len = sizeof peer;
  memset(&peer, 0, sizeof peer);
  if (getpeername(fd, (struct sockaddr*)&peer, &len) != 0 || peer.sun_family != AF_UNIX) return 0;
  const char* dir = strstr(peer.sun_path, SOCKET_DIR);
  if (!dir) return 0;
  snprintf(name, size, "%s", dir + strlen(SOCKET_DIR));
  return strncmp(name, "hidraw", 6) == 0;
}

/* Reads a whole testbed file ($UMOCKDEV_DIR + relative) into buf; returns its size or -1. */
static ssize_t readTestbedFile(const char* relative, unsigned char* buf, size_t size) {
  const char* root = getenv("UMOCKDEV_DIR");
  if (!root) return -1;
  char path[4096];
  snprintf(path, sizeof path, "%s%s", root, relative);
  FILE* f = fopen(path, "rb");
  if (!f) return -1;
  const size_t n = fread(buf, 1, size, f);
  fclose(f);
  return (ssize_t)n;
}

static int openHidraw(const char* path, int flags) {
  const char* root = getenv("UMOCKDEV_DIR");
  if (!root || strncmp(path, "/dev/hidraw", 11) != 0) return -2;
  char node[4096], sock[4096];
  struct stat st;
  snprintf(node, sizeof node, "%s%s", root, path);
  snprintf(sock, sizeof sock, "%s" SOCKET_DIR "%s", root, path + 5);
  if (lstat(sock, &st) != 0) return -2; /* not one of the test's hidraw nodes */
  if (lstat(node, &st) != 0) {          /* unplugged: the node is gone */
    errno = ENOENT;
    return -1;
  }
  const int fd = socket(AF_UNIX, SOCK_SEQPACKET | ((flags & O_CLOEXEC) ? SOCK_CLOEXEC : 0) |
                                     ((flags & O_NONBLOCK) ? SOCK_NONBLOCK : 0), 0);
  if (fd < 0) return -1;
  struct sockaddr_un addr;
  memset(&addr, 0, sizeof addr);
  addr.sun_family = AF_UNIX;
  snprintf(addr.sun_path, sizeof addr.sun_path, "%s", sock);
  if (connect(fd, (struct sockaddr*)&addr, sizeof addr) != 0) {
    close(fd);
    errno = ENODEV; /* what opening a hidraw node of a vanished device gives */
    return -1;
  }
  return fd;
}

#define WRAP_OPEN(fn)                                                 \
  int fn(const char* path, int flags, ...) {                          \
    static int (*next)(const char*, int, ...);                        \
    mode_t mode = 0;                                                  \
    if ((flags & O_CREAT) || (flags & O_TMPFILE) == O_TMPFILE) {      \
      va_list ap;                                                     \
      va_start(ap, flags);                                            \
      mode = va_arg(ap, mode_t);                                      \
      va_end(ap);                                                     \
    }                                                                 \
    const int fd = openHidraw(path, flags);                           \
    if (fd != -2) return fd;                                          \
    if (!next) next = (int (*)(const char*, int, ...))dlsym(RTLD_NEXT, #fn); \
    return next(path, flags, mode);                                   \
  }
WRAP_OPEN(open)
WRAP_OPEN(open64)

static int hidrawIoctl(const char* node, unsigned long request, void* arg) {
  char rel[512];
  if (request == HIDIOCGRDESCSIZE || request == HIDIOCGRDESC) {
    struct hidraw_report_descriptor desc;
    snprintf(rel, sizeof rel, "/sys/class/hidraw/%s/device/report_descriptor", node);
    const ssize_t n = readTestbedFile(rel, desc.value, sizeof desc.value);
    if (n < 0) {
      errno = EIO;
      return -1;
    }
    if (request == HIDIOCGRDESCSIZE) {
      *(int*)arg = (int)n;
      return 0;
    }
    struct hidraw_report_descriptor* out = arg;
    if (out->size > (unsigned)n || out->size > HID_MAX_DESCRIPTOR_SIZE) {
      errno = EINVAL;
      return -1;
    }
    memcpy(out->value, desc.value, out->size);
    return 0;
  }
  if (request == HIDIOCGRAWINFO) {
    unsigned char uevent[4096];
    snprintf(rel, sizeof rel, "/sys/class/hidraw/%s/device/uevent", node);
    const ssize_t n = readTestbedFile(rel, uevent, sizeof uevent - 1);
    if (n < 0) {
      errno = EIO;
      return -1;
    }
    uevent[n] = 0;
    const char* id = strstr((const char*)uevent, "HID_ID=");
    unsigned bus = 0, vendor = 0, product = 0;
    if (!id || sscanf(id, "HID_ID=%x:%x:%x", &bus, &vendor, &product) != 3) {
      errno = EIO;
      return -1;
    }
    struct hidraw_devinfo* info = arg;
    info->bustype = bus;
    info->vendor = (short)vendor;
    info->product = (short)product;
    return 0;
  }
  if (_IOC_TYPE(request) == 'H' && _IOC_NR(request) == 0x07 && _IOC_DIR(request) == (_IOC_WRITE | _IOC_READ)) {
    /* HIDIOCGFEATURE(len): arg[0] holds the report ID on entry; returns the bytes written, ID included. */
    unsigned char* buf = arg;
    const size_t len = _IOC_SIZE(request);
    unsigned char report[4096];
    snprintf(rel, sizeof rel, SOCKET_DIR "%s.feature-%u", node, len ? buf[0] : 0u);
    const ssize_t n = readTestbedFile(rel, report, sizeof report);
    if (n <= 0) {
      errno = EPIPE; /* what a device that stalls an unknown feature report gives */
      return -1;
    }
    const size_t copy = (size_t)n < len ? (size_t)n : len;
    memcpy(buf, report, copy);
    return (int)copy;
  }
  if (_IOC_TYPE(request) == 'H' && _IOC_NR(request) == 0x06 && _IOC_DIR(request) == (_IOC_WRITE | _IOC_READ)) {
    /* HIDIOCSFEATURE(len): recorded for the test to inspect. */
    const char* root = getenv("UMOCKDEV_DIR");
    char path[4096];
    snprintf(path, sizeof path, "%s" SOCKET_DIR "%s.sent-features", root ? root : "", node);
    FILE* f = fopen(path, "ab");
    if (f) {
      fwrite(arg, 1, _IOC_SIZE(request), f);
      fclose(f);
    }
    return (int)_IOC_SIZE(request);
  }
  errno = ENOTTY;
  return -1;
}

int ioctl(int fd, unsigned long request, ...) {
  static int (*next)(int, unsigned long, ...);
  va_list ap;
  va_start(ap, request);
  void* arg = va_arg(ap, void*);
  va_end(ap);
  char node[256];
  if (_IOC_TYPE(request) == 'H' && ourNode(fd, node, sizeof node)) return hidrawIoctl(node, request, arg);
  if (!next) next = (int (*)(int, unsigned long, ...))dlsym(RTLD_NEXT, "ioctl");
  return next(fd, request, arg);
}
