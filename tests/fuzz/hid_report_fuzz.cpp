// SPDX-License-Identifier: MIT
// libFuzzer target for the HID codec (drivers/hid_report): any report descriptor must parse or give a located
// error, any layout must be consistent, and any input report must decode or be counted, never crash; what
// decodes must re-encode and decode to the same counts and flags (docs/protocol.md, "HID armatures").
// Input: [descriptor length n: u8][n descriptor bytes] then reports as [length: u8][bytes]…
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <vector>

#include "drivers/hid_report.h"

#include "fuzz_check.h"

using namespace imps::drivers;

namespace {

void checkLayout(const HidInputLayout& l) {
  FUZZ_CHECK(!l.channels.empty() && l.channels.size() <= static_cast<size_t>(kMaxChannels));
  FUZZ_CHECK(l.reportSize >= (l.usesReportIds ? 1u : 0u) && l.reportSize <= kMaxHidReportSize);
  const size_t dataBits = (l.reportSize - (l.usesReportIds ? 1 : 0)) * 8;
  for (const HidChannel& c : l.channels) {
    FUZZ_CHECK(c.bitSize >= 1 && c.bitSize <= 32);
    FUZZ_CHECK(c.bitOffset + c.bitSize <= dataBits);
    FUZZ_CHECK(!c.name.empty());
  }
  for (const auto& f : {l.sequence, l.deviceTime})
    if (f) FUZZ_CHECK(f->bitSize >= 1 && f->bitSize <= 32 && f->bitOffset + f->bitSize <= dataBits);
  FUZZ_CHECK(!l.usesReportIds || l.reportId != 0);
  FUZZ_CHECK(std::ranges::find(l.otherInputIds, l.reportId) == l.otherInputIds.end());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const size_t n = std::min<size_t>(data[0], size - 1);
  const std::span<const uint8_t> descriptor(data + 1, n);
  std::span<const uint8_t> rest(data + 1 + n, size - 1 - n);

  auto parsed = parseHidReportDescriptor(descriptor);
  if (!parsed) {
    FUZZ_CHECK(parsed.error().str().rfind("report descriptor:", 0) == 0);
    return 0;
  }
  for (const HidField& f : parsed->fields) {
    const HidReportSize* r = parsed->report(f.kind, f.reportId);
    FUZZ_CHECK(r != nullptr);
    FUZZ_CHECK(uint64_t{f.bitOffset} + uint64_t{f.bitSize} * f.count <= r->bits);
    FUZZ_CHECK(r->bytes(parsed->usesReportIds) <= kMaxHidReportSize);
  }
  auto layout = hidArmatureLayout(*parsed);
  if (!layout) {
    FUZZ_CHECK(layout.error().str().rfind("report descriptor:", 0) == 0);
    return 0;
  }
  checkLayout(*layout);
  // A fallback description is always a valid one.
  const DeviceInfo info = hidFallbackInfo(*layout, "x", "", "");
  FUZZ_CHECK(info.channelCount == static_cast<int>(layout->channels.size()));
  FUZZ_CHECK(static_cast<int>(info.channelNames.size()) == info.channelCount);

  HidReportDecoder decoder(*layout);
  HidReportDecoder again(*layout);
  while (!rest.empty()) {
    const size_t len = std::min<size_t>(rest[0], rest.size() - 1);
    std::vector<uint8_t> report(rest.begin() + 1, rest.begin() + 1 + static_cast<std::ptrdiff_t>(len));
    rest = rest.subspan(1 + len);
    // Short reports of the chosen ID are often "almost right": also try the report padded to its size.
    if (!report.empty() && report.size() < layout->reportSize && (report[0] & 1))
      report.resize(layout->reportSize, 0);
    auto s = decoder.decode(report, 7);
    const HidDecoderStats& st = decoder.stats();
    FUZZ_CHECK(st.reports == st.samples + st.otherReports + st.unknownReportIds + st.shortReports);
    if (!s) continue;
    FUZZ_CHECK(s->channelCount == layout->channels.size());
    FUZZ_CHECK(s->arrivalTimeNs == 7 && s->deviceTimeNs >= 0);
    for (int i = 0; i < kMaxChannels; ++i) {
      if (i < s->channelCount) {
        FUZZ_CHECK(uint64_t{s->counts[i]} < (uint64_t{1} << layout->channels[i].bitSize));
        FUZZ_CHECK(static_cast<uint8_t>(s->flags[i]) <= 2);
      } else {
        FUZZ_CHECK(s->counts[i] == 0 && s->flags[i] == ChannelFlag::Valid);
      }
    }
    // Re-encoding gives a report that decodes to the same readings (flags included).
    auto encoded = encodeHidInputReport(*layout, *s);
    FUZZ_CHECK(encoded.has_value());
    FUZZ_CHECK(encoded->size() == layout->reportSize);
    auto back = again.decode(*encoded, 7);
    FUZZ_CHECK(back.has_value());
    // (A NotConnected channel is written as all ones, which need not be out of range: not compared.)
    for (int i = 0; i < s->channelCount; ++i) {
      if (s->flags[i] == ChannelFlag::NotConnected) continue;
      FUZZ_CHECK(back->counts[i] == s->counts[i] && back->flags[i] == s->flags[i]);
    }
  }
  return 0;
}
