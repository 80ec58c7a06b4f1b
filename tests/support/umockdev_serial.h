// SPDX-License-Identifier: MIT
// Test helper: a umockdev testbed presenting USB serial ports (/dev/ttyACM0 as a CDC-ACM Arduino, /dev/ttyUSB0 as
// an FTDI adapter with a latency_timer) backed by pseudo-terminals whose master ends the test drives.
// Needs LD_PRELOAD=<libimps_modem_ioctl.so>:libumockdev-preload.so.0 (set by tests/CMakeLists.txt); tests skip
// themselves without it. Header-only so only the binaries that use it link umockdev.
#pragma once

#include <umockdev.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <string>

namespace imps::test {

class UmockdevSerial {
 public:
  static constexpr const char* kAcmSysPath = "/sys/devices/pci0000:00/usb1/1-1/1-1:1.0/tty/ttyACM0";
  static constexpr const char* kAcmUsbPath = "/sys/devices/pci0000:00/usb1/1-1";
  static constexpr const char* kFtdiUsbPath = "/sys/devices/pci0000:00/usb1/1-2";

  // True when the umockdev preload library is active (otherwise /dev and /sys are the real ones).
  // (umockdev_in_mock_environment() is false here when the preload library is not first in LD_PRELOAD.)
  static bool available() {
    const char* preload = std::getenv("LD_PRELOAD");
    return preload && std::strstr(preload, "libumockdev-preload.so") && std::strstr(preload, "libimps_modem_ioctl");
  }

  UmockdevSerial() : testbed_(umockdev_testbed_new()) {}
  ~UmockdevSerial() { g_object_unref(testbed_); }
  UmockdevSerial(const UmockdevSerial&) = delete;
  UmockdevSerial& operator=(const UmockdevSerial&) = delete;

  // Adds the Arduino-like CDC-ACM port /dev/ttyACM0 (2341:0043, serial "IMPS0001"); returns the pty master fd
  // (owned by umockdev; do not close), or -1 on failure.
  int addAcm() {
    const char* description =
        "P: /devices/pci0000:00/usb1/1-1\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\nA: idVendor=2341\n"
        "A: idProduct=0043\nA: serial=IMPS0001\nA: manufacturer=Arduino (www.arduino.cc)\nA: product=Monkey\n"
        "A: busnum=1\nA: devnum=2\n\n"
        "P: /devices/pci0000:00/usb1/1-1/1-1:1.0\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_interface\nE: DRIVER=cdc_acm\n"
        "A: interface=CDC Abstract Control Model\n\n"
        "P: /devices/pci0000:00/usb1/1-1/1-1:1.0/tty/ttyACM0\nN: ttyACM0\nE: SUBSYSTEM=tty\n"
        "E: DEVNAME=/dev/ttyACM0\nA: dev=166:0\n";
    if (!add(description)) return -1;
    // libserialport follows /sys/class/tty/<name>/device to the USB interface; umockdev does not create it.
    umockdev_testbed_set_attribute_link(testbed_, kAcmSysPath, "device", "../../../1-1:1.0");
    umockdev_testbed_set_attribute_link(testbed_, "/sys/devices/pci0000:00/usb1/1-1/1-1:1.0", "driver",
                                        "../../../../../bus/usb/drivers/cdc_acm");
    return umockdev_testbed_get_dev_fd(testbed_, "/dev/ttyACM0");
  }

  // Adds an FTDI adapter /dev/ttyUSB0 (0403:6001) whose latency_timer reads `latencyMs`; returns the master fd.
  int addFtdi(int latencyMs) {
    const std::string description =
        "P: /devices/pci0000:00/usb1/1-2\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\nA: idVendor=0403\n"
        "A: idProduct=6001\nA: serial=FT123456\nA: manufacturer=FTDI\nA: product=FT232R USB UART\nA: busnum=1\n"
        "A: devnum=3\n\n"
        "P: /devices/pci0000:00/usb1/1-2/1-2:1.0\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_interface\nE: DRIVER=ftdi_sio\n\n"
        "P: /devices/pci0000:00/usb1/1-2/1-2:1.0/ttyUSB0\nE: SUBSYSTEM=usb-serial\nE: DRIVER=ftdi_sio\n"
        "A: latency_timer=" + std::to_string(latencyMs) + "\n\n"
        "P: /devices/pci0000:00/usb1/1-2/1-2:1.0/ttyUSB0/tty/ttyUSB0\nN: ttyUSB0\nE: SUBSYSTEM=tty\n"
        "E: DEVNAME=/dev/ttyUSB0\nA: dev=188:0\n";
    if (!add(description.c_str())) return -1;
    umockdev_testbed_set_attribute_link(testbed_, "/sys/devices/pci0000:00/usb1/1-2/1-2:1.0/ttyUSB0/tty/ttyUSB0",
                                        "device", "../../../ttyUSB0");
    umockdev_testbed_set_attribute_link(testbed_, "/sys/devices/pci0000:00/usb1/1-2/1-2:1.0/ttyUSB0", "driver",
                                        "../../../../../../bus/usb-serial/drivers/ftdi_sio");
    return umockdev_testbed_get_dev_fd(testbed_, "/dev/ttyUSB0");
  }

  // Unplugs the Arduino: removes the USB device, its interface, the tty and /dev/ttyACM0.
  void removeAcm() {
    // Child first: removing a parent leaves its children's /dev node and /sys/bus links behind.
    umockdev_testbed_remove_device(testbed_, kAcmSysPath);
    umockdev_testbed_remove_device(testbed_, "/sys/devices/pci0000:00/usb1/1-1/1-1:1.0");
    umockdev_testbed_remove_device(testbed_, kAcmUsbPath);
  }

  // Unplugs /dev/ttyACM0 the way the host notices it — the device node and its /sys/class/tty entry vanish —
  // but keeps umockdev's pty. (umockdev 0.17.16 cannot re-add a device node of the same name after
  // umockdev_testbed_remove_device(): it asserts that the old pty is still registered. So a replug restores the
  // node onto the same pty, and the master fd stays valid.)
  bool unplugAcmNode() {
    const std::string root = rootDir();
    char target[4096];
    const ssize_t n = ::readlink((root + "/dev/ttyACM0").c_str(), target, sizeof target - 1);
    if (n <= 0) return false;
    ptySlave_.assign(target, static_cast<size_t>(n));
    return ::unlink((root + "/dev/ttyACM0").c_str()) == 0 && ::unlink((root + "/sys/class/tty/ttyACM0").c_str()) == 0;
  }
  // Undoes unplugAcmNode(); returns the (unchanged) master fd, or -1.
  int replugAcmNode() {
    const std::string root = rootDir();
    if (ptySlave_.empty() || ::symlink(ptySlave_.c_str(), (root + "/dev/ttyACM0").c_str()) != 0 ||
        ::symlink("../../devices/pci0000:00/usb1/1-1/1-1:1.0/tty/ttyACM0", (root + "/sys/class/tty/ttyACM0").c_str()) !=
            0)
      return -1;
    return umockdev_testbed_get_dev_fd(testbed_, "/dev/ttyACM0");
  }

  std::string rootDir() const {
    gchar* root = umockdev_testbed_get_root_dir(testbed_);
    std::string out(root);
    g_free(root);
    return out;
  }

  // The text of a sysfs attribute file in the testbed (e.g. to see what the driver wrote).
  std::string sysAttribute(const std::string& sysPath) const {
    gchar* root = umockdev_testbed_get_root_dir(testbed_);
    std::string path = std::string(root) + sysPath;
    g_free(root);
    gchar* contents = nullptr;
    std::string out;
    if (g_file_get_contents(path.c_str(), &contents, nullptr, nullptr)) out = contents;
    g_free(contents);
    return out;
  }

  UMockdevTestbed* testbed() const { return testbed_; }
  const std::string& lastError() const { return error_; }

 private:
  bool add(const char* description) {
    GError* error = nullptr;
    if (umockdev_testbed_add_from_string(testbed_, description, &error)) return true;
    error_ = error ? error->message : "unknown umockdev error";
    if (error) g_error_free(error);
    return false;
  }

  UMockdevTestbed* testbed_;
  std::string error_;
  std::string ptySlave_;  // where /dev/ttyACM0 pointed before unplugAcmNode()
};

}  // namespace imps::test
