// SPDX-License-Identifier: MIT
// Rig map files: parsing, validation errors with exact file:line:column messages, and round trips.
#include "examples.h"
#include "calibration/rig_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "imps/character.h"
#include "imps/scene_reader.h"
#include "imps/utf8.h"

namespace imps::calibration {
namespace {

const Character& biped() { return test::exampleCharacter("simple_biped"); }

drivers::DeviceInfo device32() {
  drivers::DeviceInfo d;
  d.name = "Monkey-32";
  d.channelCount = 32;
  d.bitsPerChannel = 12;
  for (int i = 0; i < 32; ++i) d.channelNames.push_back("ch" + std::to_string(i));
  d.channelNames[16] = "L_elbow";
  return d;
}

// The diagnostics of a file that must not parse, one per line.
std::string errors(const std::string& json, const RigMapContext& ctx = {}) {
  auto r = parseRigMap(json, "rig.json", ctx);
  EXPECT_FALSE(r.has_value()) << "parsed but should not:\n" << json;
  return r ? "" : r.error().str();
}

// A minimal valid file around one channel object.
std::string oneChannel(const std::string& channel, const std::string& joint = "L_Forearm") {
  return "{\n"
         "  \"version\": 1,\n"
         "  \"bits\": 12,\n"
         "  \"joints\": [\n"
         "    {\"joint\": \"" + joint + "\", \"channels\": [\n"
         "      " + channel + "\n"
         "    ]}\n"
         "  ]\n"
         "}\n";
}

TEST(RigMap, ParsesEveryField) {
  const std::string text = oneChannel(
      R"({"channel": 16, "axis": "y", "sign": -1, "range_deg": 360, "offset": 100, "min_deg": -150, "max_deg": 5, )"
      R"("deadband_deg": 0.5, "smoothing_ms": 8})");
  auto r = parseRigMap(text, "rig.json", {&biped(), nullptr, true});
  ASSERT_TRUE(r.has_value()) << r.error().str();
  ASSERT_EQ(r->channels.size(), 1u);
  const ChannelMap& c = r->channels[0];
  EXPECT_EQ(c.channel, 16);
  EXPECT_EQ(c.joint, "L_Forearm");
  EXPECT_EQ(c.axis, Axis::Y);
  EXPECT_EQ(c.sign, -1);
  EXPECT_DOUBLE_EQ(c.gain, 4096 / (2 * std::numbers::pi));
  EXPECT_DOUBLE_EQ(*c.offset, 100);
  EXPECT_NEAR(c.minAngle, -150 * std::numbers::pi / 180, 1e-12);
  EXPECT_NEAR(c.maxAngle, 5 * std::numbers::pi / 180, 1e-12);
  EXPECT_NEAR(c.deadband, 0.5 * std::numbers::pi / 180, 1e-12);
  EXPECT_DOUBLE_EQ(c.smoothingMs, 8);
  EXPECT_EQ(c.loc.line, 6);
  EXPECT_EQ(c.loc.column, 19);
  ASSERT_EQ(r->joints.size(), 1u);
  EXPECT_EQ(r->joints[0].order, "Y");
}

TEST(RigMap, GainDefaultsToOneTurnForAbsoluteEncoders) {
  auto r = parseRigMap(oneChannel(R"({"channel": 0, "axis": "x", "sign": 1})"), "rig.json");
  ASSERT_TRUE(r.has_value()) << r.error().str();
  EXPECT_DOUBLE_EQ(r->channels[0].gain, 4096 / (2 * std::numbers::pi));
  EXPECT_FALSE(r->channels[0].offset.has_value());
}

TEST(RigMap, UnknownJointSuggestsTheClosestName) {
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "x", "sign": 1})", "L_Forarm"), {&biped()}),
            "rig.json:5:15: error: unknown joint 'L_Forarm'; did you mean 'L_Forearm'?\n");
}

TEST(RigMap, UnknownFieldSuggestsTheClosestName) {
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "x", "sign": 1, "deadbnd_deg": 0.1})")),
            "rig.json:6:46: error: unknown field 'deadbnd_deg' in a channel of joint 'L_Forearm'; did you mean "
            "'deadband_deg'?\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "x", "sign": 1, "wobble": 1})")),
            "rig.json:6:46: error: unknown field 'wobble' in a channel of joint 'L_Forearm' (expected 'channel', "
            "'axis', 'sign', 'gain', 'range', 'range_deg', 'offset', 'min', 'min_deg', 'max', 'max_deg', 'deadband', "
            "'deadband_deg', 'smoothing_ms', 'encoder', 'metres_per_count' or 'device')\n");
}

TEST(RigMap, MissingFields) {
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "sign": 1})")),
            "rig.json:6:7: error: missing field 'axis' in a channel of joint 'L_Forearm'\n");
  EXPECT_EQ(errors("{\"bits\": 12, \"joints\": []}"),
            "rig.json:1:1: error: missing field 'version' (this program writes \"version\": 1)\n");
  EXPECT_EQ(errors("{\"version\": 1, \"bits\": 12}"), "rig.json:1:1: error: missing field 'joints' in the rig map\n");
}

TEST(RigMap, ImpossibleValues) {
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "x", "sign": 1, "gain": 0})")),
            "rig.json:6:54: error: gain must be a positive number of counts per radian (got 0.000000)\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "x", "sign": 1, "min_deg": 10, "max_deg": -10})")),
            "rig.json:6:72: error: 'max' (-10.000000 deg) is below 'min' (10.000000 deg)\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "x", "sign": 1, "deadband": -0.1})")),
            "rig.json:6:58: error: deadband must be >= 0 radians (got -0.100000)\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "w", "sign": 1})")),
            "rig.json:6:30: error: bad axis 'w': expected 'x', 'y' or 'z' (rotations) or 'tx', 'ty' or 'tz' "
            "(translations)\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "x", "sign": 2})")),
            "rig.json:6:43: error: 'sign' must be 1 or -1\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "x", "sign": 1, "gain": NaN})")),
            "rig.json:6:54: error: NaN and infinities are not JSON numbers: write a finite number\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "x", "sign": 1, "offset": 4096})")),
            "rig.json:6:56: error: offset 4096.000000 is outside the encoder's counts [0, 4096)\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "x", "sign": 1, "gain": "600"})")),
            "rig.json:6:54: error: 'gain' must be a number, not a string\n");
}

// Translation axes: metres per count, limits and deadband in metres, linear by default, outside the rotation order.
TEST(RigMap, TranslationAxesReadMetresAndRoundTrip) {
  const std::string text =
      "{\"version\": 1, \"bits\": 12, \"joints\": [\n"
      "  {\"joint\": \"Pelvis\", \"order\": \"ZX\", \"channels\": [\n"
      "    {\"channel\": 0, \"axis\": \"z\", \"sign\": 1},\n"
      "    {\"channel\": 1, \"axis\": \"ty\", \"sign\": -1, \"metres_per_count\": 0.001, \"offset\": 100,\n"
      "     \"min\": -0.5, \"max\": 0.75, \"deadband\": 0.002},\n"
      "    {\"channel\": 2, \"axis\": \"x\", \"sign\": 1},\n"
      "    {\"channel\": 3, \"axis\": \"TX\", \"sign\": 1, \"gain\": 500}\n"
      "  ]}\n"
      "]}\n";
  auto r = parseRigMap(text, "rig.json", {&biped(), nullptr, false});
  ASSERT_TRUE(r.has_value()) << r.error().str();
  ASSERT_EQ(r->channels.size(), 4u);
  const ChannelMap& ty = r->channels[1];
  EXPECT_TRUE(ty.translation);
  EXPECT_EQ(ty.axis, Axis::Y);
  EXPECT_EQ(ty.encoder, EncoderKind::Linear);
  EXPECT_DOUBLE_EQ(ty.gain, 1000.0);  // counts per metre
  EXPECT_DOUBLE_EQ(ty.minAngle, -0.5);
  EXPECT_DOUBLE_EQ(ty.maxAngle, 0.75);
  EXPECT_DOUBLE_EQ(ty.deadband, 0.002);
  EXPECT_TRUE(r->channels[3].translation);
  EXPECT_EQ(r->channels[3].axis, Axis::X);
  EXPECT_FALSE(r->channels[0].translation);
  EXPECT_EQ(r->joints[0].order, "ZX");  // the rotation axes only
  auto again = parseRigMap(toJson(*r), "again.json");
  ASSERT_TRUE(again.has_value()) << again.error().str() << toJson(*r);
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(again->channels[i].translation, r->channels[i].translation) << i;
    EXPECT_EQ(again->channels[i].axis, r->channels[i].axis) << i;
    EXPECT_EQ(again->channels[i].gain, r->channels[i].gain) << i;
    EXPECT_EQ(again->channels[i].minAngle, r->channels[i].minAngle) << i;
    EXPECT_EQ(again->channels[i].deadband, r->channels[i].deadband) << i;
    EXPECT_EQ(again->channels[i].encoder, r->channels[i].encoder) << i;
  }
}

TEST(RigMap, TranslationAxesRefuseDegreesAndNeedAScale) {
  EXPECT_EQ(
      errors(oneChannel(R"({"channel": 0, "axis": "tz", "sign": 1})")),
      "rig.json:6:7: error: missing field 'metres_per_count' (a translation axis has no natural full scale)' in a "
      "channel of joint 'L_Forearm'\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "tz", "sign": 1, "metres_per_count": 0.01, "max_deg": 5})")),
            "rig.json:6:84: error: 'max_deg' is for rotation axes: a translation axis takes 'metres_per_count' and "
            "'min'/'max'/'deadband' in metres\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "tz", "sign": 1, "metres_per_count": -1})")),
            "rig.json:6:67: error: 'metres_per_count' must be positive\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "x", "sign": 1, "metres_per_count": 1})")),
            "rig.json:6:66: error: 'metres_per_count' is for translation axes (tx, ty, tz)\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": 0, "axis": "ty", "sign": 1, "gain": 10, "min": 1, "max": -1})")),
            "rig.json:6:76: error: 'max' (-1.000000 m) is below 'min' (1.000000 m)\n");
}

// A session split over two devices (a BVH clip with more than 64 channels): names resolve on whichever device has
// them, "device" pins one, and the errors name the device that does have the channel.
TEST(RigMap, ChannelsOfEveryDeviceOfASession) {
  std::vector<drivers::DeviceInfo> devices(2, device32());
  devices[0].name = "BVH: clip.bvh";
  devices[1].name = "BVH: clip.bvh (part 2)";
  devices[1].channelNames[3] = "RightHand:Zrotation";
  const std::string text =
      "{\"version\": 1, \"bits\": 12, \"joints\": [\n"
      "  {\"joint\": \"R_Hand\", \"channels\": [{\"channel\": \"RightHand:Zrotation\", \"axis\": \"z\", \"sign\": "
      "1}]},\n"
      "  {\"joint\": \"L_Hand\", \"channels\": [{\"channel\": 4, \"device\": 1, \"axis\": \"z\", \"sign\": 1}]},\n"
      "  {\"joint\": \"Head\", \"channels\": [{\"channel\": 3, \"axis\": \"z\", \"sign\": 1}]}\n"
      "]}\n";
  RigMapContext ctx{&biped(), &devices[0], false, devices};
  auto r = parseRigMap(text, "rig.json", ctx);
  ASSERT_TRUE(r.has_value()) << r.error().str();
  EXPECT_EQ(r->channels[0].device, 1);
  EXPECT_EQ(r->channels[0].channel, 3);
  EXPECT_EQ(r->channels[1].device, 1);
  EXPECT_EQ(r->channels[2].device, 0) << "channel 3 of device 0 is another channel than channel 3 of device 1";
  auto again = parseRigMap(toJson(*r), "again.json", ctx);
  ASSERT_TRUE(again.has_value()) << again.error().str();
  EXPECT_EQ(again->channels[1].device, 1);
  EXPECT_EQ(errors(oneChannel(R"({"channel": "RightHand:Zrotation", "device": 0, "axis": "z", "sign": 1})"), ctx),
            "rig.json:6:19: error: device 0 'BVH: clip.bvh' has no channel named 'RightHand:Zrotation'; device 1 "
            "'BVH: clip.bvh (part 2)' has it: write \"device\": 1\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": "RightHand:Zrotaton", "axis": "z", "sign": 1})"), ctx),
            "rig.json:6:19: error: no device of the session has a channel named 'RightHand:Zrotaton'; did you mean "
            "'RightHand:Zrotation' (device 1 'BVH: clip.bvh (part 2)')?\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": 1, "device": 2, "axis": "z", "sign": 1})"), ctx),
            "rig.json:6:32: error: device 2 does not exist: the session has 2 devices\n");
}

TEST(RigMap, DuplicateChannelsAndAxes) {
  const std::string text =
      "{\"version\": 1, \"bits\": 12, \"joints\": [\n"
      "  {\"joint\": \"L_Forearm\", \"channels\": [{\"channel\": 3, \"axis\": \"y\", \"sign\": 1}]},\n"
      "  {\"joint\": \"R_Forearm\", \"channels\": [{\"channel\": 3, \"axis\": \"y\", \"sign\": 1}]},\n"
      "  {\"joint\": \"Head\", \"order\": \"XX\", \"channels\": [{\"channel\": 4, \"axis\": \"x\", \"sign\": 1},\n"
      "                                    {\"channel\": 5, \"axis\": \"x\", \"sign\": 1}]}\n"
      "]}\n";
  EXPECT_EQ(errors(text),
            "rig.json:5:49: error: joint 'Head' axis x is driven by two channels\n"
            "rig.json:4:30: error: order 'XX' of joint 'Head' must list each driven axis once (driven: XX)\n"
            "rig.json:3:51: error: channel 3 is mapped twice: it already drives L_Forearm y (line 2)\n");
}

TEST(RigMap, SeveralAxesNeedAnOrder) {
  const std::string text =
      "{\"version\": 1, \"bits\": 12, \"joints\": [\n"
      "  {\"joint\": \"Head\", \"channels\": [{\"channel\": 4, \"axis\": \"x\", \"sign\": 1},\n"
      "                                    {\"channel\": 5, \"axis\": \"y\", \"sign\": 1}]}\n"
      "]}\n";
  EXPECT_EQ(errors(text),
            "rig.json:2:13: error: joint 'Head' is driven on 2 axes: add \"order\" (e.g. \"XY\") to say how they "
            "compose\n");
}

TEST(RigMap, ChannelsCheckedAgainstTheDevice) {
  const drivers::DeviceInfo dev = device32();
  EXPECT_EQ(errors(oneChannel(R"({"channel": 32, "axis": "y", "sign": 1})"), {nullptr, &dev}),
            "rig.json:6:19: error: channel 32 is out of range: device 'Monkey-32' has 32 channels (0..31)\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": "L_elbw", "axis": "y", "sign": 1})"), {nullptr, &dev}),
            "rig.json:6:19: error: device 'Monkey-32' has no channel named 'L_elbw'; did you mean 'L_elbow'?\n");
  auto ok = parseRigMap(oneChannel(R"({"channel": "L_elbow", "axis": "y", "sign": 1})"), "rig.json", {nullptr, &dev});
  ASSERT_TRUE(ok.has_value()) << ok.error().str();
  EXPECT_EQ(ok->channels[0].channel, 16);
  drivers::DeviceInfo dev10 = dev;
  dev10.bitsPerChannel = 10;
  EXPECT_EQ(errors(oneChannel(R"({"channel": 1, "axis": "y", "sign": 1})"), {nullptr, &dev10}),
            "rig.json:3:11: error: the rig map is for 12-bit encoders but the device 'Monkey-32' reports 10 bits per "
            "channel\n");
}

TEST(RigMap, WarnsWhenWrittenForAnotherDevice) {
  const drivers::DeviceInfo dev = device32();
  Diagnostics warnings;
  auto r = parseRigMap("{\"version\": 1, \"bits\": 12, \"device\": \"Monkey-16\", \"joints\": []}", "rig.json",
                       {nullptr, &dev}, &warnings);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(warnings.str(), "rig.json:1:38: warning: written for device 'Monkey-16' but used with 'Monkey-32'\n");
}

TEST(RigMap, CalibrationsNeedOffsets) {
  EXPECT_EQ(errors(oneChannel(R"({"channel": 2, "axis": "y", "sign": 1})"), {nullptr, nullptr, true}),
            "rig.json:6:19: error: missing field 'offset' for channel 2: a calibration needs every channel's offset "
            "(run `puppeteer calibrate`)\n");
}

TEST(RigMap, NewerVersionsAreRefused) {
  EXPECT_EQ(errors("{\n  \"version\": 2,\n  \"bits\": 12, \"joints\": [], \"future\": true\n}\n"),
            "rig.json:2:14: error: file format version 2 is newer than this program reads (1); update puppeteer\n");
}

TEST(RigMap, HugeVersionNumbersAreReportedNotOverflowed) {
  EXPECT_EQ(errors("{\"version\": 100000000000000000000, \"bits\": 12, \"joints\": []}"),
            "rig.json:1:13: error: file format version 100000000000000000000 is newer than this program reads (1); "
            "update puppeteer\n");
}

TEST(RigMap, InMemoryMapsAreValidatedToo) {
  RigMap m;
  m.bits = 12;
  ChannelMap c;
  c.channel = 0;
  c.joint = "Head";
  c.axis = Axis::Y;
  c.gain = 0;
  c.loc = {"mem", 1, 1};
  m.channels.push_back(c);
  m.joints.push_back({"Head", "X", {0}, {"mem", 2, 1}});
  Diagnostics d;
  EXPECT_FALSE(validateRigMap(m, {}, d));
  EXPECT_EQ(d.str(),
            "mem:1:1: error: gain must be a positive number of counts per radian (got 0.000000)\n"
            "mem:2:1: error: joint 'Head': its channels and order 'X' do not match (each driven axis once, driven: "
            "Y)\n");
}

TEST(RigMap, SyntaxErrorsHaveLocations) {
  EXPECT_EQ(errors("{\n  \"version\": 1,\n  \"bits\": 12,\n}\n"),
            "rig.json:4:1: error: expected a key after ',' (JSON has no trailing commas)\n");
  EXPECT_EQ(errors("{\"version\": 1, \"version\": 1}"),
            "rig.json:1:16: error: duplicate key 'version' (first at line 1)\n");
  EXPECT_EQ(errors("{\"version\": 1, \"bits\": 12, \"joints\": [\n"),
            "rig.json:2:1: error: unexpected end of file: expected a value\n");
}

TEST(RigMap, TextThatIsNotUtf8IsRefusedAtItsFirstBadByte) {
  EXPECT_EQ(errors("{\"version\": 1,\n  \"device\": \"ab\xFF\"}"),
            "rig.json:2:16: error: invalid UTF-8 (byte 0xFF); a JSON file must be UTF-8 text\n");
  EXPECT_EQ(errors(oneChannel(R"({"channel": 16, "axis": "y", "sign": 1})", "L_\xC3(")),
            "rig.json:5:18: error: invalid UTF-8 (byte 0xC3); a JSON file must be UTF-8 text\n");
}

TEST(RigMap, StringsFromADeviceThatAreNotUtf8AreWrittenAsValidJson) {
  // A map built in memory carries the device's own bytes: its name, channel names and the info the app records.
  auto a = parseRigMap(oneChannel(R"({"channel": "L_elbow", "axis": "y", "sign": 1})"), "a.json");
  ASSERT_TRUE(a.has_value()) << a.error().str();
  a->device = "Monkey \xFF";
  a->channels[0].channelName = "L_\xE2\x82";
  a->info = "{\"serial\":\"\xC0\x80\"}";
  std::string written;
  ASSERT_NO_THROW(written = toJson(*a));
  EXPECT_EQ(firstInvalidUtf8(written), written.size()) << written;
  auto b = parseRigMap(written, "b.json");
  ASSERT_TRUE(b.has_value()) << b.error().str() << written;
  EXPECT_EQ(b->device, "Monkey \uFFFD");
  EXPECT_EQ(b->channels[0].channelName, "L_\uFFFD");  // one replacement for a sequence cut short
  EXPECT_EQ(b->info, "{\"serial\":\"\uFFFD\uFFFD\"}");
}

TEST(RigMap, HugeFilesAreCheckedInLinearTimeAndTheReportIsCapped) {
  // 100,000 entries for one joint (each a duplicate of the first) and 200,000 unknown keys: the duplicate checks were
  // quadratic (50,000 keys took 22 s) and the report ran to megabytes. Every error is still counted.
  std::string text = "{\"version\": 1, \"bits\": 12,";
  for (int k = 0; k < 200000; ++k) text += " \"k" + std::to_string(k) + "\": 0,";
  text += " \"joints\": [\n";
  for (int j = 0; j < 100000; ++j)
    text += std::string(j ? "," : "") +
            "{\"joint\": \"Head\", \"channels\": [{\"channel\": 3, \"axis\": \"x\", \"sign\": 1}]}\n";
  text += "]}\n";
  auto r = parseRigMap(text, "big.json", {&biped()});
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().errorCount(), 200000 + 2 * 99999);  // unknown keys; joint listed twice; channel mapped twice
  const std::string report = r.error().str();
  EXPECT_EQ(std::count(report.begin(), report.end(), '\n'), 101) << report.substr(0, 2000);
  EXPECT_NE(report.find("\n... and 399898 more (399998 errors in all; only the first 100 are shown)\n"),
            std::string::npos)
      << report.substr(report.size() - 300);
}

TEST(RigMap, EveryErrorIsReportedNotOnlyTheFirst) {
  const std::string text =
      "{\"version\": 1, \"bits\": 12, \"joints\": [\n"
      "  {\"joint\": \"Hed\", \"channels\": [{\"channel\": 4, \"axis\": \"q\", \"sign\": 1}]},\n"
      "  {\"joint\": \"Neck\", \"channels\": [{\"channel\": 5, \"axis\": \"x\", \"sign\": 1, \"smoothing\": 3}]}\n"
      "]}\n";
  auto r = parseRigMap(text, "rig.json", {&biped()});
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().errorCount(), 3) << r.error().str();
}

TEST(RigMap, WriteThenReadReproducesTheMap) {
  const std::string text =
      "{\"version\": 1, \"bits\": 14, \"device\": \"Rig \\\"A\\\"\", \"info\": {\"who\": \"tech\", \"n\": [1, 2]},\n"
      " \"joints\": [\n"
      "  {\"joint\": \"L_UpperArm\", \"order\": \"zxy\", \"channels\": [\n"
      "    {\"channel\": 7, \"axis\": \"x\", \"sign\": -1, \"gain\": 2000.5, \"offset\": 16383.25, \"min\": -1, "
      "\"max\": 1.5},\n"
      "    {\"channel\": 8, \"axis\": \"y\", \"sign\": 1, \"encoder\": \"linear\", \"range_deg\": 270, \"deadband\": "
      "0.01},\n"
      "    {\"channel\": 9, \"axis\": \"z\", \"sign\": 1, \"smoothing_ms\": 12.5}]}\n"
      "]}\n";
  auto a = parseRigMap(text, "a.json", {&biped()});
  ASSERT_TRUE(a.has_value()) << a.error().str();
  const std::string written = toJson(*a);
  auto b = parseRigMap(written, "b.json", {&biped()});
  ASSERT_TRUE(b.has_value()) << b.error().str() << written;
  EXPECT_EQ(toJson(*b), written);
  EXPECT_EQ(b->bits, 14);
  EXPECT_EQ(b->device, "Rig \"A\"");
  EXPECT_EQ(b->info, R"({"who":"tech","n":[1,2]})");
  ASSERT_EQ(b->joints.size(), 1u);
  EXPECT_EQ(b->joints[0].order, "ZXY");
  ASSERT_EQ(b->channels.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const ChannelMap &x = a->channels[i], &y = b->channels[i];
    EXPECT_EQ(x.channel, y.channel);
    EXPECT_EQ(x.axis, y.axis);
    EXPECT_EQ(x.sign, y.sign);
    EXPECT_EQ(x.encoder, y.encoder);
    EXPECT_DOUBLE_EQ(x.gain, y.gain);
    EXPECT_EQ(x.offset, y.offset);
    for (auto [u, v] : {std::pair{x.minAngle, y.minAngle}, std::pair{x.maxAngle, y.maxAngle}}) {
      if (std::isfinite(u)) EXPECT_NEAR(u, v, 1e-12);
      else EXPECT_EQ(u, v);
    }
    EXPECT_NEAR(x.deadband, y.deadband, 1e-12);
    EXPECT_DOUBLE_EQ(x.smoothingMs, y.smoothingMs);
  }
  EXPECT_EQ(b->channels[1].encoder, EncoderKind::Linear);
  EXPECT_DOUBLE_EQ(b->channels[1].gain, 16384 / (1.5 * std::numbers::pi));
}

TEST(RigMap, ExamplesAreValidForTheBiped) {
  const drivers::DeviceInfo dev = device32();
  auto rig = readRigMapFile(std::string(IMPS_SOURCE_DIR) + "/examples/simple_biped.rig.json", {&biped(), &dev});
  ASSERT_TRUE(rig.has_value()) << rig.error().str();
  EXPECT_EQ(rig->channels.size(), 32u);
  auto cal = readRigMapFile(std::string(IMPS_SOURCE_DIR) + "/examples/simple_biped.calibration.json",
                            {&biped(), &dev, true});
  ASSERT_TRUE(cal.has_value()) << cal.error().str();
  ASSERT_EQ(cal->channels.size(), 32u);
  // The simulated armature's convention: mid-scale at the T-pose, one turn of 2^bits counts.
  for (const ChannelMap& c : cal->channels) {
    EXPECT_DOUBLE_EQ(*c.offset, 2048);
    EXPECT_DOUBLE_EQ(c.gain, 4096 / (2 * std::numbers::pi));
  }
  // The rig and the calibration agree on everything but the offsets.
  for (size_t i = 0; i < 32; ++i) {
    EXPECT_EQ(rig->channels[i].joint, cal->channels[i].joint);
    EXPECT_EQ(rig->channels[i].axis, cal->channels[i].axis);
    EXPECT_EQ(rig->channels[i].channel, cal->channels[i].channel);
    EXPECT_NEAR(rig->channels[i].gain, cal->channels[i].gain, 1e-9);
  }
}

TEST(RigMap, UnreadableFile) {
  auto r = readRigMapFile("/nonexistent/rig.json");
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().str(), "/nonexistent/rig.json: error: cannot read rig map: no such file\n");
}

}  // namespace
}  // namespace imps::calibration
