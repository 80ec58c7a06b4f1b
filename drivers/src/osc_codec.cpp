// SPDX-License-Identifier: MIT
// OSC 1.0 datagrams → pose frames or raw channels (address space in docs/osc.md).
// Based on: M. Wright, "The Open Sound Control 1.0 Specification", 2002.
#include "drivers/osc_codec.h"

#include <cmath>
#include <cstring>

#include "text.h"

namespace imps::drivers {
namespace {

constexpr int kMaxBundleDepth = 4;
constexpr std::string_view kJointPrefix = "/imps/joint/";

// A bounds-checked big-endian reader over one datagram. Every read checks before it touches memory.
struct Reader {
  std::span<const uint8_t> bytes;
  size_t base = 0;  // offset of `bytes` in the whole datagram, for messages

  // A datagram has no lines: the position is the byte offset, part of the "file" name ("osc:byte 12").
  std::unexpected<Diagnostics> fail(size_t at, std::string what) const {
    return diagnosticError({cat("osc:byte ", base + at)}, std::move(what));
  }
  // An OSC-string at `at`: ASCII up to a NUL, padded with NULs to a multiple of 4. Advances `at`.
  std::expected<std::string_view, Diagnostics> string(size_t& at, std::string_view what) const {
    const size_t begin = at;
    const void* nul = at < bytes.size() ? std::memchr(bytes.data() + at, 0, bytes.size() - at) : nullptr;
    if (!nul) return fail(begin, cat("expected ", what, " ending in a NUL byte"));
    const size_t length = size_t(static_cast<const uint8_t*>(nul) - bytes.data()) - at;
    const size_t padded = (length + 4) & ~size_t(3);
    if (at + padded > bytes.size()) return fail(begin, cat(what, " is not padded to a multiple of 4 bytes"));
    at += padded;
    return std::string_view(reinterpret_cast<const char*>(bytes.data() + begin), length);
  }
  bool has(size_t at, size_t n) const { return at <= bytes.size() && bytes.size() - at >= n; }
  uint32_t u32(size_t at) const {
    return uint32_t(bytes[at]) << 24 | uint32_t(bytes[at + 1]) << 16 | uint32_t(bytes[at + 2]) << 8 | bytes[at + 3];
  }
  uint64_t u64(size_t at) const { return uint64_t(u32(at)) << 32 | u32(at + 4); }
};

// The arguments of one message, typed by its type tag string.
struct Arguments {
  const Reader* r = nullptr;
  std::string_view tags;  // without the leading ','
  size_t at = 0;          // next argument's offset
  size_t index = 0;       // next tag

  size_t left() const { return tags.size() - index; }

  // The next argument as an integer (i or h).
  std::expected<int64_t, Diagnostics> integer(std::string_view what) {
    const char tag = index < tags.size() ? tags[index] : '\0';
    const size_t n = tag == 'i' ? 4 : tag == 'h' ? 8 : 0;
    if (n == 0) return r->fail(at, cat("expected ", what, " as an OSC integer (type i or h)"));
    if (!r->has(at, n)) return r->fail(at, cat("the message ends inside ", what));
    const int64_t v = n == 4 ? int64_t(int32_t(r->u32(at))) : int64_t(r->u64(at));
    at += n, ++index;
    return v;
  }
  // The next argument as a finite number (f, d, i or h).
  std::expected<double, Diagnostics> number(std::string_view what) {
    const char tag = index < tags.size() ? tags[index] : '\0';
    const size_t n = (tag == 'f' || tag == 'i') ? 4 : (tag == 'd' || tag == 'h') ? 8 : 0;
    if (n == 0) return r->fail(at, cat("expected ", what, " as an OSC number (type f, d, i or h)"));
    if (!r->has(at, n)) return r->fail(at, cat("the message ends inside ", what));
    double v = 0;
    if (tag == 'f') {
      const uint32_t bits = r->u32(at);
      float f;
      std::memcpy(&f, &bits, 4);
      v = f;
    } else if (tag == 'd') {
      const uint64_t bits = r->u64(at);
      std::memcpy(&v, &bits, 8);
    } else {
      v = tag == 'i' ? double(int32_t(r->u32(at))) : double(int64_t(r->u64(at)));
    }
    if (!std::isfinite(v)) return r->fail(at, cat(what, " is not a finite number"));
    at += n, ++index;
    return v;
  }
  // The next argument as a finite float32 (a double beyond float's range is refused, not turned into infinity).
  std::expected<float, Diagnostics> single(std::string_view what) {
    const size_t start = at;
    auto v = number(what);
    if (!v) return std::unexpected(v.error());
    if (!std::isfinite(float(*v))) return r->fail(start, cat(what, " is beyond the range of a float"));
    return float(*v);
  }
  std::expected<void, Diagnostics> end(std::string_view address) const {
    if (index != tags.size()) return r->fail(at, cat("unexpected extra arguments to ", address));
    return {};
  }
};

// The decoding of one datagram: what has been seen so far.
struct Decoder {
  OscPose& pose;
  Sample& channels;
  bool haveFrame = false, haveChannels = false, haveJointsOrRoot = false;

  std::expected<void, Diagnostics> element(const Reader& r, int depth) {
    if (r.bytes.size() % 4 != 0) return r.fail(0, "expected a size that is a multiple of 4 bytes");
    if (r.bytes.size() >= 8 && std::memcmp(r.bytes.data(), "#bundle", 8) == 0) return bundle(r, depth);
    return message(r);
  }

  std::expected<void, Diagnostics> bundle(const Reader& r, int depth) {
    if (depth >= kMaxBundleDepth) return r.fail(0, "bundles nested deeper than 4");
    if (!r.has(8, 8)) return r.fail(8, "expected the bundle's 8-byte time tag");
    size_t at = 16;
    while (at < r.bytes.size()) {
      if (!r.has(at, 4)) return r.fail(at, "expected a bundle element's size");
      const uint32_t size = r.u32(at);
      if (size % 4 != 0 || size == 0)
        return r.fail(at, "expected a bundle element size that is a positive multiple of 4");
      if (!r.has(at + 4, size)) return r.fail(at, "the bundle element is larger than what is left of the packet");
      Reader inner{r.bytes.subspan(at + 4, size), r.base + at + 4};
      if (auto e = element(inner, depth + 1); !e) return e;
      at += 4 + size;
    }
    return {};
  }

  std::expected<void, Diagnostics> message(const Reader& r) {
    size_t at = 0;
    auto address = r.string(at, "an OSC address");
    if (!address) return std::unexpected(address.error());
    if (address->empty() || address->front() != '/') return r.fail(0, "expected an OSC address starting with '/'");
    if (at == r.bytes.size()) return {};  // OSC 1.0 allows an old-style message without a type tag string
    const size_t tagsAt = at;
    auto tags = r.string(at, "a type tag string");
    if (!tags) return std::unexpected(tags.error());
    if (tags->empty() || tags->front() != ',') return r.fail(tagsAt, "expected a type tag string starting with ','");
    Arguments args{&r, tags->substr(1), at, 0};
    if (!address->starts_with("/imps/")) return {};  // another program's message: skipped
    if (*address == "/imps/frame") return frame(args, *address);
    if (*address == "/imps/root") return root(args, *address);
    if (*address == "/imps/channels") return rawChannels(args, *address);
    if (address->starts_with(kJointPrefix)) return joint(args, *address);
    return {};  // a later version's message: skipped
  }

  std::expected<void, Diagnostics> frame(Arguments& a, std::string_view address) {
    if (haveFrame) return a.r->fail(0, "a second /imps/frame in one packet");
    auto counter = a.integer("the frame counter");
    if (!counter) return std::unexpected(counter.error());
    pose.frame = uint32_t(uint64_t(*counter));
    pose.sampleTimeNs = pose.sentTimeNs = 0;
    if (a.left() > 0) {
      auto t = a.integer("the sample time (ns)");
      if (!t) return std::unexpected(t.error());
      pose.sampleTimeNs = *t;
    }
    if (a.left() > 0) {
      auto t = a.integer("the send time (ns)");
      if (!t) return std::unexpected(t.error());
      pose.sentTimeNs = *t;
    }
    haveFrame = true;
    return a.end(address);
  }

  std::expected<void, Diagnostics> root(Arguments& a, std::string_view address) {
    for (float& v : pose.root) {
      auto n = a.single("a root translation coordinate");
      if (!n) return std::unexpected(n.error());
      v = *n;
    }
    pose.hasRoot = haveJointsOrRoot = true;
    return a.end(address);
  }

  std::expected<void, Diagnostics> joint(Arguments& a, std::string_view address) {
    const std::string_view name = address.substr(kJointPrefix.size());
    if (name.empty() || name.size() > kMaxOscJointName)
      return a.r->fail(0, cat("expected a joint name of 1..", kMaxOscJointName, " bytes after /imps/joint/"));
    if (pose.jointCount >= kMaxOscJoints) return a.r->fail(0, cat("more than ", kMaxOscJoints, " joints in one frame"));
    OscJointRotation& j = pose.joints[pose.jointCount];
    float* q[4] = {&j.w, &j.x, &j.y, &j.z};
    for (float* v : q) {
      auto n = a.single("a quaternion component (w x y z)");
      if (!n) return std::unexpected(n.error());
      *v = *n;
    }
    if (j.w == 0 && j.x == 0 && j.y == 0 && j.z == 0) return a.r->fail(a.at, "expected a non-zero quaternion");
    if (auto e = a.end(address); !e) return e;
    j.name.fill('\0');
    std::memcpy(j.name.data(), name.data(), name.size());
    ++pose.jointCount;
    haveJointsOrRoot = true;
    return {};
  }

  std::expected<void, Diagnostics> rawChannels(Arguments& a, std::string_view address) {
    if (haveChannels) return a.r->fail(0, "a second /imps/channels in one packet");
    if (a.left() == 0 || a.left() > size_t(kMaxChannels))
      return a.r->fail(a.at, cat("expected 1..", kMaxChannels, " channel counts"));
    const size_t n = a.left();
    for (size_t i = 0; i < n; ++i) {
      auto v = a.integer("a channel count");
      if (!v) return std::unexpected(v.error());
      if (*v < 0 || *v > int64_t(UINT32_MAX)) return a.r->fail(a.at, "expected a channel count in 0..4294967295");
      channels.counts[i] = uint32_t(*v);
    }
    for (size_t i = n; i < size_t(kMaxChannels); ++i) channels.counts[i] = 0;
    channels.flags.fill(ChannelFlag::Valid);
    channels.channelCount = uint16_t(n);
    haveChannels = true;
    return a.end(address);
  }
};

}  // namespace

std::expected<OscDecoded, Diagnostics> decodeOscPacket(std::span<const uint8_t> packet, int64_t arrivalNs,
                                                       OscPose& pose, Sample& channels) {
  pose.jointCount = 0;
  pose.hasRoot = false;
  Decoder d{pose, channels};
  const Reader r{packet, 0};
  if (packet.empty()) return r.fail(0, "expected an OSC message or bundle, got an empty packet");
  if (auto e = d.element(r, 0); !e) return std::unexpected(e.error());
  if (d.haveChannels && d.haveJointsOrRoot)
    return r.fail(0, "a packet holds either /imps/channels or joints and root, not both");
  if (d.haveChannels) {
    channels.sequence = d.haveFrame ? pose.frame : 0;
    channels.deviceTimeNs = d.haveFrame ? pose.sampleTimeNs : 0;
    channels.arrivalTimeNs = arrivalNs;
    return OscDecoded{OscPacketKind::Channels, d.haveFrame};
  }
  if (d.haveJointsOrRoot && !d.haveFrame) return r.fail(0, "joints or root without /imps/frame");
  if (!d.haveFrame) return OscDecoded{};
  pose.arrivalTimeNs = arrivalNs;
  return OscDecoded{OscPacketKind::Pose, true};
}

}  // namespace imps::drivers
