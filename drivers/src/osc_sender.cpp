// SPDX-License-Identifier: MIT
// The OSC pose sender: liblo bundles on a thread of their own, fed by a wait-free queue.
#include "drivers/osc_sender.h"

#include <lo/lo.h>

#include <bit>
#include <charconv>
#include <chrono>

#include "text.h"
#include "imps/clock.h"

namespace imps::drivers {
namespace {

constexpr std::string_view kScheme = "osc.udp://";

// The bundle of one frame (docs/osc.md). liblo keeps the paths it is given until the bundle is freed, so they
// live in `paths` (cleared and refilled per frame; capacity kept).
lo_bundle makeBundle(const OscPose& pose, std::vector<std::string>& paths) {
  lo_bundle b = lo_bundle_new(LO_TT_IMMEDIATE);
  paths.resize(size_t(pose.jointCount) + 3);
  lo_message frame = lo_message_new();
  lo_message_add_int32(frame, int32_t(pose.frame));
  lo_message_add_int64(frame, pose.sampleTimeNs);
  lo_message_add_int64(frame, pose.sentTimeNs);
  paths[0] = "/imps/frame";
  lo_bundle_add_message(b, paths[0].c_str(), frame);
  for (uint16_t i = 0; i < pose.jointCount; ++i) {
    const OscJointRotation& j = pose.joints[i];
    lo_message m = lo_message_new();
    lo_message_add_float(m, j.w);
    lo_message_add_float(m, j.x);
    lo_message_add_float(m, j.y);
    lo_message_add_float(m, j.z);
    std::string& path = paths[1 + i];
    path = "/imps/joint/";
    path += j.nameView();
    lo_bundle_add_message(b, path.c_str(), m);
  }
  if (pose.hasRoot) {
    lo_message m = lo_message_new();
    for (float v : pose.root) lo_message_add_float(m, v);
    paths.back() = "/imps/root";
    lo_bundle_add_message(b, paths.back().c_str(), m);
  }
  return b;
}

void bump(std::atomic<uint64_t>& c) { c.store(c.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed); }

}  // namespace

struct OscPoseSender::Targets {
  std::vector<lo_address> addresses;
  ~Targets() {
    for (lo_address a : addresses) lo_address_free(a);
  }
};

std::expected<void, Diagnostics> checkOscTargetUrl(std::string_view url, std::string file) {
  auto fail = [&](size_t at, std::string what) {
    return diagnosticError({file, 1, static_cast<int>(at + 1)}, std::move(what));
  };
  if (!url.starts_with(kScheme)) return fail(0, "expected osc.udp://HOST:PORT");
  const std::string_view rest = url.substr(kScheme.size());
  const size_t colon = rest.rfind(':');
  if (colon == std::string_view::npos || colon == 0)
    return fail(kScheme.size(), "expected HOST:PORT after osc.udp:// (e.g. osc.udp://127.0.0.1:9000)");
  std::string_view port = rest.substr(colon + 1);
  if (!port.empty() && port.back() == '/') port.remove_suffix(1);
  int value = 0;
  const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (port.empty() || ec != std::errc() || end != port.data() + port.size() || value < 1 || value > 65535)
    return fail(kScheme.size() + colon + 1, "expected a port in 1..65535");
  return {};
}

std::vector<uint8_t> encodeOscPose(const OscPose& pose) {
  std::vector<std::string> paths;
  lo_bundle b = makeBundle(pose, paths);
  size_t size = lo_bundle_length(b);
  std::vector<uint8_t> out(size);
  lo_bundle_serialise(b, out.data(), &size);
  out.resize(size);
  lo_bundle_free_recursive(b);
  return out;
}

std::expected<std::unique_ptr<OscPoseSender>, Diagnostics> OscPoseSender::open(const std::vector<std::string>& urls,
                                                                               size_t queueCapacity) {
  auto targets = std::make_unique<Targets>();
  for (const std::string& url : urls) {
    if (auto ok = checkOscTargetUrl(url, url + ": osc"); !ok) return std::unexpected(ok.error());
    lo_address a = lo_address_new_from_url(url.c_str());
    if (!a) return diagnosticError({url}, "liblo cannot use this address");
    targets->addresses.push_back(a);
  }
  return std::unique_ptr<OscPoseSender>(new OscPoseSender(urls, std::move(targets), queueCapacity));
}

OscPoseSender::OscPoseSender(std::vector<std::string> urls, std::unique_ptr<Targets> targets, size_t queueCapacity)
    : urls_(std::move(urls)), targets_(std::move(targets)) {
  ring_.resize(std::bit_ceil(std::max<size_t>(queueCapacity, 2)));
  mask_ = ring_.size() - 1;
  thread_ = std::thread([this] { run(); });
}

OscPoseSender::~OscPoseSender() {
  stop_.store(true, std::memory_order_release);
  wake_.fetch_add(1, std::memory_order_release);
  wake_.notify_one();
  thread_.join();
}

bool OscPoseSender::send(const OscPose& pose) {
  const uint32_t frame = nextFrame_++;
  bump(offered_);
  const uint64_t head = head_.load(std::memory_order_relaxed);
  if (head - tail_.load(std::memory_order_acquire) >= ring_.size()) {
    bump(dropped_);
    return false;
  }
  OscPose& slot = ring_[head & mask_];
  slot = pose;
  slot.frame = frame;
  head_.store(head + 1, std::memory_order_release);
  wake_.fetch_add(1, std::memory_order_release);
  wake_.notify_one();  // a futex wake only when the sender thread sleeps
  return true;
}

void OscPoseSender::run() {
  std::vector<std::string> paths;
  for (;;) {
    // Read wake_ before head_: a send() after this load changes wake_, so wait() cannot miss it.
    const uint32_t wake = wake_.load(std::memory_order_acquire);
    const uint64_t tail = tail_.load(std::memory_order_relaxed);
    const uint64_t head = head_.load(std::memory_order_acquire);
    if (head == tail) {
      if (stop_.load(std::memory_order_acquire)) return;
      wake_.wait(wake, std::memory_order_acquire);
      continue;
    }
    OscPose& pose = ring_[tail & mask_];
    pose.sentTimeNs = steadyNowNs();
    lo_bundle b = makeBundle(pose, paths);
    for (lo_address a : targets_->addresses) {
      if (lo_send_bundle(a, b) < 0) {
        bump(sendErrors_);
        const char* why = lo_address_errstr(a);
        std::lock_guard lock(errorMutex_);
        lastError_ = why ? why : "send failed";
      } else {
        bump(sent_);
      }
    }
    lo_bundle_free_recursive(b);
    tail_.store(tail + 1, std::memory_order_release);
  }
}

bool OscPoseSender::flush(int timeoutMs) {
  const uint64_t head = head_.load(std::memory_order_relaxed);
  const int64_t until = steadyNowNs() + int64_t(timeoutMs) * 1'000'000;
  while (tail_.load(std::memory_order_acquire) < head) {
    if (steadyNowNs() >= until) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return true;
}

OscSenderStats OscPoseSender::stats() const {
  OscSenderStats s;
  s.offered = offered_.load(std::memory_order_relaxed);
  s.sent = sent_.load(std::memory_order_relaxed);
  s.dropped = dropped_.load(std::memory_order_relaxed);
  s.sendErrors = sendErrors_.load(std::memory_order_relaxed);
  return s;
}

std::string OscPoseSender::lastError() const {
  std::lock_guard lock(errorMutex_);
  return lastError_;
}

}  // namespace imps::drivers
