// SPDX-License-Identifier: MIT
// Tests for drivers/osc_codec: liblo's bundles decode to what was sent; DIY forms and number types are accepted;
// every kind of malformed datagram is refused with its byte offset, never read past.
#include "drivers/osc_codec.h"
#include "drivers/osc_sender.h"

#include <gtest/gtest.h>
#include <lo/lo.h>

#include <cmath>
#include <memory>
#include <string>

#include "osc_bytes.h"

namespace imps::drivers {
namespace {

OscPose samplePose() {
  OscPose p;
  p.frame = 41;
  p.sampleTimeNs = 123'456'789'012;
  p.sentTimeNs = 123'456'999'000;
  const char* names[] = {"Pelvis", "L_UpperArm", "a_joint_name_of_exactly_forty_seven_bytes_xxxxx"};
  for (int i = 0; i < 3; ++i) {
    std::strcpy(p.joints[i].name.data(), names[i]);
    const float a = 0.3f * float(i + 1);
    p.joints[i].w = std::cos(a), p.joints[i].x = std::sin(a) * 0.6f, p.joints[i].y = 0.0f,
    p.joints[i].z = -std::sin(a) * 0.8f;
  }
  p.jointCount = 3;
  p.hasRoot = true;
  p.root = {0.25f, 0.97f, -1.5f};
  return p;
}

struct Decoded {
  std::unique_ptr<OscPose> pose = std::make_unique<OscPose>();
  Sample sample;
  std::expected<OscDecoded, Diagnostics> result;
};

Decoded decode(const std::vector<uint8_t>& bytes, int64_t arrivalNs = 7) {
  Decoded d;
  d.result = decodeOscPacket(bytes, arrivalNs, *d.pose, d.sample);
  return d;
}

std::vector<uint8_t> serialise(lo_message m, const char* path) {
  size_t size = lo_message_length(m, path);
  std::vector<uint8_t> out(size);
  lo_message_serialise(m, path, out.data(), &size);
  lo_message_free(m);
  return out;
}

TEST(OscCodec, LibloBundleOfAPoseDecodesToThePose) {
  const OscPose sent = samplePose();
  Decoded d = decode(encodeOscPose(sent), 99);
  ASSERT_TRUE(d.result) << d.result.error().str();
  EXPECT_EQ(d.result->kind, OscPacketKind::Pose);
  EXPECT_EQ(d.pose->frame, sent.frame);
  EXPECT_EQ(d.pose->sampleTimeNs, sent.sampleTimeNs);
  EXPECT_EQ(d.pose->sentTimeNs, sent.sentTimeNs);
  EXPECT_EQ(d.pose->arrivalTimeNs, 99);
  ASSERT_EQ(d.pose->jointCount, sent.jointCount);
  for (int i = 0; i < sent.jointCount; ++i) {
    EXPECT_EQ(d.pose->joints[i].nameView(), sent.joints[i].nameView());
    EXPECT_EQ(d.pose->joints[i].w, sent.joints[i].w);  // float32 on the wire: exact
    EXPECT_EQ(d.pose->joints[i].x, sent.joints[i].x);
    EXPECT_EQ(d.pose->joints[i].y, sent.joints[i].y);
    EXPECT_EQ(d.pose->joints[i].z, sent.joints[i].z);
  }
  EXPECT_TRUE(d.pose->hasRoot);
  EXPECT_EQ(d.pose->root, sent.root);
}

TEST(OscCodec, FrameCounterWrapsAsUnsigned) {
  OscPose p = samplePose();
  p.frame = 0xFFFFFFFFu;  // int32 -1 on the wire
  Decoded d = decode(encodeOscPose(p));
  ASSERT_TRUE(d.result) << d.result.error().str();
  EXPECT_EQ(d.pose->frame, 0xFFFFFFFFu);
}

TEST(OscCodec, DiyChannelsMessageFromLiblo) {
  lo_message m = lo_message_new();
  for (int v : {0, 2048, 4095}) lo_message_add_int32(m, v);
  Decoded d = decode(serialise(m, "/imps/channels"), 55);
  ASSERT_TRUE(d.result) << d.result.error().str();
  EXPECT_EQ(d.result->kind, OscPacketKind::Channels);
  EXPECT_FALSE(d.result->hasFrame);
  EXPECT_EQ(d.sample.channelCount, 3);
  EXPECT_EQ(d.sample.counts[0], 0u);
  EXPECT_EQ(d.sample.counts[1], 2048u);
  EXPECT_EQ(d.sample.counts[2], 4095u);
  EXPECT_EQ(d.sample.counts[3], 0u);
  EXPECT_EQ(d.sample.arrivalTimeNs, 55);
  for (ChannelFlag f : d.sample.flags) EXPECT_EQ(f, ChannelFlag::Valid);
}

TEST(OscCodec, ChannelsWithAFrameTakeItsCounterAndTime) {
  OscBytes frame, channels;
  frame.str("/imps/frame").str(",ih").u32(12).i64(5'000'000);
  channels.str("/imps/channels").str(",hi").i64(4'000'000'000).u32(7);  // int64 reaches 2^32 - 1
  Decoded d = decode(OscBytes::bundle().element(frame).element(channels).bytes);
  ASSERT_TRUE(d.result) << d.result.error().str();
  EXPECT_EQ(d.result->kind, OscPacketKind::Channels);
  EXPECT_TRUE(d.result->hasFrame);
  EXPECT_EQ(d.sample.sequence, 12u);
  EXPECT_EQ(d.sample.deviceTimeNs, 5'000'000);
  EXPECT_EQ(d.sample.counts[0], 4'000'000'000u);
  EXPECT_EQ(d.sample.counts[1], 7u);
}

TEST(OscCodec, NumbersAsDoublesAndIntegersNestedBundlesAndForeignMessagesSkipped) {
  OscBytes frame, joint, root, foreign, inner;
  frame.str("/imps/frame").str(",i").u32(3);
  joint.str("/imps/joint/Head").str(",difi").f64(1.0).u32(0).f32(0.0f).u32(0);
  root.str("/imps/root").str(",fff").f32(1).f32(2).f32(3);
  foreign.str("/touchdesigner/fader").str(",f").f32(0.5f);
  inner = OscBytes::bundle().element(joint).element(foreign);
  Decoded d = decode(OscBytes::bundle().element(frame).element(inner).element(root).bytes);
  ASSERT_TRUE(d.result) << d.result.error().str();
  EXPECT_EQ(d.result->kind, OscPacketKind::Pose);
  ASSERT_EQ(d.pose->jointCount, 1);
  EXPECT_EQ(d.pose->joints[0].nameView(), "Head");
  EXPECT_EQ(d.pose->joints[0].w, 1.0f);
  EXPECT_EQ(d.pose->sampleTimeNs, 0);  // optional times absent
  EXPECT_TRUE(d.pose->hasRoot);
}

TEST(OscCodec, OtherProgramsTrafficIsIgnoredNotMalformed) {
  lo_message m = lo_message_new();
  lo_message_add_float(m, 0.5f);
  Decoded d = decode(serialise(m, "/1/fader1"));
  ASSERT_TRUE(d.result) << d.result.error().str();
  EXPECT_EQ(d.result->kind, OscPacketKind::Ignored);
  OscBytes untyped;  // OSC 1.0 allows a message without a type tag string
  untyped.str("/imps/frame");
  Decoded u = decode(untyped.bytes);
  ASSERT_TRUE(u.result) << u.result.error().str();
  EXPECT_EQ(u.result->kind, OscPacketKind::Ignored);
}

// Each malformed datagram gives an error naming the offending byte.
void expectError(const std::vector<uint8_t>& bytes, size_t offset, const std::string& words) {
  Decoded d = decode(bytes);
  ASSERT_FALSE(d.result) << "accepted: " << words;
  EXPECT_EQ(d.result.error().str().rfind("osc:byte " + std::to_string(offset) + ": error: ", 0), 0u)
      << d.result.error().str();
  EXPECT_NE(d.result.error().str().find(words), std::string::npos) << d.result.error().str();
}

TEST(OscCodec, MalformedPacketsNameTheByteAndTheProblem) {
  expectError({}, 0, "empty packet");
  expectError({'/', 'a', 'b'}, 0, "multiple of 4");
  expectError({'/', 'a', 'b', 'c'}, 0, "ending in a NUL");
  expectError(OscBytes().str("imps/frame").str(",i").u32(1).bytes, 0, "starting with '/'");
  expectError(OscBytes().str("/imps/frame").str("i").u32(1).bytes, 12, "starting with ','");
  expectError(OscBytes().str("/imps/frame").str(",i").bytes, 16, "ends inside the frame counter");
  expectError(OscBytes().str("/imps/frame").str(",f").f32(1).bytes, 16, "as an OSC integer");
  expectError(OscBytes().str("/imps/frame").str(",if").u32(1).f32(2).bytes, 20, "as an OSC integer");
  expectError(OscBytes().str("/imps/frame").str(",is").u32(1).str("x").bytes, 20, "as an OSC integer");
  expectError(OscBytes().str("/imps/root").str(",fff").f32(1).f32(NAN).f32(3).bytes, 24, "not a finite number");
  expectError(OscBytes().str("/imps/joint/A").str(",dfff").f64(1e300).f32(0).f32(0).f32(0).bytes, 24,
              "beyond the range of a float");  // found by the fuzzer: was accepted as an infinite component
  expectError(OscBytes().str("/imps/joint/").str(",ffff").f32(1).f32(0).f32(0).f32(0).bytes, 0, "joint name");
  expectError(OscBytes().str("/imps/joint/A").str(",ffff").f32(0).f32(0).f32(0).f32(0).bytes, 40, "non-zero");
  expectError(OscBytes().str("/imps/channels").str(",i").u32(0xFFFFFFFFu).bytes, 24, "0..4294967295");
  expectError(OscBytes().str("/imps/channels").str(",").bytes, 20, "1..64 channel counts");
  // Joints without the frame header, and channels mixed with joints.
  OscBytes joint, frame, channels;
  joint.str("/imps/joint/A").str(",ffff").f32(1).f32(0).f32(0).f32(0);
  frame.str("/imps/frame").str(",i").u32(1);
  channels.str("/imps/channels").str(",i").u32(1);
  expectError(joint.bytes, 0, "without /imps/frame");
  expectError(OscBytes::bundle().element(frame).element(joint).element(channels).bytes, 0, "not both");
  expectError(OscBytes::bundle().element(frame).element(frame).bytes, 44, "a second /imps/frame");
}

TEST(OscCodec, MalformedBundlesNeverReadPastThePacket) {
  OscBytes frame;
  frame.str("/imps/frame").str(",i").u32(1);
  std::vector<uint8_t> good = OscBytes::bundle().element(frame).bytes;
  ASSERT_TRUE(decode(good).result);
  std::vector<uint8_t> oversize = good;
  oversize[19] = 0xFC;  // element size 252 > what is left
  expectError(oversize, 16, "larger than what is left");
  std::vector<uint8_t> odd = good;
  odd[19] = 6;
  expectError(odd, 16, "positive multiple of 4");
  expectError(OscBytes().str("#bundle").u32(0).bytes, 8, "time tag");
  // Every truncation of a good packet (at a multiple of 4) is an error, not a crash; only the bare 16-byte bundle
  // header is valid OSC (an empty bundle).
  for (size_t n = 4; n < good.size(); n += 4) {
    if (n == 16) continue;
    Decoded d = decode(std::vector<uint8_t>(good.begin(), good.begin() + long(n)));
    EXPECT_FALSE(d.result) << n;
  }
  // Five levels of nesting are refused.
  OscBytes nested = OscBytes::bundle().element(frame);
  for (int i = 0; i < 4; ++i) nested = OscBytes::bundle().element(nested);
  Decoded d = decode(nested.bytes);
  ASSERT_FALSE(d.result);
  EXPECT_NE(d.result.error().str().find("nested deeper than 4"), std::string::npos);
}

TEST(OscCodec, JointLimitsAreEnforced) {
  OscBytes packet = OscBytes::bundle().element(OscBytes().str("/imps/frame").str(",i").u32(0));
  for (int i = 0; i <= kMaxOscJoints; ++i)
    packet.element(OscBytes().str("/imps/joint/J" + std::to_string(i)).str(",ffff").f32(1).f32(0).f32(0).f32(0));
  Decoded d = decode(packet.bytes);
  ASSERT_FALSE(d.result);
  EXPECT_NE(d.result.error().str().find("more than 128 joints"), std::string::npos) << d.result.error().str();
  const std::string longName(kMaxOscJointName + 1, 'x');
  expectError(OscBytes().str("/imps/joint/" + longName).str(",ffff").f32(1).f32(0).f32(0).f32(0).bytes, 0,
              "joint name of 1..47 bytes");
}

}  // namespace
}  // namespace imps::drivers
