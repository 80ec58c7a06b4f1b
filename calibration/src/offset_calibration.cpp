// SPDX-License-Identifier: MIT
// Offsets from a window held in the calibration pose (circular mean, noise rejection), and the check-pose test of
// signs and gains.
#include "calibration/offset_calibration.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>

#include "json_document.h"
#include "object_reader.h"

namespace imps::calibration {

using detail::JsonValue;
using detail::kDegree;
using detail::ObjectReader;

namespace {

std::string fixed(double v, int digits = 1) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

}  // namespace

WindowAverage averageWindow(const RigMap& map, std::span<const drivers::Sample> samples, const WindowOptions& options) {
  WindowAverage out;
  if (samples.empty()) out.problems.push_back("the window holds no samples");
  const double turn = map.countsPerTurn();
  std::vector<double> values;
  for (size_t i = 0; i < map.channels.size(); ++i) {
    const ChannelMap& c = map.channels[i];
    ChannelAverage avg;
    avg.mapping = i;
    avg.label = map.channelLabel(i, options.device);
    values.clear();
    for (const drivers::Sample& s : samples) {
      if (c.channel < 0 || c.channel >= s.channelCount) continue;
      const auto ch = static_cast<size_t>(c.channel);
      if (s.flags[ch] != drivers::ChannelFlag::Valid) continue;
      values.push_back(static_cast<double>(s.counts[ch]));
    }
    avg.samples = values.size();
    if (!values.empty()) {
      // Pass 1: a centre that is right across the wrap (circular mean for absolute encoders).
      double centre = values[0];
      if (c.encoder == EncoderKind::Absolute) {
        double sx = 0, sy = 0;
        for (double v : values) {
          const double phi = 2 * std::numbers::pi * v / turn;
          sx += std::cos(phi);
          sy += std::sin(phi);
        }
        centre = std::atan2(sy, sx) / (2 * std::numbers::pi) * turn;
      }
      // Pass 2: mean and spread of the (shortest) differences from that centre, so a tight window averages exactly.
      double sum = 0;
      for (double v : values) sum += countDelta(v, centre, turn, c.encoder);
      const double meanDelta = sum / static_cast<double>(values.size());
      double sq = 0;
      for (double v : values) {
        const double d = countDelta(v, centre, turn, c.encoder) - meanDelta;
        sq += d * d;
      }
      avg.mean = centre + meanDelta;
      if (c.encoder == EncoderKind::Absolute) {
        avg.mean = std::fmod(avg.mean, turn);
        if (avg.mean < 0) avg.mean += turn;
        if (avg.mean >= turn) avg.mean = 0;  // -1e-13 + turn rounds to turn: that is count 0
      }
      avg.stdDev = std::sqrt(sq / static_cast<double>(values.size()));
      avg.stdDevRadians = c.gain > 0 ? avg.stdDev / c.gain : 0;
    }
    if (!samples.empty() && avg.samples < options.minSamples) {
      out.problems.push_back(avg.label + " (" + c.joint + " " + toString(c.axis) + "): only " +
                             std::to_string(avg.samples) + " valid readings in the window (need " +
                             std::to_string(options.minSamples) + "); is it connected?");
    } else if (avg.stdDevRadians > options.maxStdDev) {
      out.problems.push_back(avg.label + " (" + c.joint + " " + toString(c.axis) +
                             ") is too noisy: standard deviation " + fixed(avg.stdDevRadians / kDegree, 2) + " deg (" +
                             fixed(avg.stdDev, 1) + " counts) > " + fixed(options.maxStdDev / kDegree, 2) +
                             " deg; hold the armature still, or check the encoder");
    }
    out.channels.push_back(std::move(avg));
  }
  return out;
}

std::expected<RigMap, Diagnostics> calibrateOffsets(RigMap map, std::span<const drivers::Sample> samples,
                                                    const WindowOptions& options, WindowAverage* report) {
  WindowAverage w = averageWindow(map, samples, options);
  if (!w.ok()) {
    Diagnostics problems;
    for (const std::string& p : w.problems) problems.error({}, p);
    if (report) *report = std::move(w);
    return std::unexpected(std::move(problems));
  }
  for (const ChannelAverage& a : w.channels) map.channels[a.mapping].offset = a.mean;
  if (report) *report = std::move(w);
  return map;
}

std::expected<std::vector<PoseTarget>, Diagnostics> parseCheckPose(std::string_view json, std::string_view fileName,
                                                                   const Character* character) {
  Diagnostics diags;
  JsonValue root;
  if (!detail::parseJson(json, fileName, root, diags)) return std::unexpected(diags);
  if (root.kind != JsonValue::Kind::Object) {
    diags.error(root.loc, std::string("a check pose must be a JSON object, not ") + detail::describe(root.kind));
    return std::unexpected(diags);
  }
  ObjectReader r(root, "the check pose", {"version", "pose", "joints"}, diags);
  if (const JsonValue* v = r.typed("version", JsonValue::Kind::Number, "a number")) {
    if (v->number > kRigMapVersion)
      diags.error(v->loc, "file format version " + detail::integerText(v->number) +
                              " is newer than this program reads (" + std::to_string(kRigMapVersion) + ")");
  } else if (!r.get("version")) {
    r.missing("version");
  }
  r.typed("pose", JsonValue::Kind::String, "a string");
  std::vector<PoseTarget> targets;
  std::vector<std::string> jointNames;
  if (character)
    for (const Joint& j : character->joints()) jointNames.push_back(j.name);
  if (const JsonValue* joints = r.typed("joints", JsonValue::Kind::Object, "an object")) {
    for (const JsonValue::Member& m : joints->members) {
      if (character && character->findJoint(m.key) < 0) {
        std::string message = "unknown joint '" + m.key + "'";
        const std::string guess = closestMatch(m.key, jointNames);
        if (!guess.empty()) message += "; did you mean '" + guess + "'?";
        diags.error(m.keyLoc, message);
      }
      if (m.value.kind != JsonValue::Kind::Object) {
        diags.error(m.value.loc, "the targets of joint '" + m.key + "' must be an object like {\"y_deg\": 90}");
        continue;
      }
      ObjectReader jr(m.value, "the targets of joint '" + m.key + "'", {"x", "y", "z", "x_deg", "y_deg", "z_deg"},
                      diags);
      for (Axis axis : {Axis::X, Axis::Y, Axis::Z}) {
        SourceLoc loc;
        if (auto a = jr.angle(toString(axis), &loc)) targets.push_back({m.key, axis, *a, loc});
      }
    }
  } else if (!r.get("joints")) {
    r.missing("joints");
  }
  if (diags.hasErrors()) return std::unexpected(diags);
  return targets;
}

std::expected<std::vector<PoseTarget>, Diagnostics> readCheckPoseFile(const std::filesystem::path& path,
                                                                      const Character* character) {
  auto text = detail::readJsonFileText(path, "check pose");
  if (!text) return std::unexpected(text.error());
  return parseCheckPose(*text, path.string(), character);
}

PoseCheck checkPose(const Calibration& calibration, const WindowAverage& window, std::span<const PoseTarget> targets,
                    const CheckOptions& options) {
  PoseCheck out;
  const RigMap& map = calibration.rigMap();
  for (const PoseTarget& t : targets) {
    int mapping = -1;
    for (size_t i = 0; i < map.channels.size(); ++i)
      if (map.channels[i].joint == t.joint && map.channels[i].axis == t.axis &&
          !map.channels[i].translation) mapping = static_cast<int>(i);
    const std::string what = t.joint + " " + toString(t.axis);
    if (mapping < 0) {
      out.warnings.push_back("no channel drives " + what + "; its target is ignored");
      continue;
    }
    const auto m = static_cast<size_t>(mapping);
    if (std::abs(t.angle) < options.minTarget) {
      out.warnings.push_back(what + ": target " + fixed(t.angle / kDegree) + " deg is too small to check (need " +
                             fixed(options.minTarget / kDegree) + " deg or more)");
      continue;
    }
    const ChannelAverage* avg = nullptr;
    for (const ChannelAverage& a : window.channels)
      if (a.mapping == m) avg = &a;
    if (!avg || avg->samples == 0) {
      out.warnings.push_back(what + ": no readings in the check window");
      continue;
    }
    ChannelCheck c;
    c.mapping = m;
    c.label = avg->label;
    c.target = t.angle;
    c.measured = calibration.rawAngle(m, avg->mean);
    c.ratio = c.measured / c.target;
    c.reversed = c.ratio < 0;
    c.misScaled = std::abs(std::abs(c.ratio) - 1.0) > options.gainTolerance;
    c.suggestedGain = map.channels[m].gain * std::abs(c.ratio);
    const std::string reading = c.label + " (" + what + ") reads " + fixed(c.measured / kDegree) +
                                " deg for a target of " + fixed(c.target / kDegree) + " deg: ";
    if (c.reversed && !c.misScaled)
      out.problems.push_back(reading + "looks reversed; set \"sign\": " + std::to_string(-map.channels[m].sign));
    else if (c.reversed)
      out.problems.push_back(reading + "looks reversed and mis-scaled; set \"sign\": " +
                             std::to_string(-map.channels[m].sign) + " and \"gain\": " + fixed(c.suggestedGain, 3));
    else if (c.misScaled)
      out.problems.push_back(reading + "looks mis-scaled (off by " + fixed((std::abs(c.ratio) - 1) * 100, 0) +
                             "%); set \"gain\": " + fixed(c.suggestedGain, 3));
    out.channels.push_back(std::move(c));
  }
  return out;
}

}  // namespace imps::calibration
