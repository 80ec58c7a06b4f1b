// SPDX-License-Identifier: MIT
// A live armature as a pose source for the viewer: a device session (its own I/O thread) publishing into a pose
// mailbox that the frame loop reads without waiting; recording every sample (key `o`) and re-calibrating (key `k`).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "calibration_flow.h"
#include "drivers/byte_transport.h"
#include "drivers/device_session.h"
#include "drivers/pose_mailbox.h"
#include "session_recorder.h"
#include "viewer.h"
#include "viewer_replay.h"

namespace imps::app {

// What the live app's recording and re-calibration need besides the device.
struct LiveSourceOptions {
  std::string recordPath;       // non-empty: start recording into this new file at once (--record)
  std::string recordDir = ".";  // where key `o` creates take-YYYYMMDD-HHMMSS.session (--record-dir)
  std::string scenePath;        // for the calibration's info
  std::string rigPath;          // --rig: the rig map key `k` calibrates when no calibration is in force
  std::string calibrationPath;  // --calibration: the calibration in force at start ("" when by channel names)
  std::string calibrationOut;   // where key `k` saves (default: calibrationPath)
  CalibrationFlowOptions calibrate;
};

// Samples become joint rotations through a calibration when one is given; otherwise channels map to joints by name
// (ChannelPoseMap): a device whose channels are named "<joint>:<Xrotation|Yrotation|Zrotation>" (a simulated
// armature playing a BVH-derived session) drives the joints of those names; any other device streams but moves
// nothing (the HUD says so).
//
// The device's problems reach the terminal (stderr, once per change of state or error) and the HUD (state and last
// error in a warning colour); a run in which no sample ever arrived ends with exitCode() kExitIoError.
//
// Every frame, poll() drains the mailbox's in-order queue (every sample, oldest first): into the recording when one
// is open (SessionRecorder, crash-safe like `puppeteer record`), and into the calibration window while one is
// being collected; then it applies the newest sample. The queue holds 16 s at 1 kHz, so a frame loop stalled for
// less than that (a reset's settle, a screenshot) loses nothing.
class LivePoseSource final : public PoseSource {
 public:
  // Starts the device session at once. `character` must outlive the source. Without `calibration` the by-name
  // mapping is built when the device has described its channels.
  LivePoseSource(drivers::TransportOpener opener, const drivers::DeviceSessionOptions& options,
                 const Character& character, std::string spec, std::optional<SampleMapper> calibration,
                 LiveSourceOptions live = {});
  ~LivePoseSource() override;
  bool poll(SkeletonCache& skeleton, int64_t* arrivalNs) override;
  void describe(HudInfo& info) override;
  std::string toggleRecording() override;
  std::string recalibrate() override;
  bool handlesDeviceKeys() const override { return true; }
  std::string takeMessage() override;
  std::string finish() override;
  int exitCode() const override;

  // The calibration in force (null when mapping by channel names).
  const calibration::Calibration* calibration() const { return map_ ? map_->calibration() : nullptr; }
  bool recording() const { return recordingWanted_; }

 private:
  void startRecording(std::string path);
  std::string stopRecording();
  void finishCalibration();
  void say(std::string message);
  void reportProblems();

  const Character& character_;
  std::string spec_;
  LiveSourceOptions live_;
  drivers::PoseMailbox mailbox_;
  std::unique_ptr<drivers::DeviceSession> session_;
  std::optional<SampleMapper> map_;
  std::optional<drivers::DeviceInfo> device_;
  std::string deviceName_;
  drivers::Sample sample_;
  std::vector<drivers::Sample> batch_;  // drained this frame; capacity kept across frames
  int64_t rateWindowStartNs_ = 0;
  uint64_t rateWindowStartCount_ = 0;
  double rateHz_ = 0.0;
  // Recording: wanted from the key (or --record) on; the file is created once the device has described itself.
  bool recordingWanted_ = false;
  std::string recordPath_;
  std::optional<SessionRecorder> recorder_;
  int64_t recordStartNs_ = 0;
  int64_t countersWrittenNs_ = 0;  // when the take last stored the link's counters
  std::string reportedError_;  // the device problem last printed, so each one is printed once
  bool gotSample_ = false;  // a sample arrived at some point: the run was not a failure to connect
  bool finished_ = false;
  // Re-calibration.
  CalibrationFlow flow_;
  std::string message_;
};

}  // namespace imps::app
