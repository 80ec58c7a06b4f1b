// SPDX-License-Identifier: MIT
// The serial-port adapter: the only file that touches libserialport. Also reads the port's sysfs entries (driver,
// FTDI latency timer) because they belong to the same "what is this port" question.
#include "drivers/serial_transport.h"

#include "text.h"
#include "imps/clock.h"

#include <fcntl.h>
#include <libserialport.h>
#include <poll.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <cstdio>
#include <sstream>
#include <fstream>

namespace imps::drivers {

namespace {

std::string spError(std::string_view what) {
  char* message = sp_last_error_message();
  std::string text = cat(what, ": ", message ? message : "unknown error");
  sp_free_error_message(message);
  return text;
}

// libserialport's last failure on `path`: its message, and the OS error code it kept.
IoError spFailure(std::string path, std::string_view what) {
  const int code = sp_last_error_code();
  return IoError{std::move(path), spError(what), code};
}

std::string baseName(const std::string& path) { return std::filesystem::path(path).filename().string(); }

// sysfs attribute of the tty's device (e.g. /sys/class/tty/ttyUSB0/device/latency_timer); "" when absent.
std::filesystem::path ttyDeviceAttribute(const std::string& portPath, const char* attribute) {
  return std::filesystem::path("/sys/class/tty") / baseName(portPath) / "device" / attribute;
}

std::string readDriver(const std::string& portPath) {
  std::error_code ec;
  const auto target = std::filesystem::read_symlink(ttyDeviceAttribute(portPath, "driver"), ec);
  return ec ? std::string() : target.filename().string();
}

std::optional<int> readLatencyTimer(const std::string& portPath) {
  std::ifstream in(ttyDeviceAttribute(portPath, "latency_timer"));
  int ms = 0;
  if (in >> ms) return ms;
  return std::nullopt;
}

bool latencyTimerWritable(const std::string& portPath) {
  return ::access(ttyDeviceAttribute(portPath, "latency_timer").c_str(), W_OK) == 0;
}

bool writeLatencyTimer(const std::string& portPath, int ms) {
  std::ofstream out(ttyDeviceAttribute(portPath, "latency_timer"));
  out << ms << '\n';
  out.flush();
  return static_cast<bool>(out);
}

// Fills `info` from an sp_port (name, description, USB identity) and from sysfs.
void describe(sp_port* port, SerialPortInfo& info) {
  info.path = sp_get_port_name(port);
  if (const char* d = sp_get_port_description(port)) info.description = d;
  info.isUsb = sp_get_port_transport(port) == SP_TRANSPORT_USB;
  if (info.isUsb) {
    int vid = 0, pid = 0;
    if (sp_get_port_usb_vid_pid(port, &vid, &pid) == SP_OK) {
      info.vendorId = static_cast<uint16_t>(vid);
      info.productId = static_cast<uint16_t>(pid);
    }
    if (const char* s = sp_get_port_usb_serial(port)) info.serialNumber = s;
    if (const char* s = sp_get_port_usb_manufacturer(port)) info.manufacturer = s;
    if (const char* s = sp_get_port_usb_product(port)) info.product = s;
  }
  info.driver = readDriver(info.path);
  if (info.vendorId == kFtdiVendorId || info.driver == "ftdi_sio") {
    info.latencyTimerMs = readLatencyTimer(info.path);
    info.latencyTimerWritable = info.latencyTimerMs && latencyTimerWritable(info.path);
  }
}

// Unix98 pseudo-terminal slaves (major 136..143). libserialport 0.1.1 cannot open them (no sysfs entry, no modem
// lines), so the simulator's `--pty` ports are opened with termios directly.
bool isPseudoTerminal(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISCHR(st.st_mode)) return false;
  const unsigned major = ::major(st.st_rdev);
  return major >= 136 && major <= 143;
}

}  // namespace

IoResult<std::vector<SerialPortInfo>> listSerialPorts() {
  sp_port** ports = nullptr;
  if (sp_list_ports(&ports) != SP_OK) return std::unexpected(spFailure("", "listing serial ports"));
  std::vector<SerialPortInfo> out;
  for (sp_port** p = ports; *p; ++p) describe(*p, out.emplace_back());
  sp_free_port_list(ports);
  std::ranges::sort(out, {}, &SerialPortInfo::path);
  return out;
}

// Either a libserialport port, or (pseudo-terminals only) a plain termios descriptor.
struct SerialTransport::Impl {
  sp_port* port = nullptr;
  int fd = -1;  // the descriptor polled for reads (libserialport's handle, or the pty's)
  bool plainFd = false;
  std::string path;

  ~Impl() {
    if (port) {
      sp_close(port);
      sp_free_port(port);
    } else if (fd >= 0) {
      ::close(fd);
    }
  }
};

SerialTransport::SerialTransport(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SerialTransport::~SerialTransport() = default;

IoResult<std::unique_ptr<SerialTransport>> SerialTransport::open(const std::string& path,
                                                                 SerialTransportOptions options) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  SerialPortInfo info;
  info.path = path;

  if (isPseudoTerminal(path)) {
    // ---- Pseudo-terminal: raw mode by hand (the baud rate means nothing on a pty).
    impl->fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (impl->fd < 0) return std::unexpected(IoError::fromErrno(path, "cannot open", errno));
    termios tio{};
    if (::tcgetattr(impl->fd, &tio) == 0) {
      ::cfmakeraw(&tio);
      ::tcsetattr(impl->fd, TCSANOW, &tio);
    }
    impl->plainFd = true;
    info.description = "pseudo-terminal";
    return std::unique_ptr<SerialTransport>(new SerialTransport(std::move(impl)));
  }

  // ---- A real (or umockdev-mocked) serial port through libserialport.
  if (sp_get_port_by_name(path.c_str(), &impl->port) != SP_OK) {
    impl->port = nullptr;
    return std::unexpected(spFailure(path, "no such serial port"));
  }
  if (sp_open(impl->port, SP_MODE_READ_WRITE) != SP_OK) {
    IoError error = spFailure(path, "cannot open");
    sp_free_port(impl->port);
    impl->port = nullptr;
    if (error.code == EACCES) error.message += " (see docs/devices.md, \"Using the rig without root\")";
    return std::unexpected(std::move(error));
  }
  sp_port_config* config = nullptr;
  bool configured = sp_new_config(&config) == SP_OK;
  configured = configured && sp_set_config_baudrate(config, options.baud) == SP_OK &&
               sp_set_config_bits(config, 8) == SP_OK && sp_set_config_parity(config, SP_PARITY_NONE) == SP_OK &&
               sp_set_config_stopbits(config, 1) == SP_OK &&
               sp_set_config_flowcontrol(config, SP_FLOWCONTROL_NONE) == SP_OK &&
               sp_set_config_dtr(config, SP_DTR_ON) == SP_OK && sp_set_config_rts(config, SP_RTS_ON) == SP_OK &&
               sp_set_config(impl->port, config) == SP_OK;
  if (config) sp_free_config(config);
  if (!configured) return std::unexpected(spFailure(path, "cannot configure 8N1"));
  if (sp_get_port_handle(impl->port, &impl->fd) != SP_OK) return std::unexpected(spFailure(path, "no OS handle"));
  describe(impl->port, info);
  info.path = path;

  std::unique_ptr<SerialTransport> transport(new SerialTransport(std::move(impl)));

  // ---- FTDI: the chip holds bytes up to latency_timer ms (16 by default) before sending a USB packet.
  if (info.latencyTimerMs && *info.latencyTimerMs > 1) {
    if (options.ftdiLatencyMs > 0 && *info.latencyTimerMs > options.ftdiLatencyMs && info.latencyTimerWritable &&
        writeLatencyTimer(path, options.ftdiLatencyMs))
      info.latencyTimerMs = readLatencyTimer(path);
    if (info.latencyTimerMs && *info.latencyTimerMs > 1)
      transport->warnings_.push_back(cat(
          path, ": warning: FTDI latency timer is ", *info.latencyTimerMs, " ms, so samples arrive up to ",
          *info.latencyTimerMs, " ms late; install the udev rule in scripts/udev/ (docs/devices.md) or run: echo 1 | "
          "sudo tee ", ttyDeviceAttribute(path, "latency_timer").string()));
  }
  transport->info_ = std::move(info);
  return transport;
}

IoResult<size_t> SerialTransport::read(std::span<uint8_t> out, int timeoutMs) {
  if (out.empty()) return 0;
  pollfd p{impl_->fd, POLLIN, 0};
  const int ready = ::poll(&p, 1, std::max(timeoutMs, 0));
  if (ready < 0) {
    if (errno == EINTR) return 0;
    return std::unexpected(IoError::fromErrno(impl_->path, "poll", errno));
  }
  if (ready == 0) {
    // A device node that vanished while nothing arrived (some drivers never raise a hang-up on a quiet port).
    if (::access(impl_->path.c_str(), F_OK) != 0)
      return std::unexpected(IoError{impl_->path, "device node vanished", ENODEV});
    return 0;
  }
  if (p.revents & (POLLERR | POLLNVAL))
    return std::unexpected(IoError{impl_->path, "the port reported an error (unplugged?)", EIO});
  ssize_t n = 0;
  if (impl_->plainFd) {
    n = ::read(impl_->fd, out.data(), out.size());
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) n = 0;
    else if (n < 0)
      return std::unexpected(IoError::fromErrno(impl_->path, "read", errno));
  } else {
    const sp_return r = sp_nonblocking_read(impl_->port, out.data(), out.size());
    if (r < 0) return std::unexpected(spFailure(impl_->path, "read"));
    n = r;
  }
  if (n == 0 && (p.revents & POLLHUP))
    return std::unexpected(IoError{impl_->path, "the device hung up (unplugged?)", EIO});
  return static_cast<size_t>(n);
}

IoResult<void> SerialTransport::write(std::span<const uint8_t> bytes, int timeoutMs) {
  const int64_t deadline = (steadyNowNs() / 1'000'000) + std::max(timeoutMs, 1);
  size_t done = 0;
  while (done < bytes.size()) {
    ssize_t n = 0;
    if (impl_->plainFd) {
      n = ::write(impl_->fd, bytes.data() + done, bytes.size() - done);
      if (n < 0 && (errno == EAGAIN || errno == EINTR)) n = 0;
      else if (n < 0)
        return std::unexpected(IoError::fromErrno(impl_->path, "write", errno));
    } else {
      const sp_return r = sp_nonblocking_write(impl_->port, bytes.data() + done, bytes.size() - done);
      if (r < 0) return std::unexpected(spFailure(impl_->path, "write"));
      n = r;
    }
    done += static_cast<size_t>(n);
    if (done == bytes.size()) break;
    const int64_t left = deadline - (steadyNowNs() / 1'000'000);
    if (left <= 0) return std::unexpected(IoError{impl_->path, "write timed out", ETIMEDOUT});
    pollfd p{impl_->fd, POLLOUT, 0};
    if (::poll(&p, 1, static_cast<int>(std::min<int64_t>(left, 100))) > 0 && (p.revents & (POLLERR | POLLNVAL)))
      return std::unexpected(IoError{impl_->path, "the port reported an error (unplugged?)", EIO});
  }
  return {};
}

std::string SerialTransport::description() const {
  if (!info_.isUsb) return info_.path;
  return cat(info_.path, " (", hex4(info_.vendorId), ":", hex4(info_.productId),
             info_.product.empty() ? "" : " ", info_.product, ")");
}

TransportOpener serialOpener(std::string path, SerialTransportOptions options) {
  return [path = std::move(path), options]() -> IoResult<std::unique_ptr<ByteTransport>> {
    auto t = SerialTransport::open(path, options);
    if (!t) return std::unexpected(t.error());
    return std::unique_ptr<ByteTransport>(std::move(*t));
  };
}

}  // namespace imps::drivers
