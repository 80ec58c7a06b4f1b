// SPDX-License-Identifier: MIT
// Test helper: a umockdev testbed with fake vendor-USB armatures (1209:0001 by default) on /dev/bus/usb/001/NNN whose
// usbdevfs ioctls are answered by the project's device model (sim::SimulatedArmature), so the real libusb talks to a
// reactive device: descriptors, the INFO vendor request, bulk OUT commands, interrupt/bulk IN frames, unplug and
// replug with udev events. Needs LD_PRELOAD=…libumockdev-preload.so.0 (set by tests/CMakeLists.txt); tests skip
// themselves without it. Header-only so only the binaries that use it link umockdev.
//
// How the URBs are served: umockdev forwards each ioctl on the device node to a UMockdevIoctlBase handler running on
// the testbed's worker thread. The client is this same process, so the handler reads and writes the caller's
// usbdevfs_urb structures in place (as libusb's own umockdev tests note, the address space is shared). IN URBs wait
// until the armature (driven by a server thread on the steady clock) has bytes. The fake device node is a socket that
// poll() always reports ready, so libusb reaps in a loop; to keep that from spinning, a reap that finds nothing right
// after one that found nothing is held back up to kReapHoldNs or until an URB completes — what a blocking poll() on
// a real usbfs node does.
#pragma once

#include <linux/usbdevice_fs.h>
#include <sys/ioctl.h>
#include <umockdev.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "drivers/binary_protocol.h"
#include "drivers/usb_transport.h"
#include "sim/simulated_armature.h"

namespace imps::test {

// The USB face of a fake armature (its device model is a sim::ArmatureOptions).
struct FakeUsbOptions {
  uint16_t vendorId = 0x1209, productId = 0x0001;
  std::string manufacturer = "IMPS", product = "IMPS USB Monkey", serial = "USB0001";
  bool interruptIn = true;   // the IN endpoint's type: interrupt (else bulk)
  int maxPacket = 64;        // wMaxPacketSize of both data endpoints
  std::string kernelDriver;  // a kernel driver bound to the interface until the host detaches it ("" = none)
  bool answersInfoRequest = true;  // false: the INFO vendor request stalls
};

// One plugged fake armature. Created and owned by UmockdevUsb. Counters and controls are thread-safe.
class FakeUsbArmature {
 public:
  static constexpr int64_t kReapHoldNs = 2'000'000;
  static constexpr size_t kMaxQueuedToHost = 256 * 1024;  // beyond this the oldest output is lost (counted)

  FakeUsbArmature(sim::ArmatureOptions armature, FakeUsbOptions usb, int devnum, std::string sysPath)
      : usb_(std::move(usb)), armature_(std::move(armature)), devnum_(devnum), sysPath_(std::move(sysPath)) {
    char node[64];
    std::snprintf(node, sizeof node, "/dev/bus/usb/001/%03d", devnum_);
    devnode_ = node;
    handler_ = umockdev_ioctl_base_new();
    g_signal_connect(handler_, "handle-ioctl", G_CALLBACK(&FakeUsbArmature::onIoctl), this);
  }
  ~FakeUsbArmature() {
    stopServing();
    g_signal_handlers_disconnect_by_data(handler_, this);
    g_object_unref(handler_);
  }
  FakeUsbArmature(const FakeUsbArmature&) = delete;
  FakeUsbArmature& operator=(const FakeUsbArmature&) = delete;

  // The sysfs/udev description umockdev_testbed_add_from_string() takes (the descriptors libusb reads from sysfs).
  std::string udevRecord() const {
    std::string hex;
    for (uint8_t b : descriptors()) {
      char two[3];
      std::snprintf(two, sizeof two, "%02x", b);
      hex += two;
    }
    char ids[64];
    std::snprintf(ids, sizeof ids, "A: idVendor=%04x\\n\nA: idProduct=%04x\\n\n", usb_.vendorId, usb_.productId);
    const std::string sys = sysPath_.substr(std::strlen("/sys"));
    const std::string node = devnode_.substr(std::strlen("/dev/"));
    return "P: " + sys + "\nN: " + node + "\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\nE: DRIVER=usb\n" +
           "E: BUSNUM=001\nE: DEVNUM=" + node.substr(node.size() - 3) + "\nE: DEVNAME=" + devnode_ + "\n" +
           "A: busnum=1\\n\nA: devnum=" + std::to_string(devnum_) + "\\n\nA: speed=12\\n\n" +
           "A: bConfigurationValue=1\\n\n" + ids + "A: manufacturer=" + usb_.manufacturer + "\\n\nA: product=" +
           usb_.product + "\\n\nA: serial=" + usb_.serial + "\\n\nH: descriptors=" + hex + "\n";
  }

  // Powers the armature on and starts serving (called by UmockdevUsb::plug once the node exists).
  void startServing() {
    {
      std::lock_guard lock(mutex_);
      poweredOnAtNs_ = clock_.nowNs();
      armature_.powerOn(poweredOnAtNs_);
    }
    server_ = std::thread([this] { serve(); });
  }
  void stopServing() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    if (server_.joinable()) server_.join();
    // A reap still held back (a client that never came back) is answered so no caller hangs.
    std::vector<Completion> left;
    {
      std::lock_guard lock(mutex_);
      for (const Parked& p : parked_) left.push_back({p.client, -1, ENODEV, true});
      parked_.clear();
    }
    finish(left);
  }

  // The device vanishes: URBs in flight complete with -ENODEV, later ioctls fail with ENODEV (what usbfs does).
  void markUnplugged() {
    {
      std::lock_guard lock(mutex_);
      unplugged_ = true;
      for (const Urb& u : pendingIn_) {
        u.urb->status = -ENODEV;
        u.urb->actual_length = 0;
        done_.push_back(u);
      }
      pendingIn_.clear();
      toHost_.clear();
      toHostPos_ = 0;
    }
    wake_.notify_all();
  }

  // While muted the device sends nothing (a hung firmware); its model keeps running.
  void setMute(bool mute) {
    std::lock_guard lock(mutex_);
    mute_ = mute;
  }
  // Queues raw bytes to the host after what is already queued (garbage, hand-made frames).
  void inject(const std::vector<uint8_t>& bytes) {
    {
      std::lock_guard lock(mutex_);
      toHost_.insert(toHost_.end(), bytes.begin(), bytes.end());
    }
    wake_.notify_all();
  }

  const std::string& devnode() const { return devnode_; }
  const std::string& sysPath() const { return sysPath_; }
  int devnum() const { return devnum_; }
  UMockdevIoctlBase* handler() const { return handler_; }
  const FakeUsbOptions& usbOptions() const { return usb_; }
  bool unplugged() {
    std::lock_guard lock(mutex_);
    return unplugged_;
  }
  // Steady-clock time of power-on: a streamed sample was due at poweredOnAtNs() + its deviceTimeNs.
  int64_t poweredOnAtNs() {
    std::lock_guard lock(mutex_);
    return poweredOnAtNs_;
  }

  uint64_t bytesToDevice() const { return bytesToDevice_.load(); }
  uint64_t bytesToHost() const { return bytesToHost_.load(); }
  uint64_t infoRequests() const { return infoRequests_.load(); }
  uint64_t claims() const { return claims_.load(); }
  uint64_t releases() const { return releases_.load(); }
  bool kernelDriverDetached() const { return detached_.load(); }
  uint64_t kernelDriverReattaches() const { return reattaches_.load(); }
  uint64_t samplesSent() {
    std::lock_guard lock(mutex_);
    return armature_.stats().samplesSent;
  }
  uint64_t commands() {
    std::lock_guard lock(mutex_);
    return armature_.stats().commands;
  }
  bool streaming() {
    std::lock_guard lock(mutex_);
    return armature_.streaming();
  }

 private:
  struct Urb {
    usbdevfs_urb* urb;
    UMockdevIoctlClient* client;
  };
  struct Parked {
    UMockdevIoctlClient* client;  // referenced while parked
    void** slot;                  // where REAPURB writes the URB pointer
    int64_t deadlineNs;
  };
  struct Completion {
    UMockdevIoctlClient* client;
    long result;
    int error;
    bool unref;
  };

  // Device descriptor, then the configuration: one vendor interface, bulk OUT 0x01 and interrupt/bulk IN 0x81.
  std::vector<uint8_t> descriptors() const {
    const uint8_t mpLo = static_cast<uint8_t>(usb_.maxPacket & 0xFF), mpHi = static_cast<uint8_t>(usb_.maxPacket >> 8);
    return {0x12, 0x01, 0x00, 0x02, 0x00, 0x00, 0x00, 0x40,
            static_cast<uint8_t>(usb_.vendorId), static_cast<uint8_t>(usb_.vendorId >> 8),
            static_cast<uint8_t>(usb_.productId), static_cast<uint8_t>(usb_.productId >> 8), 0x00, 0x01, 1, 2, 3, 1,
            0x09, 0x02, 32, 0, 1, 1, 0, 0x80, 50,                // configuration 1, 32 bytes, 100 mA
            0x09, 0x04, 0, 0, 2, 0xFF, 0x00, 0x00, 0,            // interface 0, 2 endpoints, class 0xFF
            0x07, 0x05, 0x01, 0x02, mpLo, mpHi, 0,               // bulk OUT 0x01
            0x07, 0x05, 0x81, static_cast<uint8_t>(usb_.interruptIn ? 0x03 : 0x02), mpLo, mpHi, 1};  // IN 0x81
  }

  static std::vector<uint8_t> stringDescriptor(const std::string& s) {
    std::vector<uint8_t> d{static_cast<uint8_t>(2 + 2 * s.size()), 0x03};
    for (char c : s) d.insert(d.end(), {static_cast<uint8_t>(c), 0});
    return d;
  }

  static gboolean onIoctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self) {
    return static_cast<FakeUsbArmature*>(self)->handle(client);
  }

  void finish(const std::vector<Completion>& completions) {
    for (const Completion& c : completions) {
      umockdev_ioctl_client_complete(c.client, c.result, c.error);
      if (c.unref) g_object_unref(c.client);
    }
  }

  // Runs on umockdev's worker thread. Decides under the lock, completes after releasing it.
  gboolean handle(UMockdevIoctlClient* client) {
    const unsigned long request = umockdev_ioctl_client_get_request(client);
    void* arg = *reinterpret_cast<void**>(umockdev_ioctl_client_get_arg(client)->data);
    std::vector<Completion> out;
    bool notify = false;
    {
      std::lock_guard lock(mutex_);
      auto reply = [&](long result, int error) { out.push_back({client, result, error, false}); };
      switch (request) {
        case USBDEVFS_GET_CAPABILITIES:
          *static_cast<uint32_t*>(arg) = USBDEVFS_CAP_BULK_CONTINUATION | USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
                                         USBDEVFS_CAP_REAP_AFTER_DISCONNECT | USBDEVFS_CAP_ZERO_PACKET;
          reply(0, 0);
          break;
        case USBDEVFS_CLAIMINTERFACE:
        case USBDEVFS_RELEASEINTERFACE:
          if (unplugged_) {
            reply(-1, ENODEV);
          } else {
            (request == USBDEVFS_CLAIMINTERFACE ? claims_ : releases_).fetch_add(1);
            reply(0, 0);
          }
          break;
        case USBDEVFS_SETCONFIGURATION:
        case USBDEVFS_SETINTERFACE:
        case USBDEVFS_CLEAR_HALT:
        case USBDEVFS_RESETEP:
        case USBDEVFS_RESET:
          reply(unplugged_ ? -1 : 0, unplugged_ ? ENODEV : 0);
          break;
        case USBDEVFS_GETDRIVER: {
          auto* d = static_cast<usbdevfs_getdriver*>(arg);
          if (unplugged_) {
            reply(-1, ENODEV);
          } else if (usb_.kernelDriver.empty() || detached_) {
            reply(-1, ENODATA);
          } else {
            std::snprintf(d->driver, sizeof d->driver, "%s", usb_.kernelDriver.c_str());
            reply(0, 0);
          }
          break;
        }
        case USBDEVFS_IOCTL: {  // detach (DISCONNECT) and re-attach (CONNECT) the kernel driver
          const auto* c = static_cast<usbdevfs_ioctl*>(arg);
          if (c->ioctl_code == USBDEVFS_DISCONNECT && !usb_.kernelDriver.empty() && !detached_) {
            detached_ = true;
            reply(0, 0);
          } else if (c->ioctl_code == USBDEVFS_CONNECT) {
            if (detached_) reattaches_.fetch_add(1);
            detached_ = false;
            reply(0, 0);
          } else {
            reply(-1, ENODATA);
          }
          break;
        }
        case USBDEVFS_SUBMITURB: {
          auto* urb = static_cast<usbdevfs_urb*>(arg);
          if (unplugged_) {
            reply(-1, ENODEV);
            break;
          }
          if (urb->type == USBDEVFS_URB_TYPE_CONTROL) {
            control(urb);
            done_.push_back({urb, client});
          } else if (urb->endpoint & 0x80) {
            pendingIn_.push_back({urb, client});
          } else {
            const auto* bytes = static_cast<const uint8_t*>(urb->buffer);
            armature_.receive(std::span<const uint8_t>(bytes, static_cast<size_t>(urb->buffer_length)),
                              clock_.nowNs());
            bytesToDevice_.fetch_add(static_cast<uint64_t>(urb->buffer_length));
            urb->actual_length = urb->buffer_length;
            urb->status = 0;
            done_.push_back({urb, client});
          }
          notify = true;
          reply(0, 0);
          break;
        }
        case USBDEVFS_REAPURB:
        case USBDEVFS_REAPURBNDELAY: {
          auto** slot = static_cast<void**>(arg);
          if (takeDone(client, slot)) {
            reapedEmpty_.erase(client);
            reply(0, 0);
          } else if (unplugged_ || stop_) {
            reply(-1, ENODEV);
          } else if (reapedEmpty_.count(client)) {
            g_object_ref(client);
            parked_.push_back({client, slot, clock_.nowNs() + kReapHoldNs});
            notify = true;
          } else {
            reapedEmpty_.insert(client);
            reply(-1, EAGAIN);
          }
          break;
        }
        case USBDEVFS_DISCARDURB: {
          auto it = std::find_if(pendingIn_.begin(), pendingIn_.end(), [&](const Urb& u) { return u.urb == arg; });
          if (it == pendingIn_.end()) {
            reply(-1, EINVAL);
          } else {
            it->urb->status = -ENOENT;
            it->urb->actual_length = 0;
            done_.push_back(*it);
            pendingIn_.erase(it);
            reply(0, 0);
          }
          break;
        }
        default:
          std::fprintf(stderr, "fake USB armature: unhandled ioctl 0x%lx\n", request);
          return FALSE;
      }
    }
    if (notify) wake_.notify_all();
    finish(out);
    return TRUE;
  }

  // Moves the oldest finished URB of `client` into *slot. Caller holds the lock.
  bool takeDone(UMockdevIoctlClient* client, void** slot) {
    auto it = std::find_if(done_.begin(), done_.end(), [&](const Urb& u) { return u.client == client; });
    if (it == done_.end()) return false;
    *slot = it->urb;
    done_.erase(it);
    return true;
  }

  // Answers a control URB in place: 8 setup bytes, then the data stage. Caller holds the lock.
  void control(usbdevfs_urb* urb) {
    auto* buf = static_cast<uint8_t*>(urb->buffer);
    const uint8_t type = buf[0], request = buf[1];
    const uint16_t value = static_cast<uint16_t>(buf[2] | buf[3] << 8);
    const size_t room = std::min<size_t>(static_cast<size_t>(buf[6] | buf[7] << 8),
                                         static_cast<size_t>(std::max(urb->buffer_length - 8, 0)));
    std::vector<uint8_t> data;
    bool stall = false;
    if (type == 0x80 && request == 0x06) {  // GET_DESCRIPTOR
      const std::vector<uint8_t> all = descriptors();
      const int kind = value >> 8, index = value & 0xFF;
      if (kind == 1) data.assign(all.begin(), all.begin() + 18);
      else if (kind == 2) data.assign(all.begin() + 18, all.end());
      else if (kind == 3 && index == 0) data = {4, 3, 0x09, 0x04};  // English (US)
      else if (kind == 3 && index == 1) data = stringDescriptor(usb_.manufacturer);
      else if (kind == 3 && index == 2) data = stringDescriptor(usb_.product);
      else if (kind == 3 && index == 3) data = stringDescriptor(usb_.serial);
      else stall = true;
    } else if (type == drivers::kUsbInfoRequestType && request == drivers::kUsbInfoRequest) {
      infoRequests_.fetch_add(1);
      auto block = drivers::encodeDeviceInfo(armature_.options().info);
      if (usb_.answersInfoRequest && block) data = std::move(*block);
      else stall = true;
    } else if (type & 0x80) {
      stall = true;  // an IN request this device does not know
    }
    const size_t n = std::min(room, data.size());
    if (n) std::memcpy(buf + 8, data.data(), n);
    urb->actual_length = stall ? 0 : static_cast<int>(n);
    urb->status = stall ? -EPIPE : 0;
  }

  // The device's clock: produces armature output, fills waiting IN URBs, answers held-back reaps.
  void serve() {
    std::unique_lock lock(mutex_);
    std::vector<uint8_t> produced;
    while (!stop_) {
      const int64_t now = clock_.nowNs();
      if (!unplugged_) {
        produced.clear();
        armature_.produce(now, produced);
        if (!mute_) toHost_.insert(toHost_.end(), produced.begin(), produced.end());
        if (toHost_.size() - toHostPos_ > kMaxQueuedToHost) toHostPos_ = toHost_.size() - kMaxQueuedToHost;
        while (!pendingIn_.empty() && toHostPos_ < toHost_.size()) {
          const Urb u = pendingIn_.front();
          pendingIn_.pop_front();
          const size_t n = std::min(static_cast<size_t>(u.urb->buffer_length), toHost_.size() - toHostPos_);
          std::memcpy(u.urb->buffer, toHost_.data() + toHostPos_, n);
          toHostPos_ += n;
          bytesToHost_.fetch_add(n);
          u.urb->actual_length = static_cast<int>(n);
          u.urb->status = 0;
          done_.push_back(u);
        }
        if (toHostPos_ == toHost_.size()) {
          toHost_.clear();
          toHostPos_ = 0;
        }
      }
      std::vector<Completion> out;
      int64_t next = now + 1'000'000;
      for (auto it = parked_.begin(); it != parked_.end();) {
        if (takeDone(it->client, it->slot)) {
          reapedEmpty_.erase(it->client);
          out.push_back({it->client, 0, 0, true});
        } else if (unplugged_ || now >= it->deadlineNs) {
          out.push_back({it->client, -1, unplugged_ ? ENODEV : EAGAIN, true});
        } else {
          next = std::min(next, it->deadlineNs);
          ++it;
          continue;
        }
        it = parked_.erase(it);
      }
      if (!out.empty()) {
        lock.unlock();
        finish(out);
        lock.lock();
        continue;
      }
      if (!unplugged_) next = std::min(next, armature_.nextDueNs());
      wake_.wait_until(lock, std::chrono::steady_clock::time_point(std::chrono::nanoseconds(std::max(next, now))));
    }
  }

  FakeUsbOptions usb_;
  imps::SteadyClock clock_;
  std::mutex mutex_;  // guards everything below except the atomics
  std::condition_variable wake_;
  sim::SimulatedArmature armature_;
  std::deque<Urb> pendingIn_, done_;
  std::vector<Parked> parked_;
  std::set<UMockdevIoctlClient*> reapedEmpty_;  // clients whose last reap found nothing
  std::vector<uint8_t> toHost_;
  size_t toHostPos_ = 0;
  int64_t poweredOnAtNs_ = 0;
  bool unplugged_ = false, mute_ = false, stop_ = false;
  std::atomic<bool> detached_{false};
  std::atomic<uint64_t> bytesToDevice_{0}, bytesToHost_{0}, infoRequests_{0}, claims_{0}, releases_{0},
      reattaches_{0};
  std::thread server_;
  int devnum_;
  std::string sysPath_, devnode_;
  UMockdevIoctlBase* handler_;
};

// The testbed: plug, unplug and replug fake armatures on bus 1 (each plug takes the next address, as USB does).
class UmockdevUsb {
 public:
  // True when the umockdev preload library is active (otherwise /dev and /sys are the real ones).
  static bool available() {
    const char* preload = std::getenv("LD_PRELOAD");
    return preload && std::strstr(preload, "libumockdev-preload.so");
  }

  UmockdevUsb() : testbed_(umockdev_testbed_new()) {}
  ~UmockdevUsb() {
    for (auto& d : devices_) d->stopServing();
    for (auto& d : devices_) umockdev_testbed_detach_ioctl(testbed_, d->devnode().c_str(), nullptr);
    g_object_unref(testbed_);
    devices_.clear();
  }
  UmockdevUsb(const UmockdevUsb&) = delete;
  UmockdevUsb& operator=(const UmockdevUsb&) = delete;

  // Plugs an armature into port `port` of the root hub (sysfs /sys/devices/pci0000:00/usb1/1-PORT) at the next
  // address; emits the udev "add" event. Returns the device (owned by the testbed), or nullptr (see lastError()).
  FakeUsbArmature* plug(sim::ArmatureOptions armature, FakeUsbOptions usb = {}, int port = 1) {
    const std::string sysPath = "/sys/devices/pci0000:00/usb1/1-" + std::to_string(port);
    auto device = std::make_unique<FakeUsbArmature>(std::move(armature), std::move(usb), nextAddress_++, sysPath);
    GError* error = nullptr;
    // The ioctl handler first, so the node answers as soon as the "add" event announces it.
    if (!umockdev_testbed_attach_ioctl(testbed_, device->devnode().c_str(), device->handler(), &error) ||
        !umockdev_testbed_add_from_string(testbed_, device->udevRecord().c_str(), &error)) {
      error_ = error ? error->message : "unknown umockdev error";
      if (error) g_error_free(error);
      return nullptr;
    }
    device->startServing();
    devices_.push_back(std::move(device));
    return devices_.back().get();
  }

  // Unplugs: URBs in flight fail with ENODEV, the udev "remove" event goes out, the sysfs entry and node vanish.
  // (umockdev 0.17 sends no "remove" event from umockdev_testbed_remove_device() itself.)
  void unplug(FakeUsbArmature* device) {
    device->markUnplugged();
    umockdev_testbed_uevent(testbed_, device->sysPath().c_str(), "remove");
    umockdev_testbed_remove_device(testbed_, device->sysPath().c_str());
  }

  // Plugs an armature with the identity of `device` (unplugging it first if it is still attached) back into the
  // same port, at a new address, as a replugged USB device gets.
  FakeUsbArmature* replug(FakeUsbArmature* device, sim::ArmatureOptions armature) {
    const std::string sys = device->sysPath();
    const int port = std::atoi(sys.substr(sys.rfind('-') + 1).c_str());
    FakeUsbOptions usb = device->usbOptions();
    if (!device->unplugged()) unplug(device);
    return plug(std::move(armature), std::move(usb), port);
  }

  UMockdevTestbed* testbed() const { return testbed_; }
  const std::string& lastError() const { return error_; }

 private:
  UMockdevTestbed* testbed_;
  std::vector<std::unique_ptr<FakeUsbArmature>> devices_;
  int nextAddress_ = 2;
  std::string error_;
};

}  // namespace imps::test
