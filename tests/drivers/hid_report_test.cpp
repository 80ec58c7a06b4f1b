// SPDX-License-Identifier: MIT
// Tests for drivers/hid_report: the report descriptor parser, the armature layout, the input report decoder and
// the device-side encoders, on hand-written real-world-like descriptors with known bytes.
#include "drivers/hid_report.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace imps::drivers {
namespace {

// A joystick as a cheap game controller describes itself: X/Y 10 bits, Z/Rz 8 bits, a hat switch with Null
// State, 12 buttons and 4 padding bits — 56 bits, no report IDs, fields not byte-aligned.
const std::vector<uint8_t> kJoystick = {
    0x05, 0x01, 0x09, 0x04, 0xA1, 0x01,              // Generic Desktop, Joystick, Collection (Application)
    0x09, 0x01, 0xA1, 0x00,                          //   Pointer, Collection (Physical)
    0x09, 0x30, 0x09, 0x31, 0x15, 0x00, 0x26, 0xFF, 0x03, 0x75, 0x0A, 0x95, 0x02, 0x81, 0x02,  // X, Y
    0xC0,                                            //   End Collection
    0x09, 0x32, 0x09, 0x35, 0x26, 0xFF, 0x00, 0x75, 0x08, 0x95, 0x02, 0x81, 0x02,              // Z, Rz
    0x09, 0x39, 0x15, 0x00, 0x25, 0x07, 0x75, 0x04, 0x95, 0x01, 0x81, 0x42,                    // hat, Null
    0x05, 0x09, 0x19, 0x01, 0x29, 0x0C, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x0C, 0x81, 0x02,  // buttons
    0x75, 0x04, 0x95, 0x01, 0x81, 0x03,              //   padding
    0xC0};

// A composite device: report 1 a mouse (relative axes: no channels), report 2 three 12-bit IMPS channels in an
// armature collection, feature report 3 the INFO frame (16 bytes). Uses Push/Pop around the mouse.
const std::vector<uint8_t> kComposite = {
    0x05, 0x01, 0x09, 0x02, 0xA1, 0x01, 0x85, 0x01,  // Generic Desktop, Mouse, Application, Report ID 1
    0xA4,                                            // Push
    0x05, 0x09, 0x19, 0x01, 0x29, 0x03, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x03, 0x81, 0x02,  // buttons
    0x75, 0x05, 0x95, 0x01, 0x81, 0x03,              // padding
    0x05, 0x01, 0x09, 0x30, 0x09, 0x31, 0x15, 0x81, 0x25, 0x7F, 0x75, 0x08, 0x95, 0x02, 0x81, 0x06,  // X, Y rel
    0xB4,                                            // Pop
    0xC0,
    0x06, 0xA5, 0xFF, 0x09, 0x01, 0xA1, 0x01, 0x85, 0x02,  // IMPS page, Armature, Application, Report ID 2
    0x09, 0x02, 0x15, 0x00, 0x26, 0xFE, 0x0F, 0x75, 0x0C, 0x95, 0x03, 0x81, 0x42,  // 3 × 12 bits, Null State
    0x75, 0x04, 0x95, 0x01, 0x81, 0x03,                                          // padding to 40 bits
    0x85, 0x03, 0x09, 0x30, 0x26, 0xFF, 0x00, 0x75, 0x08, 0x95, 0x10, 0xB1, 0x02,  // feature 3: 16 bytes
    0xC0};

// Packs `n`-bit values LSB first (an independent reference for the decoder).
void pack(std::vector<uint8_t>& out, uint32_t& bit, uint32_t n, uint64_t value) {
  for (uint32_t i = 0; i < n; ++i, ++bit) {
    if (out.size() <= bit / 8) out.resize(bit / 8 + 1, 0);
    if ((value >> i) & 1) out[bit / 8] |= static_cast<uint8_t>(1u << (bit % 8));
  }
}

HidInputLayout layoutOf(const std::vector<uint8_t>& descriptor) {
  auto parsed = parseHidReportDescriptor(descriptor);
  EXPECT_TRUE(parsed) << parsed.error().str();
  if (!parsed) return {};
  auto layout = hidArmatureLayout(*parsed);
  EXPECT_TRUE(layout) << layout.error().str();
  return layout ? *layout : HidInputLayout{};
}

TEST(HidReportDescriptor, ParsesAJoystick) {
  auto d = parseHidReportDescriptor(kJoystick);
  ASSERT_TRUE(d) << d.error().str();
  EXPECT_FALSE(d->usesReportIds);
  ASSERT_EQ(d->applications.size(), 1u);
  EXPECT_EQ(d->applications[0], hidUsage(0x01, 0x04));
  ASSERT_EQ(d->reports.size(), 1u);
  EXPECT_EQ(d->reports[0].bits, 56u);
  EXPECT_EQ(d->reports[0].bytes(false), 7u);
  ASSERT_EQ(d->fields.size(), 5u);
  EXPECT_EQ(d->fields[1].bitOffset, 20u);  // Z, Rz
  EXPECT_EQ(d->fields[3].usages.size(), 12u);  // Usage Minimum..Maximum expanded
  EXPECT_EQ(d->fields[3].usageOf(11), hidUsage(0x09, 12));

  HidInputLayout l = layoutOf(kJoystick);
  EXPECT_FALSE(l.looksLikeArmature);
  EXPECT_EQ(l.reportSize, 7u);
  ASSERT_EQ(l.channels.size(), 5u);  // X Y Z Rz hat; buttons and padding are not channels
  const char* names[] = {"X", "Y", "Z", "Rz", "ch4"};
  const uint32_t offsets[] = {0, 10, 20, 28, 36}, sizes[] = {10, 10, 8, 8, 4};
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(l.channels[i].name, names[i]);
    EXPECT_EQ(l.channels[i].bitOffset, offsets[i]);
    EXPECT_EQ(l.channels[i].bitSize, sizes[i]);
  }
  EXPECT_EQ(l.channels[0].logicalMax, 1023);
  EXPECT_TRUE(l.channels[4].nullState);
  EXPECT_EQ(l.bitsPerChannel(), 10);
}

TEST(HidReportDecoder, DecodesAJoystickReportByteExact) {
  HidReportDecoder dec(layoutOf(kJoystick));
  // X 0x3A5, Y 0x15C, Z 0x80, Rz 0xFE, hat 9 (outside 0..7: released), buttons 0xABC.
  const std::vector<uint8_t> report = {0xA5, 0x73, 0x05, 0xE8, 0x9F, 0xBC, 0x0A};
  auto s = dec.decode(report, 42);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->channelCount, 5);
  EXPECT_EQ(s->counts[0], 0x3A5u);
  EXPECT_EQ(s->counts[1], 0x15Cu);
  EXPECT_EQ(s->counts[2], 0x80u);
  EXPECT_EQ(s->counts[3], 0xFEu);
  EXPECT_EQ(s->counts[4], 9u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(s->flags[i], ChannelFlag::Valid);
  EXPECT_EQ(s->flags[4], ChannelFlag::NotConnected);
  EXPECT_EQ(s->arrivalTimeNs, 42);
  EXPECT_EQ(s->sequence, 0u);
  EXPECT_EQ(s->deviceTimeNs, 0);
  EXPECT_EQ(dec.stats().flaggedChannels, 1u);
  EXPECT_EQ(dec.decode(report)->sequence, 1u);  // no sequence field: the decoder numbers the samples
}

TEST(HidReportDecoder, CompositeDevicePicksTheArmatureReportAndCountsTheRest) {
  HidInputLayout l = layoutOf(kComposite);
  EXPECT_TRUE(l.usesReportIds);
  EXPECT_EQ(l.reportId, 2);
  EXPECT_EQ(l.reportSize, 6u);  // ID + 40 bits
  EXPECT_TRUE(l.looksLikeArmature);
  ASSERT_EQ(l.channels.size(), 3u);
  EXPECT_EQ(l.otherInputIds, std::vector<uint8_t>{1});
  ASSERT_TRUE(l.infoReportId.has_value());
  EXPECT_EQ(*l.infoReportId, 3);
  EXPECT_EQ(l.infoReportSize, 17u);

  HidReportDecoder dec(l);
  // 0x123, 0x456, 0xFFF (all ones: not connected, logical max 0xFFE).
  auto s = dec.decode(std::vector<uint8_t>{0x02, 0x23, 0x61, 0x45, 0xFF, 0x0F});
  ASSERT_TRUE(s);
  EXPECT_EQ(s->counts[0], 0x123u);
  EXPECT_EQ(s->counts[1], 0x456u);
  EXPECT_EQ(s->counts[2], 0xFFFu);
  EXPECT_EQ(s->flags[2], ChannelFlag::NotConnected);
  EXPECT_FALSE(dec.decode(std::vector<uint8_t>{0x01, 0x01, 0x05, 0xFB}));       // the mouse: ignored
  EXPECT_FALSE(dec.decode(std::vector<uint8_t>{0x09, 0, 0, 0, 0, 0}));          // unknown ID
  EXPECT_FALSE(dec.decode(std::vector<uint8_t>{0x02, 0x23, 0x61}));             // short
  EXPECT_FALSE(dec.decode(std::vector<uint8_t>{}));                            // empty read
  EXPECT_TRUE(dec.decode(std::vector<uint8_t>{0x02, 0, 0, 0, 0, 0, 0xEE, 0xEE}));  // padded: accepted
  const HidDecoderStats& st = dec.stats();
  EXPECT_EQ(st.reports, 6u);
  EXPECT_EQ(st.samples, 2u);
  EXPECT_EQ(st.otherReports, 1u);
  EXPECT_EQ(st.unknownReportIds, 1u);
  EXPECT_EQ(st.shortReports, 2u);
  EXPECT_EQ(st.reports, st.samples + st.otherReports + st.unknownReportIds + st.shortReports);
}

TEST(HidReportDecoder, SignedFieldsKeepRawBitsAndCheckTheSignedRange) {
  // Two 12-bit signed fields, Logical −100..100, no Null State: out of range is an outlier.
  const std::vector<uint8_t> desc = {0x05, 0x01, 0x09, 0x05, 0xA1, 0x01, 0x09, 0x30, 0x09, 0x31, 0x15, 0x9C,
                                     0x25, 0x64, 0x75, 0x0C, 0x95, 0x02, 0x81, 0x02, 0xC0};
  HidInputLayout l = layoutOf(desc);
  ASSERT_EQ(l.channels.size(), 2u);
  EXPECT_EQ(l.channels[0].logicalMin, -100);
  EXPECT_EQ(l.channels[0].logicalMax, 100);
  HidReportDecoder dec(l);
  std::vector<uint8_t> r;
  uint32_t bit = 0;
  pack(r, bit, 12, 0xF9C);  // −100: in range
  pack(r, bit, 12, 0x0C8);  // 200: out of range
  auto s = dec.decode(r);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->counts[0], 0xF9Cu);
  EXPECT_EQ(s->flags[0], ChannelFlag::Valid);
  EXPECT_EQ(s->counts[1], 0x0C8u);
  EXPECT_EQ(s->flags[1], ChannelFlag::Outlier);
}

TEST(HidReportDescriptor, ExtendedUsagesPushPopAndLongItems) {
  const std::vector<uint8_t> desc = {
      0x0B, 0x01, 0x00, 0xA5, 0xFF, 0xA1, 0x01,  // Usage (IMPS:Armature) as a 4-byte usage; Application
      0xFE, 0x02, 0x10, 0xAA, 0xBB,              // a long item: skipped
      0x75, 0x10, 0x95, 0x02, 0x15, 0x00, 0x27, 0xFF, 0xFF, 0x00, 0x00,
      0xA4, 0x75, 0x08, 0xB4,                    // Push, Report Size 8, Pop: back to 16
      0x0B, 0x02, 0x00, 0xA5, 0xFF, 0x81, 0x02,  // 2 × 16-bit channels
      0xC0};
  HidInputLayout l = layoutOf(desc);
  EXPECT_TRUE(l.looksLikeArmature);
  ASSERT_EQ(l.channels.size(), 2u);
  EXPECT_EQ(l.channels[1].bitSize, 16);
  EXPECT_EQ(l.channels[1].bitOffset, 16u);
  EXPECT_EQ(l.channels[0].usage, hidUsage(kImpsHidUsagePage, kImpsUsageChannel));
  EXPECT_EQ(l.channels[1].logicalMax, 0xFFFF);
}

TEST(HidReportDescriptor, BadDescriptorsGiveLocatedErrors) {
  const struct {
    std::vector<uint8_t> bytes;
    const char* message;
  } cases[] = {
      {{}, "report descriptor:0: error: empty"},
      {{0x05, 0x01, 0x26, 0xFF}, "report descriptor:2: error: item 0x26 needs 2 data bytes"},
      {{0xB4}, "report descriptor:0: error: Pop without a matching Push"},
      {{0xC0}, "report descriptor:0: error: End Collection without a Collection"},
      {{0xA1, 0x01, 0x81, 0x02}, "report descriptor:4: error: a Collection is not closed"},
      {{0x85, 0x00}, "report descriptor:0: error: Report ID must be 1..255"},
      {{0x75, 0x08, 0x95, 0x01, 0x81, 0x02, 0x85, 0x01, 0x81, 0x02},
       "report descriptor:4: error: a main item before the first Report ID"},
      {{0x75, 0x08, 0x96, 0x00, 0x10, 0x81, 0x02}, "report descriptor:5: error: report 0 grows beyond 4096 bytes"},
      {{0xFE, 0x05, 0x00, 0x01}, "report descriptor:0: error: truncated long item data"},
  };
  for (const auto& c : cases) {
    auto d = parseHidReportDescriptor(c.bytes);
    ASSERT_FALSE(d) << c.message;
    EXPECT_EQ(d.error().str().rfind(c.message, 0), 0u) << d.error().str();
  }
  std::vector<uint8_t> deep;
  for (int i = 0; i < 17; ++i) deep.push_back(0xA4);
  EXPECT_NE(parseHidReportDescriptor(deep).error().str().find("more than 16 nested Push"), std::string::npos);
  // Parses, but has nothing to sample: only buttons.
  const std::vector<uint8_t> buttons = {0x05, 0x09, 0x19, 0x01, 0x29, 0x08, 0x75, 0x01, 0x95, 0x08, 0x81, 0x02};
  auto d = parseHidReportDescriptor(buttons);
  ASSERT_TRUE(d) << d.error().str();
  auto l = hidArmatureLayout(*d);
  ASSERT_FALSE(l);
  EXPECT_NE(l.error().str().find("no input report carries a channel"), std::string::npos);
}

// Encoder → decoder round trips on the IMPS armature descriptor: 8, 10, 12, 16 and 32-bit channels, with and
// without report IDs, sequence and device time; 64 channels.
TEST(HidReportCodec, ArmatureRoundTripsAtEveryWidth) {
  for (int bits : {8, 10, 12, 16, 32}) {
    for (int channels : {1, 3, 32, 64}) {
      for (uint8_t id : {uint8_t{0}, uint8_t{7}}) {
        HidArmatureDescriptorOptions o;
        o.channels = channels;
        o.bits = bits;
        o.reportId = id;
        o.deviceTime = channels % 2 == 0;
        HidInputLayout l = layoutOf(hidArmatureDescriptor(o));
        ASSERT_EQ(static_cast<int>(l.channels.size()), channels);
        EXPECT_TRUE(l.looksLikeArmature);
        EXPECT_EQ(l.bitsPerChannel(), bits);
        EXPECT_EQ(l.deviceTime.has_value(), o.deviceTime);
        EXPECT_EQ(l.infoReportId.has_value(), id != 0);
        const size_t dataBits = 16 + (o.deviceTime ? 32 : 0) + channels * bits;
        EXPECT_EQ(l.reportSize, (dataBits + 7) / 8 + (id ? 1 : 0));
        HidReportDecoder dec(l);
        Sample s;
        s.channelCount = static_cast<uint16_t>(channels);
        s.sequence = 1234;
        s.deviceTimeNs = o.deviceTime ? 987'654'000 : 0;
        const uint32_t max = static_cast<uint32_t>((uint64_t{1} << bits) - 2);
        for (int i = 0; i < channels; ++i)
          s.counts[i] = static_cast<uint32_t>((static_cast<uint64_t>(i) * 2654435761u) % max);
        s.counts[channels - 1] = max;
        if (channels > 2) s.flags[1] = ChannelFlag::NotConnected;
        auto report = encodeHidInputReport(l, s);
        ASSERT_TRUE(report) << report.error().str();
        auto back = dec.decode(*report, 5);
        ASSERT_TRUE(back);
        if (channels > 2) {
          EXPECT_EQ(back->counts[1], static_cast<uint32_t>((uint64_t{1} << bits) - 1));  // all ones
          s.counts[1] = back->counts[1];
        }
        s.arrivalTimeNs = 5;
        EXPECT_EQ(*back, s) << bits << " bits, " << channels << " channels, id " << int(id);
      }
    }
  }
}

// The example in docs/protocol.md ("The IMPS armature descriptor").
TEST(HidReportCodec, ArmatureDescriptorMatchesTheDocumentedBytes) {
  HidArmatureDescriptorOptions o;
  o.channels = 3;
  o.bits = 12;
  const std::vector<uint8_t> documented = {
      0x06, 0xA5, 0xFF, 0x09, 0x01, 0xA1, 0x01, 0x85, 0x01, 0x15, 0x00, 0x09, 0x20, 0x26, 0xFF, 0xFF, 0x75, 0x10,
      0x95, 0x01, 0x81, 0x02, 0x09, 0x02, 0x26, 0xFE, 0x0F, 0x75, 0x0C, 0x95, 0x03, 0x81, 0x42, 0x75, 0x04, 0x95,
      0x01, 0x81, 0x01, 0x85, 0x02, 0x09, 0x30, 0x25, 0xFF, 0x75, 0x08, 0x95, 0xFF, 0xB2, 0x02, 0x01, 0xC0};
  EXPECT_EQ(hidArmatureDescriptor(o), documented);
  HidInputLayout l = layoutOf(documented);
  ASSERT_EQ(l.channels.size(), 3u);
  EXPECT_EQ(l.channels[2].bitOffset, 16u + 24u);
  ASSERT_TRUE(l.sequence.has_value());
  EXPECT_EQ(l.sequence->bitOffset, 0u);
  EXPECT_EQ(l.reportSize, 8u);
  EXPECT_EQ(l.infoReportSize, 256u);
}

TEST(HidReportDecoder, SequenceWrapsGapsAndResets) {
  HidArmatureDescriptorOptions o;
  o.channels = 2;
  HidInputLayout l = layoutOf(hidArmatureDescriptor(o));
  HidReportDecoder dec(l);
  auto at = [&](uint32_t seq) {
    Sample s;
    s.channelCount = 2;
    s.sequence = seq;
    auto r = encodeHidInputReport(l, s);
    EXPECT_TRUE(r);
    return dec.decode(*r)->sequence;
  };
  EXPECT_EQ(at(65534), 65534u);
  EXPECT_EQ(at(65535), 65535u);
  EXPECT_EQ(at(0), 65536u);  // unwrapped past 16 bits
  EXPECT_EQ(at(1), 65537u);
  EXPECT_EQ(at(4), 65540u);  // 2 and 3 were lost
  EXPECT_EQ(dec.stats().sequenceGaps, 1u);
  EXPECT_EQ(dec.stats().samplesDropped, 2u);
  EXPECT_EQ(at(2), 2u);  // backwards: the device restarted
  EXPECT_EQ(dec.stats().sequenceResets, 1u);
}

TEST(HidReportDescriptor, MoreThan64ChannelsKeepsTheFirst64AndWarns) {
  const std::vector<uint8_t> desc = {0x06, 0xA5, 0xFF, 0x09, 0x01, 0xA1, 0x01, 0x09, 0x02, 0x15, 0x00,
                                     0x25, 0x7F, 0x75, 0x08, 0x95, 70, 0x81, 0x02, 0xC0};
  HidInputLayout l = layoutOf(desc);
  EXPECT_EQ(l.channels.size(), 64u);
  EXPECT_EQ(l.reportSize, 70u);
  ASSERT_EQ(l.warnings.size(), 1u);
  EXPECT_NE(l.warnings[0].find("70 channels"), std::string::npos) << l.warnings[0];
}

// A 0-bit field may declare 2^32 - 1 elements (it takes no bytes, so the size limit does not stop it). Laying out
// the report must not visit them one by one: that took minutes per 24-byte descriptor (fuzz seeds
// hid_report/zero_size_huge_count_*). Ignored like any other non-channel field; a Feature one holds no INFO usage.
TEST(HidReportDescriptor, ZeroSizeFieldsWithHugeCountsAreSkippedQuickly) {
  for (const uint8_t main : {uint8_t{0x81}, uint8_t{0xB1}}) {  // Input, Feature
    const std::vector<uint8_t> desc = {0x05, 0x01, 0x09, 0x30, 0x15, 0x00, 0x26, 0xFF, 0x00, 0x75, 0x08, 0x95,
                                       0x01, 0x81, 0x02, 0x75, 0x00, 0x97, 0xFF, 0xFF, 0xFF, 0xFF, main, 0x02};
    HidInputLayout l = layoutOf(desc);
    ASSERT_EQ(l.channels.size(), 1u);
    EXPECT_EQ(l.channels[0].name, "X");
    EXPECT_EQ(l.reportSize, 1u);
    EXPECT_FALSE(l.infoReportId);
  }
}

TEST(HidReportCodec, InfoFeatureReportRoundTrips) {
  DeviceInfo info;
  info.name = "IMPS Monkey HID";
  info.serialNumber = "HID0001";
  info.firmwareVersion = "1.2";
  info.channelCount = 3;
  info.bitsPerChannel = 12;
  info.channelNames = {"hip", "knee", "ankle"};
  auto report = hidInfoReport(info, 3, 100);
  ASSERT_TRUE(report) << report.error().str();
  EXPECT_EQ(report->size(), 101u);
  EXPECT_EQ((*report)[0], 3);
  auto back = parseHidInfoReport(*report, true);
  ASSERT_TRUE(back) << back.error().str();
  EXPECT_EQ(*back, info);
  EXPECT_FALSE(hidInfoReport(info, 3, 20));  // does not fit
  std::vector<uint8_t> zeros(40, 0);
  EXPECT_FALSE(parseHidInfoReport(zeros, true));
}

}  // namespace
}  // namespace imps::drivers
