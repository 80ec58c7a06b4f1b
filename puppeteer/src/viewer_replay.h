// SPDX-License-Identifier: MIT
// Replayed sessions as a pose source for the viewer: channels mapped to joints by name (the fallback used until a
// calibration library exists) and a replay thread that feeds the frame loop through pose mailboxes.
#pragma once

#include <atomic>
#include <cstdint>
#include <expected>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "calibration/calibration.h"
#include "drivers/pose_mailbox.h"
#include "imps/skeleton_cache.h"
#include "retarget.h"
#include "sim/session_file.h"
#include "viewer.h"

namespace imps::app {

// Maps a session's channels named "<joint>:<Xrotation|Yrotation|Zrotation>" (as bvhToSession names them) onto the
// character's joint of the same name: counts → degrees with sim::countsToDegrees (mid-scale = 0 degrees), the
// joint's rotations composed in channel order as BVH does, applied on top of the joint's rest rotation from the
// scene file. Position channels and channels of unknown joints are ignored (listed by unmatched()). Readings not
// flagged Valid keep the channel's previous angle.
class ChannelPoseMap {
 public:
  ChannelPoseMap(const sim::Session& session, const Character& character);

  // Stores the readings of one sample of device `device` and sets every mapped joint's rotation in `skeleton`
  // (call skeleton.update() afterwards). Unknown devices are ignored.
  void apply(uint16_t device, const drivers::Sample& sample, SkeletonCache& skeleton);

  size_t mappedJoints() const { return joints_.size(); }
  size_t mappedChannels() const;
  const std::vector<std::string>& unmatched() const { return unmatched_; }

 private:
  struct Channel {
    size_t slot = 0;  // index into angles_
    int axis = 0;     // 0 x, 1 y, 2 z
  };
  struct MappedJoint {
    int joint = -1;
    glm::quat rest{1.0f, 0.0f, 0.0f, 0.0f};
    std::vector<Channel> channels;  // in file order
  };
  std::vector<size_t> firstSlot_;  // per device: slot of its channel 0
  std::vector<int> bits_;          // per device
  std::vector<double> angles_;     // degrees, per slot (every channel of every device)
  std::vector<MappedJoint> joints_;
  std::vector<std::string> unmatched_;
};

// A session that carries a SKELETON (a BVH clip converted by bvhToSession) retargeted onto the character: raw counts
// back to the clip's values (degrees, clip units), then Retargeter::pose (rotations with rest-pose correction, root
// translation scaled by leg length). The reference for translations is the session's first frame.
class ClipPoseMap {
 public:
  // Errors: the skeleton does not parse (the reader's diagnostics, at "session skeleton:LINE:COLUMN"), or its
  // channels differ from the devices', or it cannot be retargeted (one diagnostic without a position).
  static std::expected<ClipPoseMap, Diagnostics> create(const sim::Session& session, const Character& character,
                                                        const RetargetOptions& options);
  void apply(uint16_t device, const drivers::Sample& sample, SkeletonCache& skeleton);
  const Retargeter& retargeter() const { return *retargeter_; }
  const sim::BvhClip& clip() const { return clip_; }

 private:
  void read(uint16_t device, const drivers::Sample& sample);
  sim::BvhClip clip_;
  std::optional<Retargeter> retargeter_;
  std::vector<size_t> firstSlot_;
  std::vector<int> bits_;
  std::vector<bool> rotation_;  // per slot
  double unitsPerCount_ = 1;
  std::vector<float> values_;   // per slot: the clip's frame
  std::vector<JointPose> pose_;
};

// How samples become joint rotations: a calibration (calibration/: offsets, signs, gains, limits, deadband,
// smoothing) when there is one, a retargeted clip for sessions made from BVH, else the channels-by-name fallback
// above. Not thread-safe: the frame loop owns it.
class SampleMapper {
 public:
  // By channel names; `devices` supplies the devices' channel names.
  SampleMapper(const sim::Session& devices, const Character& character);
  // Through a calibration (each device's samples drive the mappings on that device). `label` is shown in the HUD.
  SampleMapper(calibration::Calibration calibration, std::string label);
  // Through a retargeted clip; `label` ("auto", "names", the map file) is shown in the HUD.
  SampleMapper(ClipPoseMap clip, std::string label);

  void apply(uint16_t device, const drivers::Sample& sample, SkeletonCache& skeleton);
  size_t mappedJoints() const;
  // "calibration LABEL, N joints" or "channel names, N joints".
  std::string describe() const;
  const ChannelPoseMap* byName() const { return byName_ ? &*byName_ : nullptr; }
  const ClipPoseMap* clip() const { return clip_ ? &*clip_ : nullptr; }
  // The calibration in use, or null when mapping by channel names.
  const calibration::Calibration* calibration() const {
    return calibrator_ ? &calibrator_->calibration() : nullptr;
  }

 private:
  std::optional<ChannelPoseMap> byName_;
  std::optional<ClipPoseMap> clip_;
  std::optional<calibration::Calibrator> calibrator_;
  std::string label_;
};

// Plays a session in real time (or faster / slower) on its own thread into one PoseMailbox per device, looping at
// the end; arrival times are re-stamped on the steady clock at delivery, exactly as a live device session would.
// The frame loop only ever calls mailbox(d).latest(): it never waits for the replay.
class ReplayThread {
 public:
  // `session` must outlive the thread.
  ReplayThread(const sim::Session& session, double speed);
  ~ReplayThread();  // stops and joins
  ReplayThread(const ReplayThread&) = delete;
  ReplayThread& operator=(const ReplayThread&) = delete;

  drivers::PoseMailbox& mailbox(size_t device) { return *mailboxes_[device]; }
  size_t devices() const { return mailboxes_.size(); }
  uint64_t loops() const { return loops_.load(std::memory_order_relaxed); }

 private:
  void run();
  const sim::Session& session_;
  double speed_;
  std::vector<std::unique_ptr<drivers::PoseMailbox>> mailboxes_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> loops_{0};
  imps::SteadyClock clock_;
  std::unique_ptr<sim::SessionReplay> replay_;
  std::thread thread_;
};

// A PoseSource playing a session in real time through a ReplayThread (the frame loop never waits for it).
class ReplayPoseSource final : public PoseSource {
 public:
  // `session` must outlive the source; `name` is shown in the HUD.
  ReplayPoseSource(const sim::Session& session, SampleMapper mapper, double speed, std::string name);
  bool poll(SkeletonCache& skeleton, int64_t* arrivalNs) override;
  void describe(HudInfo& info) override;

 private:
  SampleMapper map_;
  ReplayThread thread_;
  std::string name_;
  double speed_;
  drivers::Sample sample_;
  int64_t rateWindowStartNs_ = 0;
  uint64_t rateWindowStartCount_ = 0;
  double rateHz_ = 0.0;
};

// A PoseSource that steps through a session one frame per rendered frame, without a clock: frame f shows the
// f-th sample of device 0 (with the other devices' samples recorded before the next one), looping. The same
// session then gives the same pose sequence, and with the deterministic tesselator the same meshes, every run.
class SteppedReplayPoseSource final : public PoseSource {
 public:
  SteppedReplayPoseSource(const sim::Session& session, SampleMapper mapper, std::string name);
  bool poll(SkeletonCache& skeleton, int64_t* arrivalNs) override;
  void describe(HudInfo& info) override;

 private:
  const sim::Session& session_;
  SampleMapper map_;
  std::string name_;
  size_t next_ = 0;
  uint64_t frames_ = 0;
};

}  // namespace imps::app
