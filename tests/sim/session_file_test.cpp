// SPDX-License-Identifier: MIT
// Tests for sim/session_file: bit-exact write/read, crash recovery at every byte, corruption, replay timing.
#include "sim/session_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <tuple>

namespace imps::sim {
namespace {

namespace fs = std::filesystem;
using drivers::ChannelFlag;

// A fresh, empty directory per test.
fs::path tempDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path dir = fs::temp_directory_path() / ("imps_session_test_" + std::to_string(::getpid()) + "_" +
                                              info->test_suite_name() + "_" + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<uint8_t> fileBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

DeviceInfo device(int channels, int bits, const std::string& name = "IMPS Monkey-test") {
  DeviceInfo d;
  d.name = name;
  d.serialNumber = "SN-0042";
  d.firmwareVersion = "1.2.3";
  d.channelCount = channels;
  d.bitsPerChannel = bits;
  for (int i = 0; i < channels; ++i) d.channelNames.push_back("joint" + std::to_string(i) + ":Zrotation");
  d.hasDeviceTimestamp = true;
  return d;
}

Sample randomSample(std::mt19937_64& rng, int channels, uint32_t maxCount, bool flags) {
  Sample s;
  s.sequence = static_cast<uint32_t>(rng());
  s.deviceTimeNs = static_cast<int64_t>(rng());  // any bit pattern, negative included
  s.arrivalTimeNs = static_cast<int64_t>(rng() >> 1);
  s.channelCount = static_cast<uint16_t>(channels);
  for (int i = 0; i < channels; ++i) {
    s.counts[static_cast<size_t>(i)] = static_cast<uint32_t>(rng() % (uint64_t{maxCount} + 1));
    if (flags && rng() % 5 == 0) s.flags[static_cast<size_t>(i)] = static_cast<ChannelFlag>(1 + rng() % 2);
  }
  return s;
}

TEST(Crc32c, KnownValue) {
  const std::string text = "123456789";
  EXPECT_EQ(crc32c(std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size())), 0xE3069283u);
}

TEST(SessionFile, WriteThenReadIsBitExact) {
  const fs::path path = tempDir() / "take.session";
  const std::vector<DeviceInfo> devices = {device(24, 12), device(64, 32, "wide")};
  std::mt19937_64 rng(1234);
  std::vector<Sample> written;
  std::vector<uint16_t> writtenDevice;
  {
    SessionWriterOptions options;
    options.flushEverySamples = 97;
    options.flushEveryNs = 0;
    auto writer = SessionWriter::create(path, devices, options);
    ASSERT_TRUE(writer) << writer.error().firstError();
    ASSERT_TRUE(writer->appendNote("performer: test"));
    ASSERT_TRUE(writer->appendCalibration(R"({"rig":"a","gains":[1,2]})"));
    for (int i = 0; i < 3000; ++i) {
      const uint16_t d = (i % 3 == 2) ? 1 : 0;
      // Device 0 stays within 16 bits (compact records); device 1 uses the full 32-bit range.
      Sample s = randomSample(rng, devices[d].channelCount, d == 0 ? 4095u : 0xFFFFFFFFu, i % 2 == 0);
      if (i == 1000) {
        ASSERT_TRUE(writer->appendCalibration("{\"rig\":\"b\"}"));
      }
      if (i == 1500) {
        ASSERT_TRUE(writer->appendMarker(123456789, "clap"));
      }
      ASSERT_TRUE(writer->append(s, d));
      written.push_back(s);
      writtenDevice.push_back(d);
    }
    ASSERT_TRUE(writer->close());
  }
  auto session = readSession(path);
  ASSERT_TRUE(session) << session.error().firstError();
  EXPECT_EQ(session->formatVersion, 1);
  EXPECT_EQ(session->devices, devices);
  ASSERT_EQ(session->samples.size(), written.size());
  for (size_t i = 0; i < written.size(); ++i) ASSERT_EQ(session->samples[i], written[i]) << "sample " << i;
  EXPECT_EQ(session->sampleDevice, writtenDevice);
  ASSERT_EQ(session->calibrations.size(), 2u);
  EXPECT_EQ(session->calibrations[0], (SessionCalibration{0, R"({"rig":"a","gains":[1,2]})"}));
  EXPECT_EQ(session->calibrations[1], (SessionCalibration{1000, "{\"rig\":\"b\"}"}));
  ASSERT_EQ(session->markers.size(), 1u);
  EXPECT_EQ(session->markers[0], (SessionMarker{1500, 123456789, "clap"}));
  EXPECT_EQ(session->notes, std::vector<std::string>{"performer: test"});
  EXPECT_TRUE(session->recovery.closedCleanly);
  EXPECT_FALSE(session->recovery.truncated);
  EXPECT_FALSE(session->recovery.corrupt);
  EXPECT_EQ(session->recovery.bytesIgnored, 0u);
  EXPECT_EQ(session->recovery.bytesUsed, fs::file_size(path));
  EXPECT_EQ(session->recovery.message, "");
}

TEST(SessionFile, SamplesWithin16BitsAreStoredCompactly) {
  const fs::path path = tempDir() / "compact.session";
  const DeviceInfo d = device(8, 12);
  {
    auto writer = SessionWriter::create(path, d);
    ASSERT_TRUE(writer);
    Sample s;
    s.channelCount = 8;
    for (int i = 0; i < 10; ++i) ASSERT_TRUE(writer->append(s));
    s.counts[3] = 70000;  // does not fit 16 bits: this one record uses 4 bytes per count
    ASSERT_TRUE(writer->append(s));
    s.counts[3] = 0;
    s.flags[2] = ChannelFlag::Outlier;  // flags present: one byte per channel more
    ASSERT_TRUE(writer->append(s));
  }
  const size_t header = 16, record = 12;
  size_t deviceInfo = 2 + (4 + d.name.size()) + (4 + d.serialNumber.size()) + (4 + d.firmwareVersion.size()) + 2 + 1 +
                      1 + 2;
  for (const auto& n : d.channelNames) deviceInfo += 4 + n.size();
  const size_t compact = record + 26 + 8 * 2;
  const size_t expected = header + record + deviceInfo + 10 * compact + (record + 26 + 8 * 4) +
                          (record + 26 + 8 * 2 + 8) + (record + 8);
  EXPECT_EQ(fs::file_size(path), expected);
  auto session = readSession(path);
  ASSERT_TRUE(session);
  ASSERT_EQ(session->samples.size(), 12u);
  EXPECT_EQ(session->samples[10].counts[3], 70000u);
  EXPECT_EQ(session->samples[11].flags[2], ChannelFlag::Outlier);
}

// A session cut at any byte reads back exactly the samples whose records were complete before the cut.
TEST(SessionFile, TruncationAtEveryByteRecoversWholeRecords) {
  const fs::path path = tempDir() / "cut.session";
  std::mt19937_64 rng(7);
  std::vector<Sample> written;
  std::vector<uint64_t> sampleEnds;  // file size after each sample's record
  uint64_t headerEnd = 0, calibrationEnd = 0;
  {
    SessionWriterOptions options;
    options.flushEverySamples = 1;
    auto writer = SessionWriter::create(path, device(5, 16), options);
    ASSERT_TRUE(writer);
    headerEnd = writer->bytesFlushed();
    ASSERT_TRUE(writer->appendCalibration("{}"));
    ASSERT_TRUE(writer->flush());
    calibrationEnd = writer->bytesFlushed();
    for (int i = 0; i < 12; ++i) {
      written.push_back(randomSample(rng, 5, i % 4 == 0 ? 0xFFFFFFFFu : 0xFFFFu, i % 3 == 0));
      ASSERT_TRUE(writer->append(written.back()));
      sampleEnds.push_back(writer->bytesFlushed());
    }
    ASSERT_TRUE(writer->close());
  }
  const std::vector<uint8_t> bytes = fileBytes(path);
  ASSERT_GT(bytes.size(), sampleEnds.back());
  for (size_t cut = 0; cut <= bytes.size(); ++cut) {
    SCOPED_TRACE("cut at " + std::to_string(cut));
    auto session = readSessionBytes(std::span(bytes.data(), cut), "cut.session");
    if (cut < 16) {
      ASSERT_FALSE(session);
      EXPECT_EQ(session.error().firstError(), "cut.session: error: not a session file: " + std::to_string(cut) +
                                                  " bytes, shorter than the 16-byte header");
      continue;
    }
    ASSERT_TRUE(session) << session.error().firstError();
    size_t whole = 0;
    while (whole < sampleEnds.size() && sampleEnds[whole] <= cut) ++whole;
    ASSERT_EQ(session->samples.size(), whole);
    for (size_t i = 0; i < whole; ++i) ASSERT_EQ(session->samples[i], written[i]);
    EXPECT_EQ(session->devices.size(), cut >= headerEnd ? 1u : 0u);
    EXPECT_EQ(session->calibrations.size(), cut >= calibrationEnd ? 1u : 0u);
    std::vector<uint64_t> boundaries = {16, headerEnd, calibrationEnd};
    boundaries.insert(boundaries.end(), sampleEnds.begin(), sampleEnds.end());
    boundaries.push_back(bytes.size());
    uint64_t lastBoundary = 0;
    for (uint64_t b : boundaries)
      if (b <= cut) lastBoundary = b;
    const bool atBoundary = lastBoundary == cut;
    EXPECT_EQ(session->recovery.truncated, !atBoundary);
    EXPECT_FALSE(session->recovery.corrupt);
    EXPECT_EQ(session->recovery.closedCleanly, cut == bytes.size());
    EXPECT_EQ(session->recovery.bytesUsed, lastBoundary);
    EXPECT_EQ(session->recovery.bytesIgnored, cut - lastBoundary);
    if (!atBoundary) {
      EXPECT_TRUE(session->recovery.message.starts_with("cut.session: warning: truncated record"))
          << session->recovery.message;
    }
  }
}

TEST(SessionFile, CorruptByteStopsAtLastGoodRecord) {
  const fs::path path = tempDir() / "corrupt.session";
  std::mt19937_64 rng(99);
  std::vector<Sample> written;
  std::vector<uint64_t> sampleEnds;
  {
    SessionWriterOptions options;
    options.flushEverySamples = 1;
    auto writer = SessionWriter::create(path, device(6, 12), options);
    ASSERT_TRUE(writer);
    for (int i = 0; i < 20; ++i) {
      written.push_back(randomSample(rng, 6, 4095, false));
      ASSERT_TRUE(writer->append(written.back()));
      sampleEnds.push_back(writer->bytesFlushed());
    }
  }
  const std::vector<uint8_t> original = fileBytes(path);
  // Flip one bit in the payload of sample 9, then in its length field, then in its type field.
  const uint64_t record9 = sampleEnds[8];
  for (uint64_t offset : {record9 + 12 + 10, record9 + 4, record9 + 0}) {
    SCOPED_TRACE("corrupt byte " + std::to_string(offset));
    std::vector<uint8_t> bytes = original;
    bytes[offset] ^= 0x10;
    auto session = readSessionBytes(bytes, "corrupt.session");
    ASSERT_TRUE(session) << session.error().firstError();
    ASSERT_EQ(session->samples.size(), 9u);
    for (size_t i = 0; i < 9; ++i) EXPECT_EQ(session->samples[i], written[i]);
    EXPECT_TRUE(session->recovery.corrupt);
    EXPECT_FALSE(session->recovery.closedCleanly);
    EXPECT_EQ(session->recovery.bytesUsed, record9);
    EXPECT_EQ(session->recovery.bytesIgnored, original.size() - record9);
    EXPECT_TRUE(session->recovery.message.starts_with("corrupt.session: warning: corrupt record at byte " +
                                                      std::to_string(record9) + ": CRC mismatch"))
        << session->recovery.message;
  }
}

TEST(SessionFile, CrashedWriterReadsBackToLastFlush) {
  const fs::path dir = tempDir();
  const fs::path path = dir / "crash.session";
  SessionWriterOptions options;
  options.flushEverySamples = 5;
  options.flushEveryNs = 0;
  auto writer = SessionWriter::create(path, device(3, 10), options);
  ASSERT_TRUE(writer);
  Sample s;
  s.channelCount = 3;
  for (uint32_t i = 0; i < 12; ++i) {
    s.sequence = i;
    ASSERT_TRUE(writer->append(s));
  }
  // The process "dies" now: copy what is on disk while the writer still holds 2 samples in memory.
  fs::copy_file(path, dir / "snapshot.session");
  auto session = readSession(dir / "snapshot.session");
  ASSERT_TRUE(session);
  ASSERT_EQ(session->samples.size(), 10u);
  EXPECT_EQ(session->samples.back().sequence, 9u);
  EXPECT_FALSE(session->recovery.closedCleanly);
  EXPECT_FALSE(session->recovery.truncated);
  EXPECT_EQ(session->recovery.message,
            (dir / "snapshot.session").string() +
                ": warning: no END record: the recording was not closed (10 samples recovered)");
  // Earlier bytes are never rewritten: the final file starts with the snapshot.
  ASSERT_TRUE(writer->close());
  const auto snapshot = fileBytes(dir / "snapshot.session");
  const auto final = fileBytes(path);
  ASSERT_GT(final.size(), snapshot.size());
  EXPECT_TRUE(std::equal(snapshot.begin(), snapshot.end(), final.begin()));
  EXPECT_FALSE(writer->append(s));  // closed
}

TEST(SessionFile, FlushesAfterTimeOnTheInjectedClock) {
  const fs::path path = tempDir() / "timed.session";
  ManualClock clock(1'000'000);
  SessionWriterOptions options;
  options.flushEverySamples = 0;
  options.flushEveryNs = 100'000'000;
  options.clock = &clock;
  auto writer = SessionWriter::create(path, device(2, 12), options);
  ASSERT_TRUE(writer);
  const uint64_t afterHeader = fs::file_size(path);
  Sample s;
  s.channelCount = 2;
  ASSERT_TRUE(writer->append(s));
  clock.advance(99'000'000);
  ASSERT_TRUE(writer->append(s));
  EXPECT_EQ(fs::file_size(path), afterHeader);  // 99 ms: still buffered
  clock.advance(1'000'000);
  ASSERT_TRUE(writer->append(s));
  EXPECT_EQ(fs::file_size(path), afterHeader + 3 * (12 + 26 + 4));
}

TEST(SessionFile, WriterRejectsBadUse) {
  const fs::path dir = tempDir();
  const fs::path path = dir / "exists.session";
  std::ofstream(path) << "keep me";
  auto clobber = SessionWriter::create(path, device(2, 12));
  ASSERT_FALSE(clobber);
  EXPECT_EQ(clobber.error().firstError(), path.string() + ": error: cannot create session file: File exists");
  EXPECT_EQ(fileBytes(path).size(), 7u);

  auto noChannels = SessionWriter::create(dir / "bad.session", device(0, 12, "empty"));
  ASSERT_FALSE(noChannels);
  EXPECT_EQ(noChannels.error().firstError(),
            (dir / "bad.session").string() + ": error: device 'empty' has 0 channels; expected 1..64");

  auto writer = SessionWriter::create(dir / "ok.session", device(2, 12));
  ASSERT_TRUE(writer);
  Sample s;
  s.channelCount = 3;
  auto wrong = writer->append(s);
  ASSERT_FALSE(wrong);
  EXPECT_EQ(wrong.error().firstError(),
            (dir / "ok.session").string() + ": error: sample has 3 channels but device 0 has 2");
  s.channelCount = 2;
  EXPECT_FALSE(writer->append(s, 1));
}

TEST(SessionFile, AnUnreadableFileIsOneDiagnosticAtTheFile) {
  // The reader fails two ways (the file cannot be opened, its bytes are not a session); callers treat both as a bad
  // input, so both are Diagnostics, the I/O failure located at the file with no line.
  const fs::path missing = tempDir() / "missing.session";
  auto gone = readSession(missing);
  ASSERT_FALSE(gone);
  ASSERT_EQ(gone.error().all().size(), 1u);
  const Diagnostic& d = gone.error().all().front();
  EXPECT_EQ(d.severity, Severity::Error);
  EXPECT_EQ(d.loc.file, missing.string());
  EXPECT_EQ(d.loc.line, 0);
  EXPECT_EQ(d.message, "cannot open session file: No such file or directory");
  EXPECT_EQ(gone.error().str(), missing.string() + ": error: " + d.message + "\n");
}

TEST(SessionFile, ReaderErrorsAndUnknownRecords) {
  std::vector<uint8_t> junk(32, 'x');
  auto bad = readSessionBytes(junk, "junk.bin");
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().firstError(),
            "junk.bin: error: not a session file: bad magic at byte 0 (expected \"IMPSSESS\")");

  const fs::path path = tempDir() / "v.session";
  {
    auto writer = SessionWriter::create(path, device(1, 8));
    ASSERT_TRUE(writer);
    Sample s;
    s.channelCount = 1;
    s.counts[0] = 200;
    ASSERT_TRUE(writer->append(s));
  }
  std::vector<uint8_t> bytes = fileBytes(path);
  std::vector<uint8_t> future = bytes;
  future[8] = 2;  // version 2
  auto newer = readSessionBytes(future, "v.session");
  ASSERT_FALSE(newer);
  EXPECT_EQ(newer.error().firstError(),
            "v.session: error: session format version 2 is not supported (this reader knows versions 1..1)");

  // A record type from a newer writer, inserted after the header, is skipped.
  std::vector<uint8_t> unknown = {99, 0, 0, 0, 3, 0, 0, 0, 0, 0, 0, 0, 'a', 'b', 'c'};
  uint32_t crc = crc32c(std::span(unknown.data(), 8));
  crc = crc32c(std::span(unknown.data() + 12, 3), crc);
  for (int i = 0; i < 4; ++i) unknown[static_cast<size_t>(8 + i)] = static_cast<uint8_t>(crc >> (8 * i));
  bytes.insert(bytes.begin() + 16, unknown.begin(), unknown.end());
  auto withUnknown = readSessionBytes(bytes, "v.session");
  ASSERT_TRUE(withUnknown);
  EXPECT_EQ(withUnknown->recovery.unknownRecords, 1u);
  ASSERT_EQ(withUnknown->samples.size(), 1u);
  EXPECT_EQ(withUnknown->samples[0].counts[0], 200u);
  EXPECT_TRUE(withUnknown->recovery.closedCleanly);
}

TEST(SessionFile, SaveSessionRoundTrips) {
  const fs::path dir = tempDir();
  Session s;
  s.devices = {device(4, 14)};
  std::mt19937_64 rng(5);
  for (int i = 0; i < 50; ++i) {
    s.samples.push_back(randomSample(rng, 4, 16383, true));
    s.sampleDevice.push_back(0);
  }
  s.calibrations = {{0, "{\"a\":1}"}, {20, "{\"a\":2}"}};
  s.markers = {{10, 5, "m1"}, {50, 6, "at end"}};
  s.notes = {"n"};
  s.skeleton = SessionSkeleton{"HIERARCHY\n...", 0.25};
  ASSERT_TRUE(saveSession(dir / "out.session", s));
  fs::permissions(dir / "out.session", fs::perms::owner_read | fs::perms::owner_write);
  ASSERT_TRUE(saveSession(dir / "out.session", s));  // replaces an existing file, keeping its permissions
  EXPECT_EQ(fs::status(dir / "out.session").permissions(), fs::perms::owner_read | fs::perms::owner_write);
  auto back = readSession(dir / "out.session");
  ASSERT_TRUE(back) << back.error().firstError();
  EXPECT_EQ(back->devices, s.devices);
  EXPECT_EQ(back->samples, s.samples);
  EXPECT_EQ(back->sampleDevice, s.sampleDevice);
  EXPECT_EQ(back->calibrations, s.calibrations);
  EXPECT_EQ(back->markers, s.markers);
  EXPECT_EQ(back->notes, s.notes);
  EXPECT_EQ(back->skeleton, s.skeleton);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);  // no temporary left
}

// Issue 14 items 1 and 4: a layout change mid-take (a new DEVICE_INFO plus LAYOUT) and the link's counters
// (COUNTERS, the last one per device wins) are written, read back and copied by saveSession.
TEST(SessionFile, LayoutChangesAndCountersRoundTrip) {
  const fs::path dir = tempDir();
  std::mt19937_64 rng(9);
  auto w = SessionWriter::create(dir / "take.session", device(4, 12));
  ASSERT_TRUE(w) << w.error().firstError();
  std::vector<Sample> four, six;
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(w->append(four.emplace_back(randomSample(rng, 4, 4095, false))));
  const std::vector<SessionCounter> early = {{"timeouts", 1}};
  ASSERT_TRUE(w->appendCounters(0, early));
  // Samples of the new layout are refused under the old device and accepted under the new one.
  const Sample wide = randomSample(rng, 6, 4095, false);
  EXPECT_FALSE(w->append(wide, 0));
  auto index = w->appendLayoutChange(device(6, 12, "IMPS Monkey-test, 6 channels"), 0);
  ASSERT_TRUE(index) << index.error().firstError();
  EXPECT_EQ(*index, 1u);
  EXPECT_FALSE(w->appendLayoutChange(device(2, 12), 7));  // no such device
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(w->append(six.emplace_back(randomSample(rng, 6, 4095, false)), 1));
  const std::vector<SessionCounter> last = {{"timeouts", 2}, {"samplesDropped", 500}, {"aNewerCounter", 7}};
  ASSERT_TRUE(w->appendCounters(0, last));
  ASSERT_TRUE(w->close());

  auto back = readSession(dir / "take.session");
  ASSERT_TRUE(back) << back.error().firstError();
  EXPECT_TRUE(back->recovery.closedCleanly);
  EXPECT_EQ(back->recovery.unknownRecords, 0u);
  ASSERT_EQ(back->devices.size(), 2u);
  EXPECT_EQ(back->devices[1].channelCount, 6);
  ASSERT_EQ(back->samples.size(), 8u);
  EXPECT_EQ(back->sampleDevice, (std::vector<uint16_t>{0, 0, 0, 0, 0, 1, 1, 1}));
  EXPECT_EQ(back->layoutChanges, (std::vector<SessionLayoutChange>{{1, 0, 5}}));
  ASSERT_EQ(back->counters.size(), 1u);
  EXPECT_EQ(back->counters[0].device, 0u);
  EXPECT_EQ(back->counters[0].values, last);

  ASSERT_TRUE(saveSession(dir / "copy.session", *back));
  auto copy = readSession(dir / "copy.session");
  ASSERT_TRUE(copy) << copy.error().firstError();
  EXPECT_EQ(copy->samples, back->samples);
  EXPECT_EQ(copy->layoutChanges, back->layoutChanges);
  EXPECT_EQ(copy->counters, back->counters);
}

// ---- Replay

Session replaySession() {
  Session s;
  s.devices = {device(3, 12)};
  std::mt19937_64 rng(11);
  int64_t t = 5'000'000'000;
  for (int i = 0; i < 40; ++i) {
    Sample sample = randomSample(rng, 3, 4095, i % 4 == 0);
    t += 10'000'000 + static_cast<int64_t>(rng() % 3'000'000);  // ~10 ms with jitter
    sample.arrivalTimeNs = t;
    sample.deviceTimeNs = 1'000 + i * 8'000'000;  // the device's own 8 ms tick
    s.samples.push_back(sample);
    s.sampleDevice.push_back(0);
  }
  return s;
}

struct Delivery {
  int64_t atNs;
  Sample sample;
};

std::vector<Delivery> replay(const Session& s, ReplayOptions options, ManualClock& clock) {
  SessionReplay player(s, clock, options);
  std::vector<Delivery> got;
  player.run([&](uint16_t device, const Sample& sample) {
    EXPECT_EQ(device, 0);
    got.push_back({clock.nowNs(), sample});
    return true;
  });
  EXPECT_EQ(player.position(), s.samples.size());
  return got;
}

TEST(SessionReplay, DeliversAtRecordedTimesScaled) {
  const Session s = replaySession();
  for (double speed : {1.0, 2.0, 0.5}) {
    SCOPED_TRACE("speed " + std::to_string(speed));
    ManualClock clock(777);
    ReplayOptions options;
    options.speed = speed;
    options.maxSleepNs = 1'000'000'000;
    const auto got = replay(s, options, clock);
    ASSERT_EQ(got.size(), s.samples.size());
    for (size_t i = 0; i < got.size(); ++i) {
      const int64_t recorded = s.samples[i].arrivalTimeNs - s.samples[0].arrivalTimeNs;
      const int64_t expected = 777 + static_cast<int64_t>(std::llround(static_cast<double>(recorded) / speed));
      EXPECT_EQ(got[i].atNs, expected) << i;
      EXPECT_EQ(got[i].sample, s.samples[i]) << i;  // bit-exact
    }
  }
}

TEST(SessionReplay, AsFastAsPossibleNeverSleeps) {
  const Session s = replaySession();
  ManualClock clock(50);
  ReplayOptions options;
  options.speed = 0;
  const auto got = replay(s, options, clock);
  ASSERT_EQ(got.size(), s.samples.size());
  EXPECT_TRUE(clock.sleeps().empty());
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].atNs, 50);
    EXPECT_EQ(got[i].sample, s.samples[i]);
  }
}

TEST(SessionReplay, DeviceTimebaseAndLongGapsInSteps) {
  const Session s = replaySession();
  ManualClock clock(0);
  ReplayOptions options;
  options.timebase = ReplayOptions::Timebase::Device;
  options.maxSleepNs = 3'000'000;  // each 8 ms gap is slept in 3 ms steps
  const auto got = replay(s, options, clock);
  for (size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i].atNs, static_cast<int64_t>(i) * 8'000'000);
  EXPECT_EQ(clock.sleeps().size(), 3 * (s.samples.size() - 1));
}

TEST(SessionReplay, ExtremeTimestampsSaturateTheScheduleInsteadOfOverflowing) {
  // Timestamps are whatever the file holds. A gap of more than 2^63 ns, or a due time past the clock's range, used
  // to overflow (undefined behaviour; in practice a negative due time, so the sample came at once). The schedule now
  // saturates: the sample is due at the end of time, and that is when a clock that can get there delivers it.
  constexpr int64_t kMax = std::numeric_limits<int64_t>::max(), kMin = std::numeric_limits<int64_t>::min();
  for (const auto& [first, second, start] :
       {std::tuple{int64_t{0}, kMax, int64_t{1'000'000'000'000'000'000}}, std::tuple{kMin, kMax, int64_t{0}},
        std::tuple{kMin, int64_t{0}, int64_t{5}}}) {
    Session s;
    s.devices = {device(1, 12)};
    for (int64_t t : {first, second}) {
      Sample x;
      x.channelCount = 1;
      x.arrivalTimeNs = t;
      s.samples.push_back(x);
      s.sampleDevice.push_back(0);
    }
    ManualClock clock(start);
    ReplayOptions options;
    options.maxSleepNs = kMax;
    const auto got = replay(s, options, clock);
    ASSERT_EQ(got.size(), 2u);
    EXPECT_EQ(got[0].atNs, start);
    EXPECT_EQ(got[1].atNs, kMax) << first << " then " << second << " from " << start;
    for (size_t i = 1; i < clock.sleeps().size(); ++i) EXPECT_GE(clock.sleeps()[i], clock.sleeps()[i - 1]);
  }
}

TEST(SessionReplay, RewritesArrivalTimeOnlyWhenAsked) {
  const Session s = replaySession();
  ManualClock clock(1'000);
  ReplayOptions options;
  options.rewriteArrivalTime = true;
  const auto got = replay(s, options, clock);
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].sample.arrivalTimeNs, got[i].atNs);
    Sample original = got[i].sample;
    original.arrivalTimeNs = s.samples[i].arrivalTimeNs;
    EXPECT_EQ(original, s.samples[i]);
  }
  EXPECT_EQ(s.samples[0].arrivalTimeNs, replaySession().samples[0].arrivalTimeNs);  // the session is untouched
}

TEST(SessionReplay, StopSeekAndResume) {
  const Session s = replaySession();
  ManualClock clock(0);
  SessionReplay player(s, clock);
  size_t seen = 0;
  EXPECT_EQ(player.run([&](uint16_t, const Sample&) { return ++seen < 5; }), 5u);
  EXPECT_EQ(player.position(), 5u);
  player.seek(30);
  const int64_t resumeAt = clock.nowNs();
  std::vector<Delivery> got;
  EXPECT_EQ(player.run([&](uint16_t, const Sample& x) {
    got.push_back({clock.nowNs(), x});
    return true;
  }),
            10u);
  ASSERT_EQ(got.size(), 10u);
  EXPECT_EQ(got[0].sample, s.samples[30]);
  EXPECT_EQ(got[0].atNs, resumeAt);  // the schedule restarts at the seek position
  EXPECT_EQ(got[9].atNs, resumeAt + s.samples[39].arrivalTimeNs - s.samples[30].arrivalTimeNs);

  struct Stopper final : SampleConsumer {
    SessionReplay* player = nullptr;
    size_t count = 0;
    bool consume(uint16_t, const Sample&) override {
      if (++count == 3) player->stop();
      return true;
    }
  } stopper;
  player.seek(0);
  stopper.player = &player;
  EXPECT_EQ(player.run(stopper), 3u);
  EXPECT_EQ(player.position(), 3u);
}

TEST(SessionReplay, SteadyClockKeepsRealTime) {
  Session s;
  s.devices = {device(1, 12)};
  for (int i = 0; i < 6; ++i) {
    Sample x;
    x.channelCount = 1;
    x.arrivalTimeNs = i * 4'000'000;
    s.samples.push_back(x);
    s.sampleDevice.push_back(0);
  }
  SteadyClock clock;
  SessionReplay player(s, clock);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(player.run([](uint16_t, const Sample&) { return true; }), 6u);
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(20));
}

}  // namespace
}  // namespace imps::sim
