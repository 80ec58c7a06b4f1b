// SPDX-License-Identifier: MIT
// Tests for sim/bvh: the quirks of real BVH files, exact error messages, canonical writing and atomic saving.
#include "sim/bvh.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>

namespace imps::sim {
namespace {

namespace fs = std::filesystem;
using C = BvhChannel;

fs::path data(const std::string& name) { return fs::path(IMPS_SOURCE_DIR) / "tests/data/bvh" / name; }

std::string fileText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

BvhClip read(const std::string& name, Diagnostics* warnings = nullptr) {
  auto clip = readBvh(data(name), warnings);
  EXPECT_TRUE(clip) << clip.error().str();
  return clip ? *clip : BvhClip{};
}

const std::vector<std::string> kQuirkFiles = {"line_endings.bvh",          "channel_orders.bvh",
                                              "colon_names.bvh",           "end_joint.bvh",
                                              "frames_more_than_data.bvh", "frames_fewer_than_data.bvh",
                                              "truncated_last_frame.bvh"};

TEST(BvhRead, MixedLineEndingsTabsAndTrailingWhitespace) {
  const std::string text = fileText(data("line_endings.bvh"));
  ASSERT_NE(text.find("\r\n"), std::string::npos);  // the file really has all three kinds
  ASSERT_NE(text.find("Chest\r\t"), std::string::npos);
  Diagnostics warnings;
  const BvhClip clip = read("line_endings.bvh", &warnings);
  EXPECT_TRUE(warnings.all().empty());
  ASSERT_EQ(clip.joints.size(), 2u);
  EXPECT_EQ(clip.joints[0].name, "Hips");
  EXPECT_EQ(clip.joints[0].offset, (std::array<double, 3>{0, 1.5, -2.25}));
  EXPECT_EQ(clip.joints[1].name, "Chest");
  EXPECT_EQ(clip.joints[1].parent, 0);
  EXPECT_TRUE(clip.joints[1].hasEndSite);
  EXPECT_EQ(clip.joints[1].endSiteOffset, (std::array<double, 3>{0, 3.87, 0}));
  EXPECT_DOUBLE_EQ(clip.frameTime, 0.033333);
  ASSERT_EQ(clip.frames.size(), 2u);
  EXPECT_EQ(clip.frames[0], (std::vector<float>{1.5f, 2.5f, -3.5f, 10, 20, 30, -40, 50, -60}));
  EXPECT_EQ(clip.frames[1], (std::vector<float>{-1, -2, -3, 179.5f, -179.5f, 0.25f, 45, 90, -90}));

  // The same file with plain LF reads identically.
  std::string lf;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\r') {
      lf += '\n';
      if (i + 1 < text.size() && text[i + 1] == '\n') ++i;
    } else {
      lf += text[i];
    }
  }
  auto again = readBvhText(lf, "lf");
  ASSERT_TRUE(again) << again.error().str();
  EXPECT_EQ(*again, clip);
}

TEST(BvhRead, PerJointChannelOrdersSixChannelsEverywhereBlankLines) {
  const BvhClip clip = read("channel_orders.bvh");
  ASSERT_EQ(clip.joints.size(), 4u);
  EXPECT_EQ(clip.joints[0].channels, (std::vector<C>{C::Xposition, C::Yposition, C::Zposition, C::Zrotation,
                                                     C::Yrotation, C::Xrotation}));  // ZYX
  EXPECT_EQ(clip.joints[1].channels, (std::vector<C>{C::Xposition, C::Yposition, C::Zposition, C::Zrotation,
                                                     C::Xrotation, C::Yrotation}));  // ZXY
  EXPECT_EQ(clip.joints[2].channels, (std::vector<C>{C::Xposition, C::Yposition, C::Zposition, C::Xrotation,
                                                     C::Yrotation, C::Zrotation}));  // XYZ
  EXPECT_EQ(clip.joints[3].channels, (std::vector<C>{C::Yposition, C::Xposition, C::Zposition, C::Yrotation,
                                                     C::Xrotation, C::Zrotation}));  // YXZ
  EXPECT_EQ(clip.joints[2].parent, 1);
  EXPECT_EQ(clip.joints[3].parent, 0);  // back out of Spine/Neck to the root
  EXPECT_EQ(clip.channelCount(), 24u);
  EXPECT_EQ(clip.firstChannel(3), 18u);
  ASSERT_EQ(clip.frames.size(), 3u);
  EXPECT_FLOAT_EQ(clip.frames[2][23], 58.75f);  // (2*24+23)*1.25-30
}

TEST(BvhRead, JointNamesWithColons) {
  const BvhClip clip = read("colon_names.bvh");
  ASSERT_EQ(clip.joints.size(), 3u);
  EXPECT_EQ(clip.joints[0].name, "mixamorig:Hips");
  EXPECT_EQ(clip.joints[1].name, "mixamorig:Spine");
  EXPECT_EQ(clip.joints[2].name, "mixamorig:LeftArm");
  EXPECT_EQ(clip.joints[2].parent, 1);
  EXPECT_EQ(clip.frames.size(), 2u);
}

TEST(BvhRead, EndSiteVersusAJointNamedEnd) {
  const BvhClip clip = read("end_joint.bvh");
  ASSERT_EQ(clip.joints.size(), 3u);
  EXPECT_EQ(clip.joints[0].name, "Base");
  EXPECT_FALSE(clip.joints[0].hasEndSite);
  EXPECT_EQ(clip.joints[1].name, "End");
  EXPECT_EQ(clip.joints[1].parent, 0);
  EXPECT_EQ(clip.joints[1].channels, (std::vector<C>{C::Zrotation, C::Xrotation, C::Yrotation}));
  EXPECT_TRUE(clip.joints[1].hasEndSite);
  EXPECT_EQ(clip.joints[1].endSiteOffset, (std::array<double, 3>{0, 0, 30}));
  EXPECT_EQ(clip.joints[2].name, "End Effector");
  EXPECT_EQ(clip.joints[2].parent, 0);
  EXPECT_EQ(clip.frames.size(), 2u);
}

TEST(BvhRead, FrameCountDisagreeingWithDataUsesTheDataAndWarns) {
  Diagnostics warnings;
  BvhClip more = read("frames_more_than_data.bvh", &warnings);
  EXPECT_EQ(more.frames.size(), 3u);
  EXPECT_EQ(warnings.str(), data("frames_more_than_data.bvh").string() +
                                ":12:1: warning: 'Frames:' says 5 but 3 frames of data follow; using the data\n");
  ASSERT_EQ(warnings.all().size(), 1u);
  EXPECT_EQ(warnings.all()[0].severity, Severity::Warning);  // warnings do not make the input invalid
  EXPECT_FALSE(warnings.hasErrors());
  EXPECT_EQ(warnings.all()[0].loc.line, 12);
  EXPECT_EQ(warnings.all()[0].loc.column, 1);
  warnings = {};
  BvhClip fewer = read("frames_fewer_than_data.bvh", &warnings);
  EXPECT_EQ(fewer.frames.size(), 3u);
  EXPECT_EQ(fewer.frames[2], (std::vector<float>{7, 8, 9}));
  ASSERT_EQ(warnings.all().size(), 1u);
  EXPECT_NE(warnings.all()[0].message.find("'Frames:' says 1 but 3"), std::string::npos);

  warnings = {};
  BvhClip cut = read("truncated_last_frame.bvh", &warnings);
  EXPECT_EQ(cut.frames.size(), 2u);
  ASSERT_EQ(warnings.all().size(), 2u);
  EXPECT_EQ(warnings.all()[0].str(), data("truncated_last_frame.bvh").string() +
                                         ":16:1: warning: last frame has 2 of 3 values (file cut short?); dropped");
}

TEST(BvhRead, ErrorFilesSayWhatIsWrongAndWhere) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"missing_brace.bvh", ":3:2: error: expected '{' after joint name 'Hips', found 'OFFSET'"},
      {"bad_channel.bvh",
       ":5:23: error: expected a channel name (Xposition ... Zrotation) for joint 'Hips', found 'Wrotation'"},
      {"bad_number.bvh", ":15:3: error: expected a number in frame 2, found 'x5'"},
      {"short_frame.bvh", ":15:4: error: frame 2 has 2 values, expected 3"},
      {"long_frame.bvh", ":15:7: error: frame 2 has more than the 3 values the hierarchy's channels need"},
      {"end_without_site.bvh", ":6:2: error: expected 'Site' after 'End', found '{'"},
      {"unclosed_joint.bvh", ":9:1: error: unexpected end of file: expected '}' to close joint 'Hips'"},
      {"missing_frame_time.bvh", ":13:1: error: expected 'Frame Time:', found '1'"},
  };
  for (const auto& [file, message] : cases) {
    const fs::path path = data("errors/" + file);
    auto clip = readBvh(path);
    ASSERT_FALSE(clip) << file;
    EXPECT_EQ(clip.error().str(), path.string() + message + "\n");  // one error: the reader stops there
  }
  auto missing = readBvh(data("no_such_file.bvh"));
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().str(),
            data("no_such_file.bvh").string() + ": error: cannot open BVH file: No such file or directory\n");
}

TEST(BvhRead, InlineErrors) {
  auto expectError = [](std::string_view text, const std::string& message) {
    auto clip = readBvhText(text, "t.bvh");
    ASSERT_FALSE(clip) << text;
    EXPECT_EQ(clip.error().str(), message + "\n");
  };
  expectError("", "t.bvh:1:1: error: expected 'HIERARCHY' at the start of the file, found end of file");
  expectError("HIERARCHY\nMOTION\n", "t.bvh:2:1: error: expected 'ROOT', found 'MOTION'");
  expectError("HIERARCHY\nROOT\n{\n", "t.bvh:2:5: error: expected a joint name after 'ROOT'");
  expectError("HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 7\n",
              "t.bvh:5:10: error: expected a channel count 0..6 after 'CHANNELS', found '7'");
  expectError("HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 2 Xrotation Xrotation\n",
              "t.bvh:5:22: error: channel 'Xrotation' repeated in joint 'A'");
  expectError("HIERARCHY\nROOT A\n{\nOFFSET 0 zero 0\n",
              "t.bvh:4:10: error: expected 3 numbers after 'OFFSET', found 'zero'");
  expectError("HIERARCHY\nROOT A\n{\nCHANNELS 0\n}\n", "t.bvh:5:1: error: joint 'A' has no OFFSET");
  expectError("HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\n}\nMOTION\nFrames: 1\nFrame Time: 0.1 x\n",
              "t.bvh:8:17: error: unexpected 'x' after the frame time");
  expectError("HIERARCHY\nROOT A}B\n{\n", "t.bvh:2:7: error: expected '{' after joint name 'A', found '}'");
  // The position is kept as a position, not only as text.
  auto repeated = readBvhText("HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 2 Xrotation Xrotation\n", "t.bvh");
  ASSERT_FALSE(repeated);
  ASSERT_EQ(repeated.error().all().size(), 1u);
  EXPECT_EQ(repeated.error().errorCount(), 1);
  EXPECT_EQ(repeated.error().all()[0].loc.file, "t.bvh");
  EXPECT_EQ(repeated.error().all()[0].loc.line, 5);
  EXPECT_EQ(repeated.error().all()[0].loc.column, 22);
  EXPECT_EQ(repeated.error().all()[0].message, "channel 'Xrotation' repeated in joint 'A'");
  std::string deep = "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\n";
  for (int i = 0; i < 300; ++i) deep += "JOINT J\n{\nOFFSET 0 0 0\n";
  auto tooDeep = readBvhText(deep, "deep.bvh");
  ASSERT_FALSE(tooDeep);
  EXPECT_NE(tooDeep.error().str().find("error: joints nested more than 256 deep"), std::string::npos);
}

TEST(BvhRead, SizesAreBoundedWithAMessage) {
  const std::string header = "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n}\nMOTION\nFrames: 1\n";
  // A frame time whose timestamps (frame index * frame time, in ns) could not be represented.
  auto slow = readBvhText(header + "Frame Time: 1e308\n0\n", "t.bvh");
  ASSERT_FALSE(slow);
  EXPECT_EQ(slow.error().str(), "t.bvh:9:13: error: frame time 1e308 s is longer than the 3600 s this program accepts "
                                "(a BVH frame time is a fraction of a second, e.g. 0.0083333)\n");
  // More frames than the reader keeps: 2^20 (2.4 hours at 120 fps).
  std::string many = header + "Frame Time: 0.01\n";
  for (size_t f = 0; f <= (size_t{1} << 20); ++f) many += "0\n";
  auto tooMany = readBvhText(many, "t.bvh");
  ASSERT_FALSE(tooMany);
  EXPECT_EQ(tooMany.error().str(), "t.bvh:1048586:1: error: more than 1048576 frames (2 hours at 120 fps), the most "
                                   "this program reads: split the clip\n");
}

TEST(BvhRead, AnEndlessFileIsRefusedAtTheLimit) {
  // /dev/zero never ends: the reader stops at its limit instead of filling memory.
  auto endless = readBvh("/dev/zero");
  ASSERT_FALSE(endless);
  EXPECT_EQ(endless.error().str(), "/dev/zero: error: cannot read BVH file: larger than the 256 MiB limit "
                                   "(IMPS_MAX_INPUT_MIB=N raises it)\n");
}

TEST(BvhRead, LenientAboutCaseColonsBomAndJointNamesWithSpaces) {
  const std::string text =
      "\xEF\xBB\xBFhierarchy\nroot My Hips {\n offset 1 2 3\n channels 3 ZROTATION xrotation Yrotation\n}\n"
      "motion\nFrames:2\nFrame Time : +0.5\n1 2 3\n\n4 5 6";
  auto clip = readBvhText(text);
  ASSERT_TRUE(clip) << clip.error().str();
  EXPECT_EQ(clip->joints[0].name, "My Hips");
  EXPECT_EQ(clip->joints[0].channels, (std::vector<C>{C::Zrotation, C::Xrotation, C::Yrotation}));
  EXPECT_EQ(clip->frameTime, 0.5);
  EXPECT_EQ(clip->frames.size(), 2u);
}

TEST(BvhWrite, WriteThenReadReproducesEveryQuirkFile) {
  for (const auto& file : kQuirkFiles) {
    SCOPED_TRACE(file);
    const BvhClip clip = read(file);
    const auto written = writeBvh(clip);
    ASSERT_TRUE(written) << written.error().str();
    const std::string& text = *written;
    auto back = readBvhText(text, "written");
    ASSERT_TRUE(back) << back.error().str();
    EXPECT_EQ(*back, clip);
    EXPECT_EQ(writeBvh(*back).value(), text);  // canonical: a fixed point
    EXPECT_EQ(text.find('\r'), std::string::npos);
  }
}

TEST(BvhWrite, CanonicalText) {
  BvhClip clip;
  clip.joints.push_back({"Root", -1, {0, 1.5, 0}, {C::Xposition, C::Yposition, C::Zposition, C::Zrotation}, false, {}});
  clip.joints.push_back({"A", 0, {0.1, 0, 0}, {C::Zrotation}, true, {0, 2, 0}});
  clip.joints.push_back({"B", 0, {-0.1, 0, 0}, {}, true, {0, -2, 0}});
  clip.frameTime = 1.0 / 30;
  clip.frames = {{0.1f, 2, -3, 45.5f, -0.25f}};
  EXPECT_EQ(
      writeBvh(clip).value(),
      "HIERARCHY\nROOT Root\n{\n\tOFFSET 0 1.5 0\n\tCHANNELS 4 Xposition Yposition Zposition Zrotation\n"
      "\tJOINT A\n\t{\n\t\tOFFSET 0.1 0 0\n\t\tCHANNELS 1 Zrotation\n\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 2 0\n"
      "\t\t}\n\t}\n\tJOINT B\n\t{\n\t\tOFFSET -0.1 0 0\n\t\tCHANNELS 0\n\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 -2 0\n"
      "\t\t}\n\t}\n}\nMOTION\nFrames: 1\nFrame Time: 0.03333333333333333\n0.1 2 -3 45.5 -0.25\n");
}

TEST(BvhWrite, AClipThatCannotBeWrittenIsAnErrorNotAnException) {
  BvhClip clip;
  clip.joints.push_back({"Root", -1, {0, 0, 0}, {C::Zrotation}, false, {}});
  clip.joints.push_back({"A", 0, {0.1, 0, 0}, {C::Zrotation}, true, {0, 2, 0}});
  clip.frameTime = 1.0 / 30;
  clip.frames = {{1, 2}};
  ASSERT_TRUE(writeBvh(clip));
  // Each problem is one error without a location (the clip is not a file), naming the joint or frame.
  auto refused = [](const BvhClip& bad) {
    const auto text = writeBvh(bad);
    if (text) return std::string("written");
    EXPECT_EQ(text.error().errorCount(), 1);
    EXPECT_EQ(text.error().all().front().loc.file, "");
    return text.error().all().front().message;
  };
  BvhClip badParent = clip;
  badParent.joints[1].parent = 1;  // its own parent
  EXPECT_EQ(refused(badParent), "cannot write BVH: joint 'A' has a bad parent index");
  BvhClip badOrder = clip;
  badOrder.joints.push_back({"B", 0, {0, 0, 0}, {}, false, {}});
  badOrder.joints.push_back({"C", 1, {0, 0, 0}, {}, false, {}});  // A's child after A's subtree was closed
  EXPECT_EQ(refused(badOrder), "cannot write BVH: joints are not in depth-first order at 'C'");
  BvhClip badName = clip;
  badName.joints[1].name = "A{";
  EXPECT_EQ(refused(badName), "cannot write BVH: joint name 'A{' cannot be written");
  BvhClip badFrame = clip;
  badFrame.frames.push_back({3});
  EXPECT_EQ(refused(badFrame), "cannot write BVH: frame 1 has 1 values for 2 channels");
  // saveBvh puts the problem at the file and writes nothing.
  const fs::path target = fs::temp_directory_path() / ("imps_bvh_refused_" + std::to_string(::getpid()) + ".bvh");
  const auto saved = saveBvh(target, badFrame);
  ASSERT_FALSE(saved);
  EXPECT_EQ(saved.error().str(), target.string() + ": error: cannot write BVH: frame 1 has 1 values for 2 channels\n");
  EXPECT_FALSE(fs::exists(target));
}

TEST(BvhWrite, SaveIsAtomicAndReplaces) {
  const fs::path dir = fs::temp_directory_path() / ("imps_bvh_save_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const BvhClip clip = read("channel_orders.bvh");
  std::ofstream(dir / "out.bvh") << "old contents";
  fs::permissions(dir / "out.bvh", fs::perms::owner_read | fs::perms::owner_write);  // a private take stays private
  ASSERT_TRUE(saveBvh(dir / "out.bvh", clip));
  EXPECT_EQ(fs::status(dir / "out.bvh").permissions(), fs::perms::owner_read | fs::perms::owner_write);
  auto back = readBvh(dir / "out.bvh");
  ASSERT_TRUE(back) << back.error().str();
  EXPECT_EQ(*back, clip);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  auto nowhere = saveBvh(dir / "missing_dir" / "x.bvh", clip);
  ASSERT_FALSE(nowhere);
  const std::string target = (dir / "missing_dir" / "x.bvh").string();
  EXPECT_EQ(nowhere.error().firstError(),
            target + ": error: cannot save '" + target + "': creating a temporary file: No such file or directory");
  EXPECT_EQ(nowhere.error().errorCount(), 1);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace imps::sim
