// SPDX-License-Identifier: MIT
// The HID armature codec: report descriptor parser, input layout, report decoder and the device-side encoders.
// Based on: USB-IF, "Device Class Definition for Human Interface Devices (HID)", version 1.11 (2001), 6.2.2.
#include "drivers/hid_report.h"

#include <algorithm>
#include <limits>

#include "drivers/binary_protocol.h"
#include "text.h"

namespace imps::drivers {

namespace {

// Item prefixes with the size bits masked off (tag << 4 | type << 2).
enum : uint8_t {
  kInput = 0x80, kOutput = 0x90, kFeature = 0xB0, kCollection = 0xA0, kEndCollection = 0xC0,
  kUsagePage = 0x04, kLogicalMin = 0x14, kLogicalMax = 0x24, kReportSize = 0x74, kReportId = 0x84,
  kReportCount = 0x94, kPush = 0xA4, kPop = 0xB4,
  kUsage = 0x08, kUsageMin = 0x18, kUsageMax = 0x28,
};
constexpr uint8_t kLongItem = 0xFE;
constexpr size_t kMaxPushDepth = 16;
constexpr size_t kMaxCollectionDepth = 32;
constexpr size_t kMaxLocalUsages = 1024;  // bounds Usage Minimum..Maximum expansion
constexpr uint8_t kApplicationCollection = 0x01;
constexpr uint16_t kButtonPage = 0x09, kKeyboardPage = 0x07, kLedPage = 0x08, kGenericDesktopPage = 0x01;

// Descriptor bytes are not a text file: the position is the 0-based byte offset, part of the "file" name.
std::unexpected<Diagnostics> fail(size_t offset, std::string what) {
  return diagnosticError({cat("report descriptor:", offset)}, std::move(what));
}

struct Globals {
  uint16_t usagePage = 0;
  int64_t logicalMin = 0;
  uint32_t logicalMaxRaw = 0;
  uint8_t logicalMaxSize = 0;
  uint32_t reportSize = 0;
  uint32_t reportCount = 0;
  uint8_t reportId = 0;
};

// A local Usage / Usage Minimum / Usage Maximum as written: short ones take the Usage Page in force at the main
// item (HID 1.11, 6.2.2.8), 4-byte ones carry their own page.
struct LocalUsage {
  uint32_t value = 0;
  bool extended = false;
  uint32_t resolve(uint16_t page) const { return extended ? value : hidUsage(page, static_cast<uint16_t>(value)); }
};

int64_t signedValue(uint32_t raw, size_t size) {
  switch (size) {
    case 1: return static_cast<int8_t>(raw);
    case 2: return static_cast<int16_t>(raw);
    case 4: return static_cast<int32_t>(raw);
    default: return 0;
  }
}

// Reads `n` (1..32) bits at bit `offset` of a little-endian bit stream; the caller checks the bounds.
uint32_t getBits(const uint8_t* data, uint32_t offset, uint32_t n) {
  uint64_t v = 0;
  const uint32_t first = offset / 8, last = (offset + n - 1) / 8;
  for (uint32_t b = last + 1; b-- > first;) v = (v << 8) | data[b];
  v >>= offset % 8;
  return static_cast<uint32_t>(n == 32 ? v : v & ((uint64_t{1} << n) - 1));
}

void putBits(uint8_t* data, uint32_t offset, uint32_t n, uint32_t value) {
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t bit = offset + i;
    if ((value >> i) & 1u) data[bit / 8] |= static_cast<uint8_t>(1u << (bit % 8));
    else data[bit / 8] &= static_cast<uint8_t>(~(1u << (bit % 8)));
  }
}

uint32_t mask(uint32_t bits) { return bits >= 32 ? 0xFFFFFFFFu : (1u << bits) - 1; }

std::string usageName(uint32_t usage) {
  if ((usage >> 16) != kGenericDesktopPage) return {};
  switch (usage & 0xFFFF) {
    case 0x30: return "X";
    case 0x31: return "Y";
    case 0x32: return "Z";
    case 0x33: return "Rx";
    case 0x34: return "Ry";
    case 0x35: return "Rz";
    case 0x36: return "Slider";
    case 0x37: return "Dial";
    case 0x38: return "Wheel";
    default: return {};
  }
}

}  // namespace

uint32_t HidField::usageOf(uint32_t element) const {
  if (usages.empty()) return 0;
  return usages[std::min<size_t>(element, usages.size() - 1)];
}

const HidReportSize* HidReportDescriptor::report(HidReportKind kind, uint8_t id) const {
  for (const HidReportSize& r : reports)
    if (r.kind == kind && r.id == id) return &r;
  return nullptr;
}

std::expected<HidReportDescriptor, Diagnostics> parseHidReportDescriptor(std::span<const uint8_t> bytes) {
  if (bytes.empty()) return fail(0, "empty report descriptor");
  HidReportDescriptor out;
  Globals g;
  std::vector<Globals> stack;
  std::vector<LocalUsage> usages;
  LocalUsage usageMin;
  bool haveUsageMin = false;
  std::vector<uint8_t> collections;  // collection types, outermost first
  uint32_t application = 0;
  bool mainWithoutId = false;
  size_t mainWithoutIdAt = 0;

  size_t pos = 0;
  while (pos < bytes.size()) {
    const size_t at = pos;
    const uint8_t prefix = bytes[pos];
    if (prefix == kLongItem) {
      if (pos + 3 > bytes.size()) return fail(at, "truncated long item");
      const size_t size = bytes[pos + 1];
      if (pos + 3 + size > bytes.size()) return fail(at, "truncated long item data");
      pos += 3 + size;
      continue;
    }
    const size_t size = (prefix & 3) == 3 ? 4 : (prefix & 3);
    if (pos + 1 + size > bytes.size())
      return fail(at, cat("item 0x", hex4(prefix).substr(2), " needs ", size, " data bytes; the descriptor ends"));
    uint32_t raw = 0;
    for (size_t i = 0; i < size; ++i) raw |= uint32_t{bytes[pos + 1 + i]} << (8 * i);
    pos += 1 + size;
    const uint8_t item = prefix & 0xFC;

    switch (item) {
      // ---- Global items
      case kUsagePage: g.usagePage = static_cast<uint16_t>(raw); break;
      case kLogicalMin: g.logicalMin = signedValue(raw, size); break;
      case kLogicalMax: g.logicalMaxRaw = raw; g.logicalMaxSize = static_cast<uint8_t>(size); break;
      case kReportSize: g.reportSize = raw; break;
      case kReportCount: g.reportCount = raw; break;
      case kReportId:
        if (raw == 0 || raw > 255) return fail(at, "Report ID must be 1..255");
        g.reportId = static_cast<uint8_t>(raw);
        out.usesReportIds = true;
        break;
      case kPush:
        if (stack.size() >= kMaxPushDepth) return fail(at, "more than 16 nested Push items");
        stack.push_back(g);
        break;
      case kPop:
        if (stack.empty()) return fail(at, "Pop without a matching Push");
        g = stack.back();
        stack.pop_back();
        break;
      // ---- Local items
      case kUsage:
        if (usages.size() < kMaxLocalUsages) usages.push_back({raw, size == 4});
        break;
      case kUsageMin:
        usageMin = LocalUsage{raw, size == 4};
        haveUsageMin = true;
        break;
      case kUsageMax: {
        if (!haveUsageMin) break;  // a maximum without a minimum names nothing
        const uint32_t lo = usageMin.value & 0xFFFF, hi = raw & 0xFFFF;
        const uint32_t pageBits = usageMin.extended ? (usageMin.value & 0xFFFF0000u) : 0;
        for (uint32_t u = lo; u <= hi && usages.size() < kMaxLocalUsages; ++u)
          usages.push_back({pageBits | u, usageMin.extended});
        haveUsageMin = false;
        break;
      }
      // ---- Main items
      case kCollection: {
        if (collections.size() >= kMaxCollectionDepth) return fail(at, "more than 32 nested collections");
        const uint8_t type = static_cast<uint8_t>(raw);
        if (collections.empty() && type == kApplicationCollection) {
          application = usages.empty() ? 0 : usages.front().resolve(g.usagePage);
          out.applications.push_back(application);
        }
        collections.push_back(type);
        usages.clear();
        haveUsageMin = false;
        break;
      }
      case kEndCollection:
        if (collections.empty()) return fail(at, "End Collection without a Collection");
        collections.pop_back();
        if (collections.empty()) application = 0;
        usages.clear();
        haveUsageMin = false;
        break;
      case kInput:
      case kOutput:
      case kFeature: {
        HidField f;
        f.kind = item == kInput ? HidReportKind::Input : item == kOutput ? HidReportKind::Output
                                                                          : HidReportKind::Feature;
        f.reportId = g.reportId;
        f.bitSize = g.reportSize;
        f.count = g.reportCount;
        f.flags = raw;
        f.logicalMin = g.logicalMin;
        // Linux reads Logical Maximum as unsigned when Logical Minimum is not negative (0x00..0xFF is common).
        f.logicalMax = g.logicalMin < 0 ? signedValue(g.logicalMaxRaw, g.logicalMaxSize) : int64_t{g.logicalMaxRaw};
        f.application = application;
        for (const LocalUsage& u : usages) f.usages.push_back(u.resolve(g.usagePage));
        usages.clear();
        haveUsageMin = false;
        if (g.reportId == 0 && !mainWithoutId) {
          mainWithoutId = true;
          mainWithoutIdAt = at;
        }
        // Append to its report: fields of one report are laid out back to back in descriptor order.
        HidReportSize* r = nullptr;
        for (HidReportSize& existing : out.reports)
          if (existing.kind == f.kind && existing.id == f.reportId) r = &existing;
        if (!r) r = &out.reports.emplace_back(HidReportSize{f.kind, f.reportId, 0});
        const uint64_t bits = uint64_t{f.bitSize} * f.count;
        if (r->bits + bits > (kMaxHidReportSize - 1) * 8)
          return fail(at, cat("report ", int(f.reportId), " grows beyond ", kMaxHidReportSize, " bytes"));
        f.bitOffset = r->bits;
        r->bits += static_cast<uint32_t>(bits);
        out.fields.push_back(std::move(f));
        break;
      }
      default: break;  // physical range, units, designators, strings, delimiters: not needed
    }
  }
  if (!collections.empty()) return fail(bytes.size(), "a Collection is not closed by End Collection");
  if (out.usesReportIds && mainWithoutId)
    return fail(mainWithoutIdAt, "a main item before the first Report ID in a descriptor that uses report IDs");
  return out;
}

int HidInputLayout::bitsPerChannel() const {
  int bits = 0;
  for (const HidChannel& c : channels) bits = std::max(bits, int{c.bitSize});
  return bits;
}

std::expected<HidInputLayout, Diagnostics> hidArmatureLayout(const HidReportDescriptor& d) {
  // ---- Count the channels of every input report; pick the richest.
  auto isChannelField = [](const HidField& f) {
    return f.kind == HidReportKind::Input && !(f.flags & kHidConstant) && (f.flags & kHidVariable) &&
           !(f.flags & kHidRelative) && f.bitSize >= 1 && f.bitSize <= 32;
  };
  auto isChannelUsage = [](uint32_t usage) {
    const uint16_t page = static_cast<uint16_t>(usage >> 16);
    if (page == kButtonPage || page == kKeyboardPage || page == kLedPage) return false;
    return usage != hidUsage(kImpsHidUsagePage, kImpsUsageSequence) &&
           usage != hidUsage(kImpsHidUsagePage, kImpsUsageDeviceTime);
  };
  std::optional<uint8_t> best;
  size_t bestCount = 0;
  for (const HidReportSize& r : d.reports) {
    if (r.kind != HidReportKind::Input) continue;
    size_t n = 0;
    for (const HidField& f : d.fields)
      if (f.reportId == r.id && isChannelField(f))
        for (uint32_t e = 0; e < f.count; ++e) n += isChannelUsage(f.usageOf(e)) ? 1 : 0;
    if (n > bestCount || (n == bestCount && n > 0 && best && r.id < *best)) {
      best = r.id;
      bestCount = n;
    }
  }
  if (!best)
    return diagnosticError({"report descriptor"},
                           "no input report carries a channel (an absolute Data Variable "
                           "Input item of 1..32 bits)");

  HidInputLayout layout;
  layout.usesReportIds = d.usesReportIds;
  layout.reportId = *best;
  layout.reportSize = d.report(HidReportKind::Input, *best)->bytes(d.usesReportIds);
  for (const HidReportSize& r : d.reports)
    if (r.kind == HidReportKind::Input && r.id != *best) layout.otherInputIds.push_back(r.id);

  // ---- Lay out the chosen report.
  bool armatureApplication = true;
  size_t ignored = 0;
  for (const HidField& f : d.fields) {
    if (f.kind == HidReportKind::Feature && !layout.infoReportId) {
      // Elements past the last usage repeat it: look at most at one element per usage (Report Count may be
      // 2^32 − 1 with a Report Size of 0, which makes no bytes but must not make 4 billion iterations).
      const size_t distinct = std::min<size_t>(std::max<uint32_t>(f.count, 1), std::max<size_t>(f.usages.size(), 1));
      for (uint32_t e = 0; e < distinct; ++e)
        if (f.usageOf(e) == hidUsage(kImpsHidUsagePage, kImpsUsageInfo)) {
          layout.infoReportId = f.reportId;
          layout.infoReportSize = d.report(HidReportKind::Feature, f.reportId)->bytes(d.usesReportIds);
          break;
        }
    }
    if (f.kind != HidReportKind::Input || f.reportId != *best) continue;
    // Only 1..32-bit elements can be channels or counters. This also bounds the loop: the report size limit
    // caps Report Count at 32760 for them, while a 0-bit field may declare 2^32 − 1 elements.
    if (f.bitSize < 1 || f.bitSize > 32) continue;
    for (uint32_t e = 0; e < f.count; ++e) {
      const uint32_t usage = f.usageOf(e);
      const uint32_t offset = f.bitOffset + e * f.bitSize;
      const bool data = !(f.flags & kHidConstant) && (f.flags & kHidVariable) && f.bitSize >= 1 && f.bitSize <= 32;
      if (data && usage == hidUsage(kImpsHidUsagePage, kImpsUsageSequence) && !layout.sequence) {
        layout.sequence = HidCounterField{offset, static_cast<uint8_t>(f.bitSize)};
        continue;
      }
      if (data && usage == hidUsage(kImpsHidUsagePage, kImpsUsageDeviceTime) && !layout.deviceTime) {
        layout.deviceTime = HidCounterField{offset, static_cast<uint8_t>(f.bitSize)};
        continue;
      }
      if (!isChannelField(f) || !isChannelUsage(usage)) continue;
      if (layout.channels.size() >= static_cast<size_t>(kMaxChannels)) {
        ++ignored;
        continue;
      }
      HidChannel c;
      c.bitOffset = offset;
      c.bitSize = static_cast<uint8_t>(f.bitSize);
      c.logicalMin = f.logicalMin;
      c.logicalMax = f.logicalMax;
      c.rangeChecked = f.logicalMax >= f.logicalMin && !(f.logicalMin == 0 && f.logicalMax == 0);
      c.nullState = (f.flags & kHidNullState) != 0;
      c.usage = usage;
      c.name = usageName(usage);
      const std::string fallback = "ch" + std::to_string(layout.channels.size());
      for (const HidChannel& other : layout.channels)
        if (!c.name.empty() && other.name == c.name) c.name.clear();
      if (c.name.empty()) c.name = fallback;
      if (!c.rangeChecked)
        layout.warnings.push_back(cat("channel ", c.name, ": no usable logical range; values are not checked"));
      armatureApplication = armatureApplication && f.application == hidUsage(kImpsHidUsagePage, kImpsUsageArmature);
      layout.channels.push_back(std::move(c));
    }
  }
  if (ignored)
    layout.warnings.push_back(cat("input report ", int(*best), " has ", kMaxChannels + ignored, " channels; the ",
                                  ignored, " beyond ", kMaxChannels, " are ignored"));
  layout.looksLikeArmature = armatureApplication;
  return layout;
}

DeviceInfo hidFallbackInfo(const HidInputLayout& layout, std::string name, std::string serialNumber,
                           std::string firmwareVersion) {
  DeviceInfo info;
  info.name = std::move(name);
  info.serialNumber = std::move(serialNumber);
  info.firmwareVersion = std::move(firmwareVersion);
  info.channelCount = static_cast<int>(layout.channels.size());
  info.bitsPerChannel = layout.bitsPerChannel();
  for (const HidChannel& c : layout.channels) info.channelNames.push_back(c.name);
  info.hasDeviceTimestamp = layout.deviceTime.has_value();
  return info;
}

std::expected<DeviceInfo, Diagnostics> parseHidInfoReport(std::span<const uint8_t> report, bool usesReportIds) {
  if (usesReportIds) report = report.empty() ? report : report.subspan(1);
  BinaryDecoder decoder;
  decoder.feed(report);
  auto m = decoder.next();
  if (!m) return diagnosticError({}, "the INFO feature report holds no valid binary-protocol frame");
  if (const auto* i = std::get_if<msg::Info>(&m->payload)) return i->info;
  return diagnosticError(
      {}, cat("the INFO feature report holds a frame of type 0x", hex4(uint8_t(m->type())).substr(2), ", not INFO"));
}

// ---- Decoder

HidReportDecoder::HidReportDecoder(HidInputLayout layout) : layout_(std::move(layout)) {}

void HidReportDecoder::setLayout(HidInputLayout layout) {
  layout_ = std::move(layout);
  reset();
}

void HidReportDecoder::reset() {
  haveSequence_ = haveTime_ = false;
  lastSequenceRaw_ = sequence_ = lastTimeRaw_ = 0;
  timeUs_ = 0;
}

std::optional<Sample> HidReportDecoder::decode(std::span<const uint8_t> report, int64_t arrivalTimeNs) {
  ++stats_.reports;
  stats_.bytes += report.size();
  if (layout_.usesReportIds && !report.empty() && report[0] != layout_.reportId) {
    if (std::ranges::find(layout_.otherInputIds, report[0]) != layout_.otherInputIds.end()) ++stats_.otherReports;
    else ++stats_.unknownReportIds;
    return std::nullopt;
  }
  if (report.size() < layout_.reportSize || layout_.channels.empty()) {
    ++stats_.shortReports;
    return std::nullopt;
  }
  const uint8_t* data = report.data() + (layout_.usesReportIds ? 1 : 0);

  Sample s;
  s.arrivalTimeNs = arrivalTimeNs;
  s.channelCount = static_cast<uint16_t>(layout_.channels.size());
  for (size_t i = 0; i < layout_.channels.size(); ++i) {
    const HidChannel& c = layout_.channels[i];
    const uint32_t raw = getBits(data, c.bitOffset, c.bitSize);
    s.counts[i] = raw;
    if (!c.rangeChecked) continue;
    int64_t v = raw;
    if (c.logicalMin < 0 && c.bitSize < 64 && (raw >> (c.bitSize - 1)) & 1u) v -= int64_t{1} << c.bitSize;
    if (v < c.logicalMin || v > c.logicalMax) {
      s.flags[i] = c.nullState ? ChannelFlag::NotConnected : ChannelFlag::Outlier;
      ++stats_.flaggedChannels;
    }
  }

  if (const auto& f = layout_.sequence) {
    const uint32_t raw = getBits(data, f->bitOffset, f->bitSize);
    if (haveSequence_) {
      const uint32_t delta = (raw - lastSequenceRaw_) & mask(f->bitSize);
      const uint32_t half = f->bitSize >= 32 ? 0x80000000u : (1u << (f->bitSize - 1));
      if (delta == 0 || delta >= half) {
        ++stats_.sequenceResets;
        sequence_ = raw;
      } else {
        if (delta > 1) {
          ++stats_.sequenceGaps;
          stats_.samplesDropped += delta - 1;
        }
        sequence_ += delta;
      }
    } else {
      sequence_ = raw;
      haveSequence_ = true;
    }
    lastSequenceRaw_ = raw;
    s.sequence = sequence_;
  } else {
    s.sequence = ownSequence_++;
  }
  if (const auto& f = layout_.deviceTime) {
    const uint32_t raw = getBits(data, f->bitOffset, f->bitSize);
    timeUs_ = haveTime_ ? timeUs_ + ((raw - lastTimeRaw_) & mask(f->bitSize)) : raw;
    haveTime_ = true;
    lastTimeRaw_ = raw;
    // Kept below 2^63 ns: a device clock does not run for 292 years.
    s.deviceTimeNs = static_cast<int64_t>(std::min<uint64_t>(timeUs_, uint64_t{1} << 53) * 1000);
  }
  ++stats_.samples;
  return s;
}

// ---- Device side

std::expected<std::vector<uint8_t>, Diagnostics> encodeHidInputReport(const HidInputLayout& layout,
                                                                      const Sample& sample) {
  if (sample.channelCount != layout.channels.size())
    return diagnosticError(
        {}, cat("the sample has ", sample.channelCount, " channels, the report ", layout.channels.size()));
  if (layout.reportSize == 0 || layout.reportSize > kMaxHidReportSize)
    return diagnosticError({}, "the layout has no valid report size");
  std::vector<uint8_t> out(layout.reportSize, 0);
  if (layout.usesReportIds) out[0] = layout.reportId;
  uint8_t* data = out.data() + (layout.usesReportIds ? 1 : 0);
  for (size_t i = 0; i < layout.channels.size(); ++i) {
    const HidChannel& c = layout.channels[i];
    uint32_t v = sample.counts[i];
    if (sample.flags[i] == ChannelFlag::NotConnected && c.nullState) v = 0xFFFFFFFFu;
    putBits(data, c.bitOffset, c.bitSize, v & mask(c.bitSize));
  }
  if (const auto& f = layout.sequence) putBits(data, f->bitOffset, f->bitSize, sample.sequence & mask(f->bitSize));
  if (const auto& f = layout.deviceTime)
    putBits(data, f->bitOffset, f->bitSize,
            static_cast<uint32_t>(static_cast<uint64_t>(std::max<int64_t>(sample.deviceTimeNs, 0) / 1000) &
                                  mask(f->bitSize)));
  return out;
}

namespace {
// Appends one short item with the smallest data size that holds `value` (signed when `isSigned`).
void item(std::vector<uint8_t>& d, uint8_t prefix, int64_t value, bool isSigned = false) {
  size_t size = 0;
  if (isSigned) size = value >= -128 && value <= 127 ? 1 : value >= -32768 && value <= 32767 ? 2 : 4;
  else size = value < 0x100 ? 1 : value < 0x10000 ? 2 : 4;
  d.push_back(static_cast<uint8_t>(prefix | (size == 4 ? 3 : size)));
  for (size_t i = 0; i < size; ++i) d.push_back(static_cast<uint8_t>(static_cast<uint64_t>(value) >> (8 * i)));
}
}  // namespace

std::vector<uint8_t> hidArmatureDescriptor(const HidArmatureDescriptorOptions& o) {
  const int channels = std::clamp(o.channels, 1, kMaxChannels);
  const int bits = std::clamp(o.bits, 2, 32);
  std::vector<uint8_t> d;
  item(d, kUsagePage, kImpsHidUsagePage);
  item(d, kUsage, kImpsUsageArmature);
  item(d, kCollection, kApplicationCollection);
  if (o.reportId) item(d, kReportId, o.reportId);
  item(d, kLogicalMin, 0, true);
  if (o.sequence) {
    item(d, kUsage, kImpsUsageSequence);
    item(d, kLogicalMax, 0xFFFF);
    item(d, kReportSize, 16);
    item(d, kReportCount, 1);
    item(d, kInput, kHidVariable);
  }
  if (o.deviceTime) {
    item(d, kUsage, kImpsUsageDeviceTime);
    item(d, kLogicalMax, 0xFFFFFFFFLL);
    item(d, kReportSize, 32);
    item(d, kReportCount, 1);
    item(d, kInput, kHidVariable);
  }
  item(d, kUsage, kImpsUsageChannel);
  item(d, kLogicalMax, static_cast<int64_t>((uint64_t{1} << bits) - 2));
  item(d, kReportSize, bits);
  item(d, kReportCount, channels);
  item(d, kInput, kHidVariable | kHidNullState);
  if (const int pad = (8 - (channels * bits) % 8) % 8) {
    item(d, kReportSize, pad);
    item(d, kReportCount, 1);
    item(d, kInput, kHidConstant);
  }
  if (o.reportId && o.infoReportSize > 0) {
    item(d, kReportId, o.reportId + 1);
    item(d, kUsage, kImpsUsageInfo);
    item(d, kLogicalMax, 0xFF);
    item(d, kReportSize, 8);
    item(d, kReportCount, o.infoReportSize);
    item(d, kFeature, kHidVariable | 0x100);  // Buffered Bytes
  }
  d.push_back(kEndCollection);
  return d;
}

std::expected<std::vector<uint8_t>, Diagnostics> hidInfoReport(const DeviceInfo& info, uint8_t reportId,
                                                               size_t dataSize) {
  std::vector<uint8_t> frame;
  if (auto r = appendFrame(Message{0, kFlagReply, msg::Info{info}}, frame); !r) return std::unexpected(r.error());
  if (frame.size() > dataSize)
    return diagnosticError({},
                           cat("the INFO frame takes ", frame.size(), " bytes; the feature report holds ", dataSize));
  std::vector<uint8_t> out;
  if (reportId) out.push_back(reportId);
  out.insert(out.end(), frame.begin(), frame.end());
  out.resize(dataSize + (reportId ? 1 : 0), 0);
  return out;
}

}  // namespace imps::drivers
