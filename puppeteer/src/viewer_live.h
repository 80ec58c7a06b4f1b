// A live armature as a pose source for the viewer: a device session (its own I/O thread) publishing into a pose
// mailbox that the frame loop reads without waiting.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "drivers/byte_transport.h"
#include "drivers/device_session.h"
#include "drivers/pose_mailbox.h"
#include "viewer.h"
#include "viewer_replay.h"

namespace imps::app {

// Samples become joint rotations through a calibration when one is given; otherwise channels map to joints by name
// (ChannelPoseMap): a device whose channels are named "<joint>:<Xrotation|Yrotation|Zrotation>" (a simulated
// armature playing a BVH-derived session) drives the joints of those names; any other device streams but moves
// nothing (the HUD says so).
class LivePoseSource final : public PoseSource {
 public:
  // Starts the device session at once. `character` must outlive the source. Without `calibration` the by-name
  // mapping is built when the device has described its channels.
  LivePoseSource(drivers::TransportOpener opener, const drivers::DeviceSessionOptions& options,
                 const Character& character, std::string spec, std::optional<SampleMapper> calibration);
  ~LivePoseSource() override;
  bool poll(SkeletonCache& skeleton, int64_t* arrivalNs) override;
  void describe(HudInfo& info) override;

 private:
  const Character& character_;
  std::string spec_;
  drivers::PoseMailbox mailbox_;
  std::unique_ptr<drivers::DeviceSession> session_;
  std::optional<SampleMapper> map_;
  std::string deviceName_;
  drivers::Sample sample_;
  int64_t rateWindowStartNs_ = 0;
  uint64_t rateWindowStartCount_ = 0;
  double rateHz_ = 0.0;
};

}  // namespace imps::app
