// SPDX-License-Identifier: MIT
// Takes recorded in the app (puppeteer/src/session_recorder.cpp): what is appended reads back sample-exact with the
// device and the calibration in force; a layout change is recorded, not dropped; recordings never overwrite; a
// full disk (a file-size limit) is reported and the take stays readable up to its last flush; take names.
#include "session_recorder.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>
#include <ctime>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "calibration/calibration.h"
#include "cli_run.h"
#include "error_text.h"
#include "examples.h"
#include "scratch_dir.h"
#include "sim/session_file.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;

drivers::DeviceInfo device(int channels) {
  drivers::DeviceInfo d;
  d.name = "IMPS Simulated Monkey";
  d.serialNumber = "SIM0001";
  d.firmwareVersion = "sim-1";
  d.channelCount = channels;
  d.bitsPerChannel = 12;
  d.hasDeviceTimestamp = true;
  for (int i = 0; i < channels; ++i) d.channelNames.push_back("ch" + std::to_string(i));
  return d;
}

// `n` samples of `channels` random counts (and a flag now and then), sequence numbers from `first`.
std::vector<drivers::Sample> samples(size_t n, int channels, uint32_t first, uint32_t seed) {
  std::mt19937 random(seed);
  std::vector<drivers::Sample> out(n);
  for (size_t i = 0; i < n; ++i) {
    drivers::Sample& s = out[i];
    s.sequence = first + uint32_t(i);
    s.deviceTimeNs = int64_t(s.sequence) * 1'000'000;
    s.arrivalTimeNs = 7'000'000'000 + s.deviceTimeNs + int64_t(random() % 1000);
    s.channelCount = uint16_t(channels);
    for (int c = 0; c < channels; ++c) s.counts[size_t(c)] = random() % 4096;
    if (i % 17 == 3) s.flags[0] = drivers::ChannelFlag(1);
  }
  return out;
}

TEST(SessionRecorder, WhatIsRecordedReadsBackSampleExact) {
  const ScratchDir dir("imps_session_recorder");
  const fs::path path = dir / "take.session";
  auto calibration = calibration::Calibration::readFile(test::sourceFile("examples/simple_biped.calibration.json"),
                                                        &test::exampleCharacter("simple_biped"), nullptr);
  ASSERT_TRUE(calibration) << calibration.error().str();
  const drivers::DeviceInfo dev = device(32);
  auto recorder = SessionRecorder::create(path, dev, &*calibration);
  ASSERT_TRUE(recorder) << test::errorOf(recorder);
  const std::vector<drivers::Sample> first = samples(300, 32, 0, 1), second = samples(200, 32, 300, 2);
  ASSERT_TRUE(recorder->append(first));
  drivers::DeviceSessionStats stats;
  stats.crcErrors = 3;
  stats.samplesDropped = 5;
  ASSERT_TRUE(recorder->appendCounters(stats));
  ASSERT_TRUE(recorder->append(second));
  EXPECT_EQ(recorder->samples(), 500u);
  EXPECT_EQ(recorder->path(), path);
  ASSERT_TRUE(recorder->close());

  auto session = sim::readSession(path);
  ASSERT_TRUE(session) << session.error().str();
  EXPECT_TRUE(session->recovery.closedCleanly);
  ASSERT_EQ(session->devices.size(), 1u);
  EXPECT_EQ(session->devices[0], dev);
  ASSERT_EQ(session->samples.size(), first.size() + second.size());
  for (size_t i = 0; i < first.size(); ++i) ASSERT_EQ(session->samples[i], first[i]) << i;
  for (size_t i = 0; i < second.size(); ++i) ASSERT_EQ(session->samples[first.size() + i], second[i]) << i;
  ASSERT_EQ(session->calibrations.size(), 1u);
  EXPECT_EQ(session->calibrations[0].firstSample, 0u);
  EXPECT_TRUE(session->layoutChanges.empty());
  ASSERT_EQ(session->counters.size(), 1u);
  bool crc = false;
  for (const sim::SessionCounter& c : session->counters[0].values)
    if (c.name == "crcErrors") crc = c.value == 3;
  EXPECT_TRUE(crc);
}

// A line-protocol device that re-locks to another channel count: a LAYOUT record, and every sample kept under it.
TEST(SessionRecorder, ALayoutChangeIsRecordedNotDropped) {
  const ScratchDir dir("imps_session_recorder");
  const fs::path path = dir / "layout.session";
  auto recorder = SessionRecorder::create(path, device(8), nullptr);
  ASSERT_TRUE(recorder) << test::errorOf(recorder);
  const std::vector<drivers::Sample> eight = samples(50, 8, 0, 3), six = samples(40, 6, 50, 4);
  ASSERT_TRUE(recorder->append(eight));
  ASSERT_TRUE(recorder->append(six));
  EXPECT_EQ(recorder->layoutChanges(), 1u);
  ASSERT_TRUE(recorder->close());
  auto session = sim::readSession(path);
  ASSERT_TRUE(session) << session.error().str();
  ASSERT_EQ(session->samples.size(), 90u);
  EXPECT_EQ(session->layoutChanges.size(), 1u);
  ASSERT_EQ(session->devices.size(), 2u);
  EXPECT_EQ(session->devices[1].channelCount, 6);
  for (size_t i = 0; i < six.size(); ++i) EXPECT_EQ(session->samples[50 + i], six[i]) << i;
  EXPECT_TRUE(session->calibrations.empty());
}

TEST(SessionRecorder, NeverOverwritesAndNeedsADirectory) {
  const ScratchDir dir("imps_session_recorder");
  writeBytes(dir / "existing.session", "precious");
  EXPECT_FALSE(SessionRecorder::create(dir / "existing.session", device(4), nullptr));
  EXPECT_EQ(fileBytes(dir / "existing.session"), "precious");
  EXPECT_FALSE(SessionRecorder::create(dir / "nodir/take.session", device(4), nullptr));
  EXPECT_FALSE(fs::exists(dir / "nodir"));
}

// A full disk (here a file-size limit, as `ulimit -f`): append reports the write error, and the file reads back up
// to its last flush, every sample in it exact.
TEST(SessionRecorder, AFullDiskIsReportedAndTheTakeStaysReadable) {
  const ScratchDir dir("imps_session_recorder");
  const fs::path path = dir / "full.session";
  sim::SessionWriterOptions options;
  options.flushEverySamples = 16;
  auto recorder = SessionRecorder::create(path, device(32), nullptr, options);
  ASSERT_TRUE(recorder) << test::errorOf(recorder);
  const std::vector<drivers::Sample> all = samples(2000, 32, 0, 5);
  const auto oldHandler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit old{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old), 0);
  rlimit limited = old;
  limited.rlim_cur = 32 * 1024;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &limited), 0);
  bool failed = false;
  std::string error;
  for (size_t i = 0; i < all.size() && !failed; i += 16) {
    auto appended = recorder->append(std::span(all).subspan(i, 16));
    if (!appended) failed = true, error = test::errorOf(appended);
  }
  ::setrlimit(RLIMIT_FSIZE, &old);
  std::signal(SIGXFSZ, oldHandler);
  ASSERT_TRUE(failed) << "32 KiB cannot hold 2000 samples of 32 channels";
  EXPECT_NE(error.find("File too large"), std::string::npos) << error;
  auto session = sim::readSession(path);
  ASSERT_TRUE(session) << session.error().str();
  EXPECT_FALSE(session->recovery.closedCleanly);
  ASSERT_GT(session->samples.size(), 0u);
  ASSERT_LT(session->samples.size(), all.size());
  for (size_t i = 0; i < session->samples.size(); ++i) ASSERT_EQ(session->samples[i], all[i]) << i;
}

TEST(SessionRecorder, HelpersNameTakesChannelsAndCounters) {
  const ScratchDir dir("imps_session_recorder");
  std::tm when{};
  when.tm_year = 2026 - 1900, when.tm_mon = 10, when.tm_mday = 27, when.tm_hour = 9, when.tm_min = 5, when.tm_sec = 7;
  when.tm_isdst = -1;
  const std::time_t t = std::mktime(&when);
  const fs::path first = newTakePath(dir.path(), t);
  EXPECT_EQ(first.parent_path(), dir.path());
  EXPECT_EQ(first.filename(), "take-20261127-090507.session");
  writeBytes(first, "");
  EXPECT_EQ(newTakePath(dir.path(), t).filename(), "take-20261127-090507-2.session");

  drivers::DeviceInfo named = device(3);
  named.channelNames = {"a", "b", "c"};
  EXPECT_EQ(withChannelCount(named, 3), named);
  const drivers::DeviceInfo two = withChannelCount(named, 2);
  EXPECT_EQ(two.channelCount, 2);
  EXPECT_EQ(two.channelNames, (std::vector<std::string>{"ch0", "ch1"}));
  EXPECT_EQ(two.name, named.name);

  drivers::DeviceSessionStats stats;
  stats.crcErrors = 4;
  const std::string summary = countersSummary(stats);
  for (const drivers::NamedCounter& c : drivers::namedCounters(stats))
    EXPECT_NE(summary.find(std::string(c.label) + ": " + std::to_string(c.value)), std::string::npos) << c.label;
}

}  // namespace
}  // namespace imps::app
