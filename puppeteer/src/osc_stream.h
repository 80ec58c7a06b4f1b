// SPDX-License-Identifier: MIT
// Streaming the app's poses to other programs and hosts (`--osc-out`, docs/osc.md), and an OSC pose stream as the
// app's pose source (`--device osc.udp://:PORT`).
#pragma once

#include <cstdint>
#include <expected>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/device_spec.h"
#include "drivers/osc_receiver.h"
#include "drivers/osc_sender.h"
#include "drivers/pose_mailbox.h"
#include "viewer.h"
#include "viewer_replay.h"

namespace imps::app {

// The character's pose as an OSC frame: every joint's local rotation (in joint order; at most kMaxOscJoints, names
// cut to kMaxOscJointName bytes are not sent — see skippedJoints()) and the first joint's translation as the root.
class OscPoseWriter {
 public:
  explicit OscPoseWriter(const Character& character);
  // Fills `pose` from `skeleton`'s local transforms; sampleTimeNs = `sampleTimeNs`.
  void write(const SkeletonCache& skeleton, int64_t sampleTimeNs, drivers::OscPose& pose) const;
  // Joints not streamed (names too long, or beyond kMaxOscJoints), for a warning at start.
  const std::vector<std::string>& skippedJoints() const { return skipped_; }

 private:
  std::vector<int> joints_;  // character joint index per streamed joint
  std::vector<std::string> skipped_;
  drivers::OscPose names_;  // names pre-filled once
};

// Wraps a pose source: every pose it applies is also queued on an OscPoseSender (its own thread; the frame loop
// never waits, a full queue drops the frame and counts it). Everything else is forwarded to the wrapped source.
class OscStreamingSource final : public PoseSource {
 public:
  // `inner` and `character` must outlive this source.
  OscStreamingSource(PoseSource& inner, std::unique_ptr<drivers::OscPoseSender> sender, const Character& character);
  bool poll(SkeletonCache& skeleton, int64_t* arrivalNs) override;
  void describe(HudInfo& info) override;
  void frameDone() override { inner_.frameDone(); }
  std::string toggleRecording() override { return inner_.toggleRecording(); }
  std::string recalibrate() override { return inner_.recalibrate(); }
  std::string takeMessage() override { return inner_.takeMessage(); }
  // The wrapped source's message, then the sender's counters ("OSC out: N frames to T targets, …").
  std::string finish() override;

 private:
  PoseSource& inner_;
  std::unique_ptr<drivers::OscPoseSender> sender_;
  OscPoseWriter writer_;
  std::unique_ptr<drivers::OscPose> pose_;  // scratch (large: kept off the stack)
};

// `--osc-out URL…`: the sender, or nullptr when `urls` is empty. Prints "puppeteer: error: …" and returns the
// exit code (kExitUsage) on a bad URL; warns about joints that cannot be streamed.
std::expected<std::unique_ptr<drivers::OscPoseSender>, int> openOscOut(const std::vector<std::string>& urls,
                                                                     const Character& character);

// An OSC pose stream as the pose source (`--device osc.udp://[ADDRESS]:PORT`): pose frames set the joints of the
// same names (rotations as sent, normalised only when off unit length by more than 1e-5; the root translation on
// the first joint); raw-channel frames go through the pose mailbox and `calibration` (or channel names) like a
// device's samples. Counters in the HUD and at the end.
class OscPoseSource final : public PoseSource {
 public:
  // Binds the port now: OscReceiver::open's error when it cannot. `character` must outlive the source.
  static IoResult<std::unique_ptr<OscPoseSource>> open(const drivers::DeviceSpec& spec, const Character& character,
                                                       std::optional<SampleMapper> calibration,
                                                       drivers::OscReceiverOptions options = {});
  ~OscPoseSource() override;
  bool poll(SkeletonCache& skeleton, int64_t* arrivalNs) override;
  void describe(HudInfo& info) override;
  std::string toggleRecording() override { return "recording an OSC stream is not supported (record at the sender)"; }
  std::string recalibrate() override { return "re-calibrate at the sender: this host receives calibrated poses"; }
  // "OSC in: N poses, M samples, L late, O out of order, D dropped, X malformed, T timeouts".
  std::string finish() override;
  const drivers::OscReceiver& receiver() const { return *receiver_; }

 private:
  OscPoseSource(const Character& character, std::string spec, std::optional<SampleMapper> calibration);
  void applyPose(SkeletonCache& skeleton);

  const Character& character_;
  std::string spec_;
  drivers::PoseMailbox mailbox_;
  std::unique_ptr<drivers::OscReceiver> receiver_;
  std::optional<SampleMapper> map_;
  std::unique_ptr<drivers::OscPose> pose_;
  drivers::Sample sample_;
  std::vector<std::string> cachedNames_;  // joint names of the last frame, and their character indices
  std::vector<int> cachedJoints_;
  std::vector<std::string> unknownJoints_;  // names in the stream the character does not have (first 16)
  int64_t rateWindowStartNs_ = 0;
  uint64_t rateWindowStartCount_ = 0;
  double rateHz_ = 0.0;
};

}  // namespace imps::app
