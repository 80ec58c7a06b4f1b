// The live device pose source: device session → pose mailbox → joints by channel name.
#include "viewer_live.h"

#include <chrono>
#include <utility>

namespace imps::app {
namespace {
int64_t steadyNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}
}  // namespace

LivePoseSource::LivePoseSource(drivers::TransportOpener opener, const drivers::DeviceSessionOptions& options,
                               const Character& character, std::string spec, std::optional<SampleMapper> calibration)
    : character_(character), spec_(std::move(spec)), map_(std::move(calibration)) {
  session_ = std::make_unique<drivers::DeviceSession>(std::move(opener), mailbox_, options);
  session_->start();
  rateWindowStartNs_ = steadyNowNs();
}

LivePoseSource::~LivePoseSource() { session_->stop(); }

bool LivePoseSource::poll(SkeletonCache& skeleton, int64_t* arrivalNs) {
  if (deviceName_.empty()) {
    // The channel names arrive with the handshake; build the by-name map once (deviceInfo() takes a mutex: not
    // per frame once known).
    std::optional<drivers::DeviceInfo> info = session_->deviceInfo();
    if (!info) return false;
    if (!map_) {
      sim::Session names;
      names.devices.push_back(*info);
      map_.emplace(names, character_);
    }
    deviceName_ = info->name.empty() ? "device" : info->name;
  }
  if (!mailbox_.latest(sample_)) return false;
  map_->apply(0, sample_, skeleton);
  if (arrivalNs) *arrivalNs = sample_.arrivalTimeNs;
  return true;
}

void LivePoseSource::describe(HudInfo& info) {
  const drivers::DeviceSessionStats st = session_->stats();
  const int64_t now = steadyNowNs();
  if (now - rateWindowStartNs_ >= 500'000'000) {
    rateHz_ = double(st.samples - rateWindowStartCount_) / (double(now - rateWindowStartNs_) * 1e-9);
    rateWindowStartNs_ = now, rateWindowStartCount_ = st.samples;
  }
  info.source = (deviceName_.empty() ? std::string("device") : deviceName_) + " (" + spec_ + ")";
  if (map_) info.mapping = map_->describe();
  info.state = drivers::toString(st.state);
  if (map_ && map_->mappedJoints() == 0) info.state += ", no channel names a joint: nothing moves";
  info.sampleRateHz = rateHz_;
  info.dropped = st.samplesDropped;
  info.corrupt = st.crcErrors + st.malformedFrames + st.parseErrors;
  const drivers::PoseMailboxStats ms = mailbox_.stats();
  info.overwritten = ms.overwritten;
  info.sampleAgeMs = double(ms.lastAgeNs) * 1e-6;
}

}  // namespace imps::app
