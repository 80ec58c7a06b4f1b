// SPDX-License-Identifier: MIT
// Test helper: a umockdev testbed presenting USB HID devices (usb_device → usb_interface → hid → hidraw, with
// uevent HID_ID/HID_NAME/HID_UNIQ and a report_descriptor) whose /dev/hidrawN nodes the test plays as a fake
// armature: the test-only interposer tests/interposers/hidraw.c connects hidapi's open() of the node to a
// SOCK_SEQPACKET socket served here, so every sendReport() is exactly one read on the host side (as on hidraw),
// and closing it (unplug()) is the POLLHUP hidapi reports as a read error.
// Needs LD_PRELOAD=<libimps_hidraw.so>:…:libumockdev-preload.so.0 (set by tests/CMakeLists.txt); tests skip
// themselves without it. Header-only so only the binaries that use it link umockdev.
#pragma once

#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <umockdev.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace imps::test {

class UmockdevHid {
 public:
  // One USB HID device: hidraw<index> on USB port 1-<index + 3>.
  struct Device {
    int index = 0;
    uint16_t vendorId = 0x2341, productId = 0x8036;
    uint16_t releaseBcd = 0x0102;
    std::string serialNumber = "HID0001";
    std::string manufacturer = "IMPS";
    std::string product = "Monkey HID";
    std::vector<uint8_t> descriptor;
  };

  // True when the umockdev preload library and the hidraw interposer are active.
  static bool available() {
    const char* preload = std::getenv("LD_PRELOAD");
    return preload && std::strstr(preload, "libumockdev-preload.so") && std::strstr(preload, "libimps_hidraw");
  }

  UmockdevHid() : testbed_(umockdev_testbed_new()) { ::mkdir((rootDir() + "/imps-hidraw").c_str(), 0755); }
  ~UmockdevHid() {
    for (Node& n : nodes_) {
      if (n.connection >= 0) ::close(n.connection);
      if (n.listener >= 0) ::close(n.listener);
    }
    g_object_unref(testbed_);
  }
  UmockdevHid(const UmockdevHid&) = delete;
  UmockdevHid& operator=(const UmockdevHid&) = delete;

  // Adds the sysfs tree, the /dev/hidrawN node and the socket the interposer connects it to.
  bool add(const Device& d) {
    const std::string port = "1-" + std::to_string(d.index + 3);
    const std::string usb = "/devices/pci0000:00/usb1/" + port;
    const std::string intf = usb + "/" + port + ":1.0";
    char hidName[64];
    std::snprintf(hidName, sizeof hidName, "0003:%04X:%04X.%04X", d.vendorId, d.productId, d.index + 1);
    const std::string hid = intf + "/" + hidName;
    const std::string raw = "hidraw" + std::to_string(d.index);
    std::string hex;
    for (uint8_t b : d.descriptor) {
      char h[3];
      std::snprintf(h, sizeof h, "%02X", b);
      hex += h;
    }
    char ids[64];
    std::snprintf(ids, sizeof ids, "A: idVendor=%04x\nA: idProduct=%04x\nA: bcdDevice=%04x\n", d.vendorId,
                  d.productId, d.releaseBcd);
    char hidId[64];
    std::snprintf(hidId, sizeof hidId, "E: HID_ID=0003:%08X:%08X\n", d.vendorId, d.productId);
    const std::string description =
        "P: " + usb + "\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\n" + ids + "A: serial=" + d.serialNumber +
        "\nA: manufacturer=" + d.manufacturer + "\nA: product=" + d.product + "\nA: busnum=1\nA: devnum=" +
        std::to_string(d.index + 4) + "\n\n"
        "P: " + intf + "\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_interface\nE: DRIVER=usbhid\nA: bInterfaceNumber=00\n"
        "A: bInterfaceClass=03\n\n"
        "P: " + hid + "\nE: SUBSYSTEM=hid\nE: DRIVER=hid-generic\n" + hidId + "E: HID_NAME=" + d.manufacturer +
        " " + d.product + "\nE: HID_UNIQ=" + d.serialNumber + "\nH: report_descriptor=" + hex + "\n\n"
        "P: " + hid + "/hidraw/" + raw + "\nN: " + raw + "\nE: SUBSYSTEM=hidraw\nE: DEVNAME=/dev/" + raw +
        "\nA: dev=244:" + std::to_string(d.index) + "\n";
    GError* error = nullptr;
    if (!umockdev_testbed_add_from_string(testbed_, description.c_str(), &error)) {
      error_ = error ? error->message : "unknown umockdev error";
      if (error) g_error_free(error);
      return false;
    }
    // The hidraw node's `device` link leads to the hid device (uevent, report_descriptor), as in real sysfs.
    umockdev_testbed_set_attribute_link(testbed_, ("/sys" + hid + "/hidraw/" + raw).c_str(), "device",
                                        ("../../../" + std::string(hidName)).c_str());
    Node n;
    n.index = d.index;
    n.raw = raw;
    n.classLink = "../../devices/pci0000:00/usb1/" + port + "/" + port + ":1.0/" + hidName + "/hidraw/" + raw;
    n.listener = listenOn(socketPath(raw));
    if (n.listener < 0) return false;
    nodes_.push_back(n);
    return true;
  }

  // The feature report hidapi's hid_get_feature_report(id) returns (bytes, ID first), via the interposer.
  void setFeatureReport(int index, uint8_t id, const std::vector<uint8_t>& report) {
    std::ofstream out(socketPath(node(index).raw) + ".feature-" + std::to_string(id), std::ios::binary);
    out.write(reinterpret_cast<const char*>(report.data()), static_cast<std::streamsize>(report.size()));
  }

  // Waits until the host opened hidraw<index> and accepts that connection (closing an older one).
  bool waitForOpen(int index, int timeoutMs) {
    Node& n = node(index);
    pollfd p{n.listener, POLLIN, 0};
    if (::poll(&p, 1, timeoutMs) <= 0) return false;
    const int c = ::accept(n.listener, nullptr, nullptr);
    if (c < 0) return false;
    timeval tv{2, 0};  // a stuck host fails the test instead of hanging it
    ::setsockopt(c, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    if (n.connection >= 0) ::close(n.connection);
    n.connection = c;
    return true;
  }

  // Sends one input report (one read on the host); false when the host is not connected.
  bool sendReport(int index, const std::vector<uint8_t>& report) {
    Node& n = node(index);
    if (n.connection < 0) return false;
    return ::send(n.connection, report.data(), report.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(report.size());
  }

  // Unplugs hidraw<index> the way the host sees it: the connection hangs up (hidapi's read fails), the device
  // node and its /sys/class/hidraw entry vanish (enumeration no longer finds it, opening fails).
  void unplug(int index) {
    Node& n = node(index);
    if (n.connection >= 0) ::close(n.connection);
    n.connection = -1;
    ::unlink((rootDir() + "/sys/class/hidraw/" + n.raw).c_str());
    const std::string dev = rootDir() + "/dev/" + n.raw;
    ::rename(dev.c_str(), (dev + ".unplugged").c_str());
  }
  // Undoes unplug(): the node and class entry are back; the host may open again (waitForOpen).
  void replug(int index) {
    Node& n = node(index);
    ::symlink(n.classLink.c_str(), (rootDir() + "/sys/class/hidraw/" + n.raw).c_str());
    const std::string dev = rootDir() + "/dev/" + n.raw;
    ::rename((dev + ".unplugged").c_str(), dev.c_str());
  }

  std::string rootDir() const {
    gchar* root = umockdev_testbed_get_root_dir(testbed_);
    std::string out(root);
    g_free(root);
    return out;
  }
  const std::string& lastError() const { return error_; }

 private:
  struct Node {
    int index = 0;
    std::string raw, classLink;
    int listener = -1, connection = -1;
  };
  Node& node(int index) {
    for (Node& n : nodes_)
      if (n.index == index) return n;
    std::fprintf(stderr, "UmockdevHid: no hidraw%d\n", index);
    std::abort();
  }
  std::string socketPath(const std::string& raw) const { return rootDir() + "/imps-hidraw/" + raw; }
  int listenOn(const std::string& path) {
    const int s = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", path.c_str());
    if (s < 0 || ::bind(s, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 || ::listen(s, 8) != 0) {
      error_ = "cannot listen on " + path + ": " + std::strerror(errno);
      if (s >= 0) ::close(s);
      return -1;
    }
    return s;
  }

  UMockdevTestbed* testbed_;
  std::vector<Node> nodes_;
  std::string error_;
};

}  // namespace imps::test
