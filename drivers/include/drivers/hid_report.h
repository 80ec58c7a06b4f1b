// SPDX-License-Identifier: MIT
// The HID armature codec (docs/protocol.md, "HID armatures"): parses a HID report descriptor into the layout of
// the armature's input report, decodes input reports into Samples, and (device side, for tests and the simulator)
// builds descriptors and encodes reports. Pure: no hidapi, no I/O.
#pragma once

#include <cstddef>
#include <cstdint>
#include <expected>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "drivers/sample.h"
#include "imps/diagnostic.h"

namespace imps::drivers {

// ---- The IMPS usages (vendor-defined usage page) -------------------------------------------------------------
inline constexpr uint16_t kImpsHidUsagePage = 0xFFA5;
inline constexpr uint16_t kImpsUsageArmature = 0x01;   // the top-level Application collection of an armature
inline constexpr uint16_t kImpsUsageChannel = 0x02;    // an encoder channel (any usage that is not below works)
inline constexpr uint16_t kImpsUsageSequence = 0x20;   // input: sample counter, wraps at 2^ReportSize
inline constexpr uint16_t kImpsUsageDeviceTime = 0x21; // input: device clock in µs, wraps at 2^ReportSize
inline constexpr uint16_t kImpsUsageInfo = 0x30;       // feature: one binary-protocol INFO frame, zero-padded
// An extended usage: page in the high 16 bits, usage id in the low 16 (as the HID spec's 4-byte Usage items).
constexpr uint32_t hidUsage(uint16_t page, uint16_t id) { return (uint32_t{page} << 16) | id; }

// Largest report (data bytes plus the report ID byte) the codec accepts; also hidraw's buffer size.
inline constexpr size_t kMaxHidReportSize = 4096;

// ---- Parsed report descriptor --------------------------------------------------------------------------------

enum class HidReportKind : uint8_t { Input, Output, Feature };

// Bits of a main item's data (HID 1.11, 6.2.2.5).
inline constexpr uint32_t kHidConstant = 0x001;   // padding / fixed data
inline constexpr uint32_t kHidVariable = 0x002;   // one value per element (not an array of usage indices)
inline constexpr uint32_t kHidRelative = 0x004;
inline constexpr uint32_t kHidNullState = 0x040;  // a value outside the logical range means "no data"

// One Input, Output or Feature main item: `count` elements of `bitSize` bits each, starting at `bitOffset` bits
// into the report's data (the report ID byte, when present, is not counted).
struct HidField {
  HidReportKind kind = HidReportKind::Input;
  uint8_t reportId = 0;  // 0 when the descriptor uses no report IDs
  uint32_t bitOffset = 0;
  uint32_t bitSize = 0;   // Report Size
  uint32_t count = 0;     // Report Count
  uint32_t flags = 0;     // kHid* main item bits
  int64_t logicalMin = 0, logicalMax = 0;  // Logical Maximum is unsigned when Logical Minimum >= 0 (as Linux)
  // Extended usages of the elements in order; element i uses usages[min(i, size-1)]. May be empty.
  std::vector<uint32_t> usages;
  uint32_t application = 0;  // extended usage of the enclosing top-level Application collection (0: none)
  uint32_t usageOf(uint32_t element) const;
};

// One report: its kind, ID and total data size.
struct HidReportSize {
  HidReportKind kind = HidReportKind::Input;
  uint8_t id = 0;
  uint32_t bits = 0;
  // Bytes hidraw (and hidapi) deliver for it: the data rounded up to bytes, plus the ID byte when IDs are used.
  size_t bytes(bool usesReportIds) const { return (bits + 7) / 8 + (usesReportIds ? 1 : 0); }
};

struct HidReportDescriptor {
  std::vector<HidField> fields;     // in descriptor order
  std::vector<HidReportSize> reports;  // one per (kind, id) that has fields, in order of first appearance
  bool usesReportIds = false;
  std::vector<uint32_t> applications;  // extended usages of the top-level Application collections, in order
  const HidReportSize* report(HidReportKind kind, uint8_t id) const;
};

// Parses a report descriptor (short items; long items are skipped). Understands Usage Page, Usage, Usage
// Minimum/Maximum, Logical Minimum/Maximum, Report Size/Count/ID, Push/Pop, Input/Output/Feature, Collection and
// End Collection; other items are accepted and ignored. Errors are one diagnostic whose file is
// "report descriptor:OFFSET" (printed "report descriptor:OFFSET: error: …"), OFFSET the 0-based byte offset of the
// offending item: a truncated item, Report ID 0, Pop without Push, more than 16
// pushes or 32 nested collections, unbalanced collections, a main item without an ID in a descriptor that uses
// report IDs, a report larger than kMaxHidReportSize, or an empty descriptor. Never throws.
std::expected<HidReportDescriptor, Diagnostics> parseHidReportDescriptor(std::span<const uint8_t> bytes);

// ---- The armature's input report -----------------------------------------------------------------------------

// One encoder channel inside the input report.
struct HidChannel {
  uint32_t bitOffset = 0;  // into the report's data (after the ID byte)
  uint8_t bitSize = 0;     // 1..32
  int64_t logicalMin = 0, logicalMax = 0;
  bool rangeChecked = true;  // false when the descriptor declared no usable range (max < min, or 0..0)
  bool nullState = false;    // out-of-range values mean "not connected" (otherwise "outlier")
  uint32_t usage = 0;
  std::string name;          // from the usage: "X", "Rz", "Slider", … or "ch<i>"
  bool operator==(const HidChannel&) const = default;
};

// A scalar input field of the IMPS page (sequence or device time).
struct HidCounterField {
  uint32_t bitOffset = 0;
  uint8_t bitSize = 0;  // 1..32
  bool operator==(const HidCounterField&) const = default;
};

// Where the samples are in the device's input reports, chosen from a parsed descriptor by hidArmatureLayout().
struct HidInputLayout {
  bool usesReportIds = false;
  uint8_t reportId = 0;     // the input report carrying the channels (0 without report IDs)
  size_t reportSize = 0;    // bytes per input report as hidapi delivers it (ID byte included when used)
  std::vector<HidChannel> channels;  // 1..kMaxChannels, in descriptor order
  std::optional<HidCounterField> sequence, deviceTime;
  std::vector<uint8_t> otherInputIds;  // input reports of the same device that carry no samples (ignored)
  // The feature report carrying the INFO frame (kImpsUsageInfo), if declared: its ID and size in bytes (ID
  // byte included when used).
  std::optional<uint8_t> infoReportId;
  size_t infoReportSize = 0;
  // True when the channels sit in an Application collection with the IMPS armature usage.
  bool looksLikeArmature = false;
  std::vector<std::string> warnings;  // e.g. channels beyond 64 ignored, a channel without a usable range
  int bitsPerChannel() const;  // the widest channel
  bool operator==(const HidInputLayout&) const = default;
};

// What a HID transport tells the session when it opens (ByteTransport::hidDescription()): the device's
// description and where the samples are in its input reports.
struct HidDeviceDescription {
  DeviceInfo info;
  HidInputLayout layout;
};

// Picks the input report with the most channels (ties: the lowest ID) and lays it out. A channel is an element
// of an Input item that is Data, Variable and Absolute, 1..32 bits, not on the Button/Keyboard/LED pages and not
// the IMPS sequence or device-time usage. Beyond 64 channels the rest are ignored (warned). Error
// "report descriptor: error: …" when no input report has a channel.
std::expected<HidInputLayout, Diagnostics> hidArmatureLayout(const HidReportDescriptor& descriptor);

// The description a HID armature gets when it sends no INFO feature report: channel count, widest channel,
// names from the usages, device timestamp when a device-time field exists; name/serial/firmware as given.
DeviceInfo hidFallbackInfo(const HidInputLayout& layout, std::string name, std::string serialNumber,
                           std::string firmwareVersion);

// Reads the INFO frame out of a feature report's bytes (ID byte first when `usesReportIds`): the first valid
// binary-protocol frame in it, which must be INFO (trailing zero padding is ignored). Errors name what is wrong
// (one diagnostic without a position).
std::expected<DeviceInfo, Diagnostics> parseHidInfoReport(std::span<const uint8_t> report, bool usesReportIds);

// ---- Decoder -------------------------------------------------------------------------------------------------

// Every report fed is exactly one of samples + otherReports + unknownReportIds + shortReports.
struct HidDecoderStats {
  uint64_t reports = 0;
  uint64_t bytes = 0;
  uint64_t samples = 0;
  uint64_t otherReports = 0;      // another input report of the device (listed in otherInputIds): ignored
  uint64_t unknownReportIds = 0;  // a report ID the descriptor does not declare for input
  uint64_t shortReports = 0;      // fewer bytes than the layout's reportSize (includes empty reads)
  uint64_t flaggedChannels = 0;   // channel values outside their logical range
  uint64_t sequenceGaps = 0;      // with a sequence field: forward jumps
  uint64_t samplesDropped = 0;    // sequence numbers missing across them
  uint64_t sequenceResets = 0;    // a sequence that repeated or went backwards
  bool operator==(const HidDecoderStats&) const = default;
};

// Turns input reports, one per call as hidraw delivers them, into Samples. Not thread-safe (the session's I/O
// thread owns it). Bad reports never throw: they are counted and skipped. Reports longer than the layout's size
// are decoded and the extra bytes ignored (some firmware always sends 64 bytes).
//
// Sample fields: counts are each channel's raw bits (two's complement for signed fields, so a wrap-around rig
// map sees them as continuous); a value outside the logical range is flagged NotConnected on a Null State field,
// Outlier otherwise. sequence: the device's counter unwrapped to 32 bits, or the decoder's own running number
// without one. deviceTimeNs: the device-time field unwrapped to 64 bits, × 1000; 0 without one.
class HidReportDecoder {
 public:
  explicit HidReportDecoder(HidInputLayout layout = {});
  // Replaces the layout (a reconnect may bring another device); forgets sequence and time tracking; keeps stats.
  void setLayout(HidInputLayout layout);
  // Decodes one report (report ID byte first when the layout uses IDs); nullopt when it carries no sample.
  std::optional<Sample> decode(std::span<const uint8_t> report, int64_t arrivalTimeNs = 0);
  // Forgets sequence and time tracking (after a reconnect); keeps stats.
  void reset();
  const HidInputLayout& layout() const { return layout_; }
  const HidDecoderStats& stats() const { return stats_; }

 private:
  HidInputLayout layout_;
  HidDecoderStats stats_;
  bool haveSequence_ = false;
  uint32_t lastSequenceRaw_ = 0, sequence_ = 0;
  bool haveTime_ = false;
  uint32_t lastTimeRaw_ = 0;
  uint64_t timeUs_ = 0;
  uint32_t ownSequence_ = 0;
};

// ---- Device side ---------------------------------------------------------------------------------------------

// The input report for `sample` (device side: tests, the simulator, firmware reference). Counts are written as
// their low bitSize bits; a NotConnected channel on a Null State field is written as all ones. The sequence
// and device-time fields (when the layout has them) get sample.sequence and deviceTimeNs / 1000, truncated to
// their size. Error (a diagnostic without a position) when sample.channelCount differs from the layout's channel
// count.
std::expected<std::vector<uint8_t>, Diagnostics> encodeHidInputReport(const HidInputLayout& layout,
                                                                      const Sample& sample);

// The report descriptor of an IMPS HID armature (docs/protocol.md): an Application collection (IMPS page,
// Armature usage) with input report `reportId` holding an optional 16-bit sequence, an optional 32-bit device
// time in µs, and `channels` channels of `bits` bits with Logical 0..2^bits−2 and Null State (all ones = not
// connected), padded to a byte; plus, when infoReportSize > 0, feature report `reportId + 1` of that many data
// bytes for the INFO frame. channels 1..64, bits 2..32 (clamped).
struct HidArmatureDescriptorOptions {
  int channels = 32;
  int bits = 12;
  uint8_t reportId = 1;  // 0: no report IDs (then there is no info feature report)
  bool sequence = true;
  bool deviceTime = false;
  uint16_t infoReportSize = 255;
};
std::vector<uint8_t> hidArmatureDescriptor(const HidArmatureDescriptorOptions& options);

// The INFO feature report for `info` (ID byte first when `reportId` != 0), zero-padded to `dataSize` data bytes.
// Error (a diagnostic without a position) when the INFO frame does not fit or `info` cannot be encoded.
std::expected<std::vector<uint8_t>, Diagnostics> hidInfoReport(const DeviceInfo& info, uint8_t reportId,
                                                               size_t dataSize);

}  // namespace imps::drivers
