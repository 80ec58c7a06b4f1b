// SPDX-License-Identifier: MIT
// Recorded session files: writer, reader with recovery, replay. The byte layout is specified in
// docs/session-format.md; the constants below are the only other place it lives.
#include "sim/session_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <thread>
#include <utility>

#include "imps/atomic_file.h"
#include "imps/file_read.h"

namespace imps::sim {

namespace {

constexpr std::array<char, 8> kMagic = {'I', 'M', 'P', 'S', 'S', 'E', 'S', 'S'};
constexpr uint16_t kFormatVersion = 1;
constexpr size_t kFileHeaderBytes = 16;
constexpr size_t kRecordHeaderBytes = 12;
constexpr uint32_t kMaxPayloadBytes = kMaxRecordPayloadBytes;  // larger lengths are treated as corruption
constexpr size_t kMaxSessionFileBytes = size_t{1} << 30;  // readSession refuses larger (or endless) inputs

enum RecordType : uint16_t {
  kDeviceInfo = 1,
  kCalibration = 2,
  kSample = 3,
  kSkeleton = 4,
  kMarker = 5,
  kNote = 6,
  kEnd = 7,
  kLayout = 8,
  kCounters = 9,
};

// SAMPLE encoding byte.
constexpr uint8_t kCounts32 = 1;      // counts stored as uint32 (else uint16)
constexpr uint8_t kFlagsPresent = 2;  // one flag byte per channel follows the counts (else all Valid)
constexpr size_t kSampleFixedBytes = 26;

// ---- CRC-32C, slicing-by-1 table (the records are small; this is not on a per-sample hot path of the app).
constexpr std::array<uint32_t, 256> makeCrcTable() {
  std::array<uint32_t, 256> table{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? (c >> 1) ^ 0x82F63B78u : c >> 1;
    table[i] = c;
  }
  return table;
}
constexpr std::array<uint32_t, 256> kCrcTable = makeCrcTable();

// ---- Little-endian encoding.
void putU8(std::vector<uint8_t>& out, uint8_t v) { out.push_back(v); }
void putU16(std::vector<uint8_t>& out, uint16_t v) {
  out.push_back(static_cast<uint8_t>(v));
  out.push_back(static_cast<uint8_t>(v >> 8));
}
void putU32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
void putU64(std::vector<uint8_t>& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
void putI64(std::vector<uint8_t>& out, int64_t v) { putU64(out, static_cast<uint64_t>(v)); }
void putBytes(std::vector<uint8_t>& out, std::string_view s) { out.insert(out.end(), s.begin(), s.end()); }
void putString(std::vector<uint8_t>& out, std::string_view s) {
  putU32(out, static_cast<uint32_t>(s.size()));
  putBytes(out, s);
}

// Bounds-checked little-endian decoding of one payload; any read past the end sets failed_.
class ByteReader {
 public:
  explicit ByteReader(std::span<const uint8_t> bytes) : bytes_(bytes) {}
  bool ok() const { return !failed_; }
  size_t remaining() const { return bytes_.size() - pos_; }
  uint64_t readLe(int n) {
    if (failed_ || remaining() < static_cast<size_t>(n)) {
      failed_ = true;
      return 0;
    }
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= static_cast<uint64_t>(bytes_[pos_ + static_cast<size_t>(i)]) << (8 * i);
    pos_ += static_cast<size_t>(n);
    return v;
  }
  uint8_t u8() { return static_cast<uint8_t>(readLe(1)); }
  uint16_t u16() { return static_cast<uint16_t>(readLe(2)); }
  uint32_t u32() { return static_cast<uint32_t>(readLe(4)); }
  int64_t i64() { return static_cast<int64_t>(readLe(8)); }
  uint64_t u64() { return readLe(8); }
  std::string bytes(size_t n) {
    if (failed_ || remaining() < n) {
      failed_ = true;
      return {};
    }
    std::string s(reinterpret_cast<const char*>(bytes_.data() + pos_), n);
    pos_ += n;
    return s;
  }
  std::string string() { return bytes(u32()); }
  std::string rest() { return bytes(remaining()); }

 private:
  std::span<const uint8_t> bytes_;
  size_t pos_ = 0;
  bool failed_ = false;
};

std::string errnoText(int err) { return std::strerror(err); }

// Checks a DeviceInfo against what the format can store; "" when fine.
std::string checkDevice(const DeviceInfo& d) {
  if (d.channelCount < 1 || d.channelCount > drivers::kMaxChannels)
    return "device '" + d.name + "' has " + std::to_string(d.channelCount) + " channels; expected 1.." +
           std::to_string(drivers::kMaxChannels);
  if (d.bitsPerChannel < 1 || d.bitsPerChannel > 32)
    return "device '" + d.name + "' has " + std::to_string(d.bitsPerChannel) + " bits per channel; expected 1..32";
  if (d.channelNames.size() > 0xFFFF) return "device '" + d.name + "' has too many channel names";
  return {};
}

void encodeDevice(std::vector<uint8_t>& out, uint16_t index, const DeviceInfo& d) {
  putU16(out, index);
  putString(out, d.name);
  putString(out, d.serialNumber);
  putString(out, d.firmwareVersion);
  putU16(out, static_cast<uint16_t>(d.channelCount));
  putU8(out, static_cast<uint8_t>(d.bitsPerChannel));
  putU8(out, d.hasDeviceTimestamp ? 1 : 0);
  putU16(out, static_cast<uint16_t>(d.channelNames.size()));
  for (const auto& n : d.channelNames) putString(out, n);
}

void encodeSample(std::vector<uint8_t>& out, uint16_t device, const Sample& s) {
  const size_t n = s.channelCount;
  bool wide = false, flagged = false;
  for (size_t i = 0; i < n; ++i) {
    wide |= s.counts[i] > 0xFFFF;
    flagged |= s.flags[i] != drivers::ChannelFlag::Valid;
  }
  putU16(out, device);
  putU16(out, s.channelCount);
  putU8(out, static_cast<uint8_t>((wide ? kCounts32 : 0) | (flagged ? kFlagsPresent : 0)));
  putU8(out, 0);
  putU32(out, s.sequence);
  putI64(out, s.deviceTimeNs);
  putI64(out, s.arrivalTimeNs);
  for (size_t i = 0; i < n; ++i) {
    if (wide)
      putU32(out, s.counts[i]);
    else
      putU16(out, static_cast<uint16_t>(s.counts[i]));
  }
  if (flagged)
    for (size_t i = 0; i < n; ++i) putU8(out, static_cast<uint8_t>(s.flags[i]));
}

}  // namespace

uint32_t crc32c(std::span<const uint8_t> bytes, uint32_t crc) {
  crc = ~crc;
  for (uint8_t b : bytes) crc = kCrcTable[(crc ^ b) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

// ---------------------------------------------------------------------------------------------------------------
// Writer

std::expected<SessionWriter, Diagnostics> SessionWriter::create(const std::filesystem::path& path,
                                                                const DeviceInfo& device,
                                                                SessionWriterOptions options) {
  return create(path, std::span<const DeviceInfo>(&device, 1), options);
}

std::expected<SessionWriter, Diagnostics> SessionWriter::create(const std::filesystem::path& path,
                                                                std::span<const DeviceInfo> devices,
                                                                SessionWriterOptions options) {
  const std::string name = path.string();
  if (devices.empty()) return std::unexpected(singleError({name}, "a session needs at least one device"));
  if (devices.size() > 0xFFFF) return std::unexpected(singleError({name}, "too many devices"));
  for (const auto& d : devices)
    if (auto problem = checkDevice(d); !problem.empty()) return std::unexpected(singleError({name}, problem));

  SessionWriter w;
  w.path_ = path;
  w.options_ = options;
  w.devices_.assign(devices.begin(), devices.end());
  // O_EXCL: a recording never clobbers an earlier one.
  w.fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);  // less the umask, as fopen
  if (w.fd_ < 0) return std::unexpected(singleError({name}, "cannot create session file: " + errnoText(errno)));

  w.buffer_.insert(w.buffer_.end(), kMagic.begin(), kMagic.end());
  putU16(w.buffer_, kFormatVersion);
  putU16(w.buffer_, static_cast<uint16_t>(kFileHeaderBytes));
  putU32(w.buffer_, 0);  // flags: none defined in version 1
  for (size_t i = 0; i < w.devices_.size(); ++i) {
    w.scratch_.clear();
    encodeDevice(w.scratch_, static_cast<uint16_t>(i), w.devices_[i]);
    if (auto r = w.appendRecord(kDeviceInfo, w.scratch_); !r) return std::unexpected(r.error());
  }
  if (auto r = w.flush(); !r) return std::unexpected(r.error());
  return w;
}

SessionWriter::SessionWriter(SessionWriter&& other) noexcept { *this = std::move(other); }

SessionWriter& SessionWriter::operator=(SessionWriter&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) (void)close();
    path_ = std::move(other.path_);
    fd_ = std::exchange(other.fd_, -1);
    options_ = other.options_;
    devices_ = std::move(other.devices_);
    buffer_ = std::move(other.buffer_);
    scratch_ = std::move(other.scratch_);
    bufferedSamples_ = other.bufferedSamples_;
    samples_ = other.samples_;
    flushed_ = other.flushed_;
    lastFlushNs_ = other.lastFlushNs_;
    closed_ = std::exchange(other.closed_, true);
  }
  return *this;
}

SessionWriter::~SessionWriter() {
  if (fd_ >= 0) (void)close();
}

Clock& SessionWriter::clock() const {
  static SteadyClock steady;
  return options_.clock ? *options_.clock : steady;
}

std::expected<void, Diagnostics> SessionWriter::usable() const {
  if (fd_ < 0 || closed_) return std::unexpected(singleError({path_.string()}, "session writer is closed"));
  return {};
}

std::expected<void, Diagnostics> SessionWriter::appendRecord(uint16_t type, std::span<const uint8_t> payload) {
  if (payload.size() > kMaxPayloadBytes)
    return std::unexpected(singleError({path_.string()}, "record of " + std::to_string(payload.size()) +
                                                             " bytes exceeds the format's limit of " +
                                                             std::to_string(kMaxPayloadBytes)));
  const size_t start = buffer_.size();
  putU16(buffer_, type);
  putU16(buffer_, 0);
  putU32(buffer_, static_cast<uint32_t>(payload.size()));
  uint32_t crc = crc32c(std::span<const uint8_t>(buffer_.data() + start, 8));
  crc = crc32c(payload, crc);
  putU32(buffer_, crc);
  buffer_.insert(buffer_.end(), payload.begin(), payload.end());
  return {};
}

std::expected<void, Diagnostics> SessionWriter::append(const Sample& sample, uint16_t device) {
  if (auto r = usable(); !r) return r;
  if (device >= devices_.size())
    return std::unexpected(singleError({path_.string()}, "sample for device " + std::to_string(device) + " but only " +
                                                             std::to_string(devices_.size()) + " devices"));
  if (sample.channelCount != devices_[device].channelCount)
    return std::unexpected(singleError({path_.string()}, "sample has " + std::to_string(sample.channelCount) +
                                                             " channels but device " + std::to_string(device) +
                                                             " has " + std::to_string(devices_[device].channelCount)));
  scratch_.clear();
  encodeSample(scratch_, device, sample);
  if (auto r = appendRecord(kSample, scratch_); !r) return r;
  ++samples_;
  ++bufferedSamples_;
  bool due = options_.flushEverySamples > 0 && bufferedSamples_ >= options_.flushEverySamples;
  if (!due && options_.flushEveryNs > 0) due = clock().nowNs() - lastFlushNs_ >= options_.flushEveryNs;
  if (due) return flush();
  return {};
}

std::expected<void, Diagnostics> SessionWriter::appendCalibration(std::string_view json) {
  if (auto r = usable(); !r) return r;
  return appendRecord(kCalibration, std::span(reinterpret_cast<const uint8_t*>(json.data()), json.size()));
}

std::expected<void, Diagnostics> SessionWriter::appendMarker(int64_t timeNs, std::string_view label) {
  if (auto r = usable(); !r) return r;
  scratch_.clear();
  putI64(scratch_, timeNs);
  putBytes(scratch_, label);
  return appendRecord(kMarker, scratch_);
}

std::expected<void, Diagnostics> SessionWriter::appendNote(std::string_view text) {
  if (auto r = usable(); !r) return r;
  return appendRecord(kNote, std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
}

std::expected<uint16_t, Diagnostics> SessionWriter::appendLayoutChange(const DeviceInfo& device, uint16_t previous) {
  if (auto r = usable(); !r) return std::unexpected(r.error());
  if (auto problem = checkDevice(device); !problem.empty())
    return std::unexpected(singleError({path_.string()}, problem));
  if (previous >= devices_.size() || devices_.size() >= 0xFFFF)
    return std::unexpected(singleError({path_.string()}, "layout change of device " + std::to_string(previous) +
                                                             " but there are " + std::to_string(devices_.size()) +
                                                             " devices"));
  const auto index = static_cast<uint16_t>(devices_.size());
  scratch_.clear();
  encodeDevice(scratch_, index, device);
  if (auto r = appendRecord(kDeviceInfo, scratch_); !r) return std::unexpected(r.error());
  scratch_.clear();
  putU16(scratch_, index);
  putU16(scratch_, previous);
  if (auto r = appendRecord(kLayout, scratch_); !r) return std::unexpected(r.error());
  devices_.push_back(device);
  return index;
}

std::expected<void, Diagnostics> SessionWriter::appendLayout(uint16_t device, uint16_t previous) {
  if (auto r = usable(); !r) return r;
  if (device >= devices_.size() || previous >= device)
    return std::unexpected(singleError({path_.string()}, "layout change of device " + std::to_string(previous) +
                                                             " to device " + std::to_string(device)));
  scratch_.clear();
  putU16(scratch_, device);
  putU16(scratch_, previous);
  return appendRecord(kLayout, scratch_);
}

std::expected<void, Diagnostics> SessionWriter::appendCounters(uint16_t device,
                                                               std::span<const SessionCounter> counters) {
  if (auto r = usable(); !r) return r;
  if (device >= devices_.size() || counters.size() > 0xFFFF)
    return std::unexpected(singleError(
        {path_.string()}, "counters for device " + std::to_string(device) + " of " + std::to_string(devices_.size())));
  scratch_.clear();
  putU16(scratch_, device);
  putU16(scratch_, static_cast<uint16_t>(counters.size()));
  for (const SessionCounter& c : counters) {
    putString(scratch_, c.name);
    putU64(scratch_, c.value);
  }
  return appendRecord(kCounters, scratch_);
}

std::expected<void, Diagnostics> SessionWriter::appendSkeleton(const SessionSkeleton& skeleton) {
  if (auto r = usable(); !r) return r;
  scratch_.clear();
  putU64(scratch_, std::bit_cast<uint64_t>(skeleton.positionUnitsPerCount));
  putBytes(scratch_, skeleton.bvh);
  return appendRecord(kSkeleton, scratch_);
}

std::expected<void, Diagnostics> SessionWriter::writeAll(std::span<const uint8_t> bytes) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      // Drop a partly written record so a later flush appends after whole records only.
      if (::ftruncate(fd_, static_cast<off_t>(flushed_)) == 0) (void)::lseek(fd_, 0, SEEK_END);
      return std::unexpected(singleError(
          {path_.string()}, "write failed at byte " + std::to_string(flushed_ + done) + ": " + errnoText(err)));
    }
    done += static_cast<size_t>(n);
  }
  return {};
}

std::expected<void, Diagnostics> SessionWriter::flush() {
  if (auto r = usable(); !r) return r;
  lastFlushNs_ = clock().nowNs();
  if (buffer_.empty()) return {};
  if (auto r = writeAll(buffer_); !r) return r;
  flushed_ += buffer_.size();
  buffer_.clear();
  bufferedSamples_ = 0;
  if (options_.syncOnFlush && ::fdatasync(fd_) != 0)
    return std::unexpected(singleError({path_.string()}, "fdatasync failed: " + errnoText(errno)));
  return {};
}

std::expected<void, Diagnostics> SessionWriter::close() {
  if (auto r = usable(); !r) return r;
  scratch_.clear();
  putU64(scratch_, samples_);
  auto result = appendRecord(kEnd, scratch_);
  if (result) result = flush();
  if (result && ::fsync(fd_) != 0)
    result = std::unexpected(singleError({path_.string()}, "fsync failed: " + errnoText(errno)));
  if (::close(fd_) != 0 && result)
    result = std::unexpected(singleError({path_.string()}, "close failed: " + errnoText(errno)));
  fd_ = -1;
  closed_ = true;
  return result;
}

// ---------------------------------------------------------------------------------------------------------------
// Reader

std::expected<Session, Diagnostics> readSession(const std::filesystem::path& path) {
  // The magic first: a file that is not a session (/dev/zero, a picture) is refused without reading it whole.
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::unexpected(singleError({path.string()}, "cannot open session file: " + errnoText(errno)));
  std::array<char, kFileHeaderBytes> header{};
  in.read(header.data(), header.size());
  if (in.gcount() == static_cast<std::streamsize>(header.size()) &&
      !std::equal(kMagic.begin(), kMagic.end(), header.begin()))
    return readSessionBytes(std::span(reinterpret_cast<const uint8_t*>(header.data()), header.size()), path.string());
  auto text = readFileText(path, kMaxSessionFileBytes);
  if (!text) return std::unexpected(singleError({path.string()}, "cannot read session file: " + text.error().message));
  return readSessionBytes(std::span(reinterpret_cast<const uint8_t*>(text->data()), text->size()), path.string());
}

std::expected<Session, Diagnostics> readSessionBytes(std::span<const uint8_t> bytes, std::string_view name) {
  const std::string file(name);
  if (bytes.size() < kFileHeaderBytes)
    return std::unexpected(singleError(
        {file}, "not a session file: " + std::to_string(bytes.size()) + " bytes, shorter than the 16-byte header"));
  if (!std::equal(kMagic.begin(), kMagic.end(), bytes.begin()))
    return std::unexpected(singleError({file}, "not a session file: bad magic at byte 0 (expected \"IMPSSESS\")"));
  ByteReader header(bytes.subspan(8, 8));
  Session s;
  s.formatVersion = header.u16();
  const uint16_t headerBytes = header.u16();
  if (s.formatVersion == 0 || s.formatVersion > kFormatVersion)
    return std::unexpected(singleError({file}, "session format version " + std::to_string(s.formatVersion) +
                                                   " is not supported (this reader knows versions 1.." +
                                                   std::to_string(kFormatVersion) + ")"));
  if (headerBytes < kFileHeaderBytes || headerBytes > bytes.size())
    return std::unexpected(singleError({file}, "bad header size " + std::to_string(headerBytes) + " at byte 10"));

  SessionRecovery& rec = s.recovery;
  rec.fileBytes = bytes.size();
  size_t pos = headerBytes;
  rec.bytesUsed = pos;
  auto stop = [&](bool truncated, const std::string& what) {
    rec.truncated = truncated;
    rec.corrupt = !truncated;
    rec.message = file + ": warning: " + what;
  };

  while (pos < bytes.size()) {
    const size_t recordStart = pos;
    const std::string at = " at byte " + std::to_string(recordStart);
    if (bytes.size() - pos < kRecordHeaderBytes) {
      stop(true, "truncated record header" + at + " (" + std::to_string(bytes.size() - pos) + " of " +
                     std::to_string(kRecordHeaderBytes) + " bytes)");
      break;
    }
    ByteReader rh(bytes.subspan(pos, kRecordHeaderBytes));
    const uint16_t type = rh.u16();
    (void)rh.u16();  // record flags: none defined in version 1
    const uint32_t length = rh.u32();
    const uint32_t storedCrc = rh.u32();
    if (length > kMaxPayloadBytes) {
      stop(false, "corrupt record" + at + ": payload length " + std::to_string(length) + " exceeds the limit");
      break;
    }
    if (bytes.size() - pos - kRecordHeaderBytes < length) {
      stop(true, "truncated record" + at + " (type " + std::to_string(type) + ", payload " + std::to_string(length) +
                     " bytes, " + std::to_string(bytes.size() - pos - kRecordHeaderBytes) + " present)");
      break;
    }
    const auto payload = bytes.subspan(pos + kRecordHeaderBytes, length);
    const uint32_t crc = crc32c(payload, crc32c(bytes.subspan(pos, 8)));
    if (crc != storedCrc) {
      stop(false, "corrupt record" + at + ": CRC mismatch (type " + std::to_string(type) + ", length " +
                      std::to_string(length) + ")");
      break;
    }

    // The record is whole and intact; decode it. Invalid contents also end the read.
    ByteReader r(payload);
    std::string invalid;
    bool end = false;
    switch (type) {
      case kDeviceInfo: {
        const uint16_t index = r.u16();
        DeviceInfo d;
        d.name = r.string();
        d.serialNumber = r.string();
        d.firmwareVersion = r.string();
        d.channelCount = r.u16();
        d.bitsPerChannel = r.u8();
        const uint8_t hasTime = r.u8();
        const uint16_t names = r.u16();
        for (uint16_t i = 0; i < names && r.ok(); ++i) d.channelNames.push_back(r.string());
        d.hasDeviceTimestamp = hasTime != 0;
        if (!r.ok() || r.remaining() != 0)
          invalid = "DEVICE_INFO payload does not match its length";
        else if (index != s.devices.size())
          invalid = "DEVICE_INFO for device " + std::to_string(index) + ", expected device " +
                    std::to_string(s.devices.size());
        else if (hasTime > 1)
          invalid = "DEVICE_INFO has a bad hasDeviceTimestamp byte";
        else if (auto problem = checkDevice(d); !problem.empty())
          invalid = problem;
        else
          s.devices.push_back(std::move(d));
        break;
      }
      case kSample: {
        const uint16_t device = r.u16();
        const uint16_t channels = r.u16();
        const uint8_t encoding = r.u8();
        const uint8_t reserved = r.u8();
        Sample sample;
        sample.sequence = r.u32();
        sample.deviceTimeNs = r.i64();
        sample.arrivalTimeNs = r.i64();
        sample.channelCount = channels;
        const size_t width = (encoding & kCounts32) ? 4 : 2;
        const size_t expected =
            kSampleFixedBytes + channels * width + ((encoding & kFlagsPresent) ? channels : size_t{0});
        if (!r.ok() || payload.size() != expected)
          invalid = "SAMPLE payload of " + std::to_string(payload.size()) + " bytes, expected " +
                    std::to_string(expected);
        else if ((encoding & ~(kCounts32 | kFlagsPresent)) != 0 || reserved != 0)
          invalid = "SAMPLE has unknown encoding bits";
        else if (device >= s.devices.size())
          invalid = "SAMPLE for device " + std::to_string(device) + " which has no DEVICE_INFO";
        else if (channels != s.devices[device].channelCount)
          invalid = "SAMPLE has " + std::to_string(channels) + " channels, device " + std::to_string(device) +
                    " has " + std::to_string(s.devices[device].channelCount);
        if (!invalid.empty()) break;
        for (size_t i = 0; i < channels; ++i)
          sample.counts[i] = static_cast<uint32_t>(r.readLe(static_cast<int>(width)));
        if (encoding & kFlagsPresent) {
          for (size_t i = 0; i < channels && invalid.empty(); ++i) {
            const uint8_t f = r.u8();
            if (f > static_cast<uint8_t>(drivers::ChannelFlag::Outlier))
              invalid = "SAMPLE channel " + std::to_string(i) + " has unknown flag " + std::to_string(f);
            sample.flags[i] = static_cast<drivers::ChannelFlag>(f);
          }
        }
        if (!invalid.empty()) break;
        s.samples.push_back(sample);
        s.sampleDevice.push_back(device);
        break;
      }
      case kCalibration:
        s.calibrations.push_back({s.samples.size(), r.rest()});
        break;
      case kMarker: {
        SessionMarker m;
        m.firstSample = s.samples.size();
        m.timeNs = r.i64();
        m.label = r.rest();
        if (!r.ok())
          invalid = "MARKER payload shorter than 8 bytes";
        else
          s.markers.push_back(std::move(m));
        break;
      }
      case kNote:
        s.notes.push_back(r.rest());
        break;
      case kSkeleton: {
        SessionSkeleton k;
        k.positionUnitsPerCount = std::bit_cast<double>(r.u64());
        k.bvh = r.rest();
        if (!r.ok())
          invalid = "SKELETON payload shorter than 8 bytes";
        else if (!std::isfinite(k.positionUnitsPerCount) || k.positionUnitsPerCount < 0)
          invalid = "SKELETON has a bad position scale";
        else
          s.skeleton = std::move(k);
        break;
      }
      case kLayout: {
        SessionLayoutChange change;
        change.device = r.u16();
        change.previous = r.u16();
        change.firstSample = s.samples.size();
        if (!r.ok() || r.remaining() != 0)
          invalid = "LAYOUT payload is not 4 bytes";
        else if (change.device >= s.devices.size() || change.previous >= change.device)
          invalid = "LAYOUT of device " + std::to_string(change.device) + " from device " +
                    std::to_string(change.previous) + " (" + std::to_string(s.devices.size()) + " devices declared)";
        else
          s.layoutChanges.push_back(change);
        break;
      }
      case kCounters: {
        SessionCounters counters;
        counters.device = r.u16();
        const uint16_t n = r.u16();
        for (uint16_t i = 0; i < n && r.ok(); ++i) {
          SessionCounter c;
          c.name = r.string();
          c.value = r.u64();
          counters.values.push_back(std::move(c));
        }
        if (!r.ok() || r.remaining() != 0)
          invalid = "COUNTERS payload does not match its length";
        else if (counters.device >= s.devices.size())
          invalid = "COUNTERS for device " + std::to_string(counters.device) + " which has no DEVICE_INFO";
        if (!invalid.empty()) break;
        std::erase_if(s.counters, [&](const SessionCounters& c) { return c.device == counters.device; });
        s.counters.push_back(std::move(counters));
        break;
      }
      case kEnd: {
        const uint64_t count = r.u64();
        if (!r.ok() || r.remaining() != 0)
          invalid = "END payload is not 8 bytes";
        else if (count != s.samples.size())
          invalid = "END says " + std::to_string(count) + " samples but " + std::to_string(s.samples.size()) +
                    " were read";
        else
          end = true;
        break;
      }
      default:
        ++rec.unknownRecords;  // a newer writer's record type: skip it (docs/session-format.md, versioning)
        break;
    }
    if (!invalid.empty()) {
      stop(false, "invalid record" + at + ": " + invalid);
      break;
    }
    pos += kRecordHeaderBytes + length;
    rec.bytesUsed = pos;
    ++rec.recordsRead;
    if (end) {
      rec.closedCleanly = true;
      if (pos < bytes.size())
        rec.message = file + ": warning: " + std::to_string(bytes.size() - pos) +
                      " bytes after the END record at byte " + std::to_string(recordStart) + " ignored";
      break;
    }
  }
  rec.bytesIgnored = rec.fileBytes - rec.bytesUsed;
  if (!rec.closedCleanly && rec.message.empty())
    rec.message = file + ": warning: no END record: the recording was not closed (" + std::to_string(s.samples.size()) +
                  " samples recovered)";
  s.samples.shrink_to_fit();
  s.sampleDevice.shrink_to_fit();
  return s;
}

std::expected<void, Diagnostics> saveSession(const std::filesystem::path& path, const Session& session) {
  if (session.samples.size() != session.sampleDevice.size())
    return std::unexpected(
        singleError({path.string()}, "session has " + std::to_string(session.samples.size()) + " samples but " +
                                         std::to_string(session.sampleDevice.size()) + " device indices"));
  const std::filesystem::path tmp = temporarySibling(path.string());  // created exclusively by the writer
  std::error_code ignored;
  SessionWriterOptions options;
  options.flushEverySamples = 4096;
  options.flushEveryNs = 0;
  auto result = [&]() -> std::expected<void, Diagnostics> {
    auto writer = SessionWriter::create(tmp, session.devices, options);
    if (!writer) return std::unexpected(writer.error());
    if (session.skeleton)
      if (auto r = writer->appendSkeleton(*session.skeleton); !r) return r;
    for (const auto& note : session.notes)
      if (auto r = writer->appendNote(note); !r) return r;
    size_t calibration = 0, marker = 0, layout = 0;
    for (size_t i = 0; i <= session.samples.size(); ++i) {
      for (; layout < session.layoutChanges.size() && session.layoutChanges[layout].firstSample <= i; ++layout)
        if (auto r = writer->appendLayout(session.layoutChanges[layout].device, session.layoutChanges[layout].previous);
            !r)
          return r;
      for (; calibration < session.calibrations.size() && session.calibrations[calibration].firstSample <= i;
           ++calibration)
        if (auto r = writer->appendCalibration(session.calibrations[calibration].json); !r) return r;
      for (; marker < session.markers.size() && session.markers[marker].firstSample <= i; ++marker)
        if (auto r = writer->appendMarker(session.markers[marker].timeNs, session.markers[marker].label); !r) return r;
      if (i < session.samples.size())
        if (auto r = writer->append(session.samples[i], session.sampleDevice[i]); !r) return r;
    }
    // Anything indexed past the last sample still belongs to the session.
    for (; layout < session.layoutChanges.size(); ++layout)
      if (auto r = writer->appendLayout(session.layoutChanges[layout].device, session.layoutChanges[layout].previous);
          !r)
        return r;
    for (; calibration < session.calibrations.size(); ++calibration)
      if (auto r = writer->appendCalibration(session.calibrations[calibration].json); !r) return r;
    for (; marker < session.markers.size(); ++marker)
      if (auto r = writer->appendMarker(session.markers[marker].timeNs, session.markers[marker].label); !r) return r;
    for (const SessionCounters& c : session.counters)
      if (auto r = writer->appendCounters(c.device, c.values); !r) return r;
    return writer->close();
  }();
  if (!result) {
    std::filesystem::remove(tmp, ignored);
    // The writer names the file it wrote; the user asked for `path`, and the temporary file is gone.
    auto named = [&](std::string text) {
      for (size_t at = text.find(tmp.string()); at != std::string::npos; at = text.find(tmp.string(), at))
        text.replace(at, tmp.string().size(), path.string());
      return text;
    };
    Diagnostics errors;
    for (const Diagnostic& d : result.error().all())
      errors.error(SourceLoc{named(d.loc.file), d.loc.line, d.loc.column}, named(d.message));
    return std::unexpected(std::move(errors));
  }
  if (auto committed = commitTemporaryFile(tmp.string(), path.string()); !committed)
    return std::unexpected(singleError({path.string()}, committed.error().message));
  return {};
}

// ---------------------------------------------------------------------------------------------------------------
// Replay

namespace {

constexpr int64_t kTimeMax = std::numeric_limits<int64_t>::max(), kTimeMin = std::numeric_limits<int64_t>::min();
int64_t saturatingSub(int64_t a, int64_t b) {
  int64_t r;
  return __builtin_sub_overflow(a, b, &r) ? (b < 0 ? kTimeMax : kTimeMin) : r;
}
int64_t saturatingAdd(int64_t a, int64_t b) {
  int64_t r;
  return __builtin_add_overflow(a, b, &r) ? (b > 0 ? kTimeMax : kTimeMin) : r;
}
int64_t saturatingRound(double ns) {
  if (!(ns < 0x1p63)) return kTimeMax;
  if (ns < -0x1p63) return kTimeMin;
  return static_cast<int64_t>(std::llround(ns));
}

}  // namespace

SessionReplay::SessionReplay(const Session& session, Clock& clock, ReplayOptions options)
    : session_(session), clock_(clock), options_(options) {}

void SessionReplay::seek(size_t index) { position_ = std::min(index, session_.samples.size()); }

int64_t SessionReplay::recordedTimeNs(size_t index) const {
  if (options_.timebase == ReplayOptions::Timebase::Device) {
    const uint16_t device = index < session_.sampleDevice.size() ? session_.sampleDevice[index] : 0;
    if (device < session_.devices.size() && session_.devices[device].hasDeviceTimestamp)
      return session_.samples.deviceTimeNs(index);
  }
  return session_.samples.arrivalTimeNs(index);
}

size_t SessionReplay::run(const std::function<bool(uint16_t, const Sample&)>& consume) {
  struct Adapter final : SampleConsumer {
    const std::function<bool(uint16_t, const Sample&)>& f;
    explicit Adapter(const std::function<bool(uint16_t, const Sample&)>& fn) : f(fn) {}
    bool consume(uint16_t device, const Sample& sample) override { return f(device, sample); }
  } adapter(consume);
  return run(adapter);
}

size_t SessionReplay::run(SampleConsumer& consumer) {
  const size_t n = session_.samples.size();
  size_t delivered = 0;
  if (position_ < n) {
    const int64_t startNs = clock_.nowNs();
    const int64_t firstRecordedNs = recordedTimeNs(position_);
    const bool paced = options_.speed > 0;
    const int64_t maxSleep = std::max<int64_t>(options_.maxSleepNs, 1);
    Sample out;
    while (position_ < n && !stopRequested_.load(std::memory_order_relaxed)) {
      const size_t p = position_;
      if (paced) {
        // Recorded timestamps are whatever the file holds: the schedule saturates instead of overflowing.
        const int64_t recorded = saturatingSub(recordedTimeNs(p), firstRecordedNs);
        const int64_t offset = options_.speed == 1.0 ? recorded : saturatingRound(double(recorded) / options_.speed);
        const int64_t due = saturatingAdd(startNs, offset);
        for (int64_t now = clock_.nowNs(); now < due; now = clock_.nowNs()) {
          if (stopRequested_.load(std::memory_order_relaxed)) break;
          clock_.sleepUntilNs(std::min(due, saturatingAdd(now, maxSleep)));
        }
        if (stopRequested_.load(std::memory_order_relaxed)) break;
      }
      const uint16_t device = p < session_.sampleDevice.size() ? session_.sampleDevice[p] : 0;
      out = session_.samples[p];
      if (options_.rewriteArrivalTime) out.arrivalTimeNs = clock_.nowNs();
      position_ = p + 1;
      ++delivered;
      if (!consumer.consume(device, out)) break;
    }
  }
  stopRequested_.store(false, std::memory_order_relaxed);
  return delivered;
}

}  // namespace imps::sim
