// SPDX-License-Identifier: MIT
// The app's OSC pose streaming without a window: a posed character sent with OscPoseWriter + OscPoseSender and
// received by OscPoseSource poses a second character identically (bit for bit); unknown joints are reported;
// raw channels from a DIY sender go through the calibration exactly as a device's samples do; --osc-out wraps a
// pose source and streams each pose it applies.
#include "osc_stream.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <thread>

#include "calibration/calibration.h"
#include "eventually.h"
#include "examples.h"
#include "imps/skeleton_cache.h"
#include "osc_bytes.h"

namespace imps::app {
namespace {

const Character& biped() { return test::exampleCharacter("simple_biped"); }

// An OSC source on an ephemeral loopback port (the CLI's specs always name a port; tests let the OS pick).
std::unique_ptr<OscPoseSource> openSource(std::optional<SampleMapper> calibration = std::nullopt) {
  drivers::DeviceSpec spec;
  spec.kind = drivers::DeviceKind::Osc;
  spec.path = "127.0.0.1";
  auto source = OscPoseSource::open(spec, biped(), std::move(calibration));
  EXPECT_TRUE(source) << source.error().str();
  return source ? std::move(*source) : nullptr;
}

std::string target(const OscPoseSource& s) { return "osc.udp://127.0.0.1:" + std::to_string(s.receiver().port()); }

// Polls like the frame loop until a pose arrives.
bool pollUntilPose(PoseSource& source, SkeletonCache& skeleton) {
  return eventually([&] {
    int64_t arrival = 0;
    return source.poll(skeleton, &arrival) && arrival > 0;
  });
}

TEST(OscPoseStreaming, AReceivedPoseIsTheSentPoseBitForBit) {
  SkeletonCache sent(biped()), received(biped());
  const auto& joints = biped().joints();
  for (size_t j = 0; j < joints.size(); ++j)
    sent.setRotation(int(j), glm::angleAxis(0.1f * float(j + 1), glm::normalize(glm::vec3(1, float(j % 3), 0.5f))) *
                                 joints[j].rest.rotation);
  sent.setTranslation(0, joints[0].rest.translation + glm::vec3(0.1f, -0.05f, 0.3f));
  auto source = openSource();
  ASSERT_TRUE(source);
  {
    auto sender = drivers::OscPoseSender::open({target(*source)});
    ASSERT_TRUE(sender) << sender.error().str();
    const OscPoseWriter writer(biped());
    EXPECT_TRUE(writer.skippedJoints().empty());
    auto pose = std::make_unique<drivers::OscPose>();
    writer.write(sent, 12345, *pose);
    EXPECT_EQ(pose->jointCount, joints.size());
    ASSERT_TRUE((*sender)->send(*pose));
  }
  ASSERT_TRUE(pollUntilPose(*source, received));
  for (size_t j = 0; j < joints.size(); ++j) {
    const glm::quat a = sent.local(int(j)).rotation, b = received.local(int(j)).rotation;
    EXPECT_TRUE(a.w == b.w && a.x == b.x && a.y == b.y && a.z == b.z)
        << joints[j].name << " " << a.w << " " << a.x << " " << a.y << " " << a.z << " vs " << b.w << " " << b.x << " "
        << b.y << " " << b.z << " len " << glm::length(a);
  }
  EXPECT_EQ(sent.local(0).translation, received.local(0).translation);
  const std::string summary = source->finish();
  EXPECT_NE(summary.find("OSC in: 1 poses, 0 channel samples, 0 late, 0 out of order, 0 dropped, 0 malformed"),
            std::string::npos)
      << summary;
}

// A UDP socket for hand-made datagrams.
void sendDatagram(uint16_t port, const std::vector<uint8_t>& bytes) {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  EXPECT_EQ(sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to),
            ssize_t(bytes.size()));
  ::close(fd);
}

TEST(OscPoseStreaming, UnknownJointsAreIgnoredAndReported) {
  auto source = openSource();
  ASSERT_TRUE(source);
  OscBytes frame, known, unknown;
  frame.str("/imps/frame").str(",i").u32(0);
  const glm::quat turn = glm::angleAxis(0.5f, glm::vec3(0, 0, 1));
  known.str("/imps/joint/Head").str(",ffff").f32(turn.w).f32(turn.x).f32(turn.y).f32(turn.z);
  unknown.str("/imps/joint/mixamorig:Tail").str(",ffff").f32(1).f32(0).f32(0).f32(0);
  sendDatagram(source->receiver().port(), OscBytes::bundle().element(frame).element(unknown).element(known).bytes);
  SkeletonCache skeleton(biped());
  ASSERT_TRUE(pollUntilPose(*source, skeleton));
  const glm::quat head = skeleton.local(biped().findJoint("Head")).rotation;
  EXPECT_EQ(head.w, turn.w);
  EXPECT_EQ(head.z, turn.z);
  EXPECT_NE(source->finish().find("joints the character does not have: mixamorig:Tail"), std::string::npos);
  HudInfo info;
  source->describe(info);
  EXPECT_NE(info.state.find("unknown joint mixamorig:Tail"), std::string::npos) << info.state;
}

TEST(OscPoseStreaming, RawChannelsGoThroughTheCalibrationLikeADevice) {
  auto c = calibration::Calibration::readFile(std::string(IMPS_SOURCE_DIR) + "/examples/simple_biped.calibration.json",
                                              &biped());
  ASSERT_TRUE(c) << c.error().str();
  SampleMapper direct(*c, "direct");
  auto source = openSource(SampleMapper(std::move(*c), "osc"));
  ASSERT_TRUE(source);
  drivers::Sample sample;
  sample.channelCount = 32;
  OscBytes channels;
  channels.str("/imps/channels").str("," + std::string(32, 'i'));
  for (int i = 0; i < 32; ++i) {
    sample.counts[i] = uint32_t(1800 + 23 * i);
    channels.u32(sample.counts[i]);
  }
  sendDatagram(source->receiver().port(), channels.bytes);
  SkeletonCache viaOsc(biped()), viaDevice(biped());
  ASSERT_TRUE(pollUntilPose(*source, viaOsc));
  direct.apply(0, sample, viaDevice);
  int moved = 0;
  for (size_t j = 0; j < biped().joints().size(); ++j) {
    const glm::quat a = viaOsc.local(int(j)).rotation, b = viaDevice.local(int(j)).rotation;
    EXPECT_TRUE(a.w == b.w && a.x == b.x && a.y == b.y && a.z == b.z) << biped().joints()[j].name;
    moved += a != biped().joints()[j].rest.rotation ? 1 : 0;
  }
  EXPECT_GT(moved, 5);  // the calibration really turned joints
  EXPECT_NE(source->finish().find("0 poses, 1 channel samples"), std::string::npos);
}

// A pose source that applies a given rotation to one joint every poll.
class TurningSource final : public PoseSource {
 public:
  bool poll(SkeletonCache& skeleton, int64_t* arrivalNs) override {
    if (polls_ >= 3) return false;
    skeleton.setRotation(biped().findJoint("L_UpperArm"), glm::angleAxis(0.2f * float(++polls_), glm::vec3(0, 0, 1)));
    *arrivalNs = 1000 * polls_;
    return true;
  }
  void describe(HudInfo& info) override { info.state = "turning"; }
  std::string finish() override { return "turned"; }

 private:
  int polls_ = 0;
};

TEST(OscPoseStreaming, OscOutStreamsEveryPoseTheWrappedSourceApplies) {
  auto receiverSource = openSource();
  ASSERT_TRUE(receiverSource);
  auto sender = openOscOut({target(*receiverSource)}, biped());
  ASSERT_TRUE(sender && *sender);
  TurningSource turning;
  OscStreamingSource streaming(turning, std::move(*sender), biped());
  SkeletonCache skeleton(biped());
  int64_t arrival = 0;
  for (int i = 0; i < 5; ++i) EXPECT_EQ(streaming.poll(skeleton, &arrival), i < 3);
  EXPECT_EQ(arrival, 3000);
  HudInfo info;
  streaming.describe(info);
  EXPECT_EQ(info.state, "turning, OSC out to 1 (0 dropped)");
  ASSERT_TRUE(eventually([&] { return receiverSource->receiver().stats().poses == 3; }));
  SkeletonCache received(biped());
  ASSERT_TRUE(pollUntilPose(*receiverSource, received));
  EXPECT_EQ(received.local(biped().findJoint("L_UpperArm")).rotation,
            skeleton.local(biped().findJoint("L_UpperArm")).rotation);
  const std::string summary = streaming.finish();
  EXPECT_EQ(summary.rfind("turned\npuppeteer: OSC out: 3 frames, 3 bundles sent, 0 dropped (queue full), 0 send errors "
                          "to 1 target(s)",
                          0),
            0u)
      << summary;
}

TEST(OscPoseStreaming, BadTargetsAreUsageErrors) {
  testing::internal::CaptureStderr();
  auto bad = openOscOut({"osc.udp://127.0.0.1:0"}, biped());
  const std::string err = testing::internal::GetCapturedStderr();
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error(), 2);
  EXPECT_NE(err.find("puppeteer: error: --osc-out osc.udp://127.0.0.1:0: osc:1:21: error: expected a port in 1..65535"),
            std::string::npos)
      << err;
  auto none = openOscOut({}, biped());
  ASSERT_TRUE(none);
  EXPECT_EQ(*none, nullptr);
}

}  // namespace
}  // namespace imps::app
