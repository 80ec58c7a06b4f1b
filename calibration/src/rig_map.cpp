// SPDX-License-Identifier: MIT
// Rig map / calibration files: parsing with source locations, validation against a character and a device,
// writing (nlohmann-json) and atomic saves.
#include "calibration/rig_map.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>
#include <sstream>
#include <map>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "imps/utf8.h"
#include "json_document.h"
#include "object_reader.h"

namespace imps::calibration {

using detail::JsonValue;
using detail::ObjectReader;
using detail::kDegree;

const char* toString(Axis axis) {
  switch (axis) {
    case Axis::X: return "x";
    case Axis::Y: return "y";
    case Axis::Z: return "z";
  }
  return "?";
}

int RigMap::findChannel(int channel) const {
  for (size_t i = 0; i < channels.size(); ++i)
    if (channels[i].channel == channel) return static_cast<int>(i);
  return -1;
}

std::string RigMap::channelLabel(size_t mapping, const drivers::DeviceInfo* dev) const {
  const ChannelMap& c = channels[mapping];
  std::string name = c.channelName;
  if (name.empty() && dev && c.channel >= 0 && static_cast<size_t>(c.channel) < dev->channelNames.size())
    name = dev->channelNames[static_cast<size_t>(c.channel)];
  std::string label = c.channel >= 0 ? "channel " + std::to_string(c.channel) : "channel";
  if (!name.empty()) label += " '" + name + "'";
  return label;
}

namespace {


std::string channelText(const ChannelMap& c) {
  return c.channelName.empty() ? "channel " + std::to_string(c.channel) : "channel '" + c.channelName + "'";
}

// Value checks for one channel, each reported at `at(field)`.
template <typename LocFn>
void checkChannelValues(const ChannelMap& c, int bits, LocFn at, Diagnostics& diags) {
  if (c.sign != 1 && c.sign != -1) diags.error(at("sign"), "'sign' must be 1 or -1, not " + std::to_string(c.sign));
  const char* per = c.translation ? "metre" : "radian";
  if (!(std::isfinite(c.gain) && c.gain > 0))
    diags.error(at("gain"), std::string("gain must be a positive number of counts per ") + per + " (got " +
                                std::to_string(c.gain) + ")");
  const double unit = c.translation ? 1.0 : kDegree;
  const char* unitName = c.translation ? " m" : " deg";
  if (std::isnan(c.minAngle) || std::isnan(c.maxAngle)) diags.error(at("min"), "limits must not be NaN");
  else if (c.minAngle > c.maxAngle)
    diags.error(at("max"), "'max' (" + std::to_string(c.maxAngle / unit) + unitName + ") is below 'min' (" +
                               std::to_string(c.minAngle / unit) + unitName + ")");
  if (!(c.deadband >= 0) || !std::isfinite(c.deadband))
    diags.error(at("deadband"), std::string("deadband must be >= 0 ") + per + "s (got " + std::to_string(c.deadband) +
                                    ")");
  if (!(c.smoothingMs >= 0) || !std::isfinite(c.smoothingMs))
    diags.error(at("smoothing_ms"), "smoothing_ms must be >= 0 (got " + std::to_string(c.smoothingMs) + ")");
  if (c.offset) {
    const double turn = static_cast<double>(uint64_t{1} << bits);
    if (!std::isfinite(*c.offset)) diags.error(at("offset"), "offset must be a finite number of counts");
    else if (c.encoder == EncoderKind::Absolute && (*c.offset < 0 || *c.offset >= turn))
      diags.error(at("offset"), "offset " + std::to_string(*c.offset) + " is outside the encoder's counts [0, " +
                                    std::to_string(uint64_t{1} << bits) + ")");
  }
}

// Checks that need the whole map or the context: duplicates, orders, joints, device channels, offsets.
void checkMap(RigMap& map, const RigMapContext& ctx, Diagnostics& diags) {
  if (ctx.device && ctx.device->bitsPerChannel != map.bits)
    diags.error(map.bitsLoc, "the rig map is for " + std::to_string(map.bits) + "-bit encoders but the device '" +
                                 ctx.device->name + "' reports " + std::to_string(ctx.device->bitsPerChannel) +
                                 " bits per channel");
  // The devices channels live on: a session's, else the one device.
  std::vector<const drivers::DeviceInfo*> devices;
  for (const drivers::DeviceInfo& d : ctx.devices) devices.push_back(&d);
  if (ctx.devices.empty() && ctx.device) devices.push_back(ctx.device);
  auto deviceText = [&](size_t d) {
    return devices.size() > 1 ? "device " + std::to_string(d) + " '" + devices[d]->name + "'"
                              : "device '" + devices[d]->name + "'";
  };
  auto channelOn = [&](size_t d, const std::string& name) {
    const auto& names = devices[d]->channelNames;
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? -1 : static_cast<int>(it - names.begin());
  };
  for (ChannelMap& c : map.channels) {
    if (devices.empty()) continue;  // resolved later; Calibration requires indices
    if (static_cast<size_t>(c.device) >= devices.size()) {
      diags.error(c.deviceLoc, "device " + std::to_string(c.device) + " does not exist: the session has " +
                                   std::to_string(devices.size()) + " device" + (devices.size() == 1 ? "" : "s"));
      c.channel = -1;
      continue;
    }
    if (c.channelName.empty()) continue;
    // Channel names → indices: on the channel's device, else (no "device" given) on whichever device has it.
    int found = channelOn(static_cast<size_t>(c.device), c.channelName);
    for (size_t d = 0; found < 0 && d < devices.size(); ++d) {
      const int there = channelOn(d, c.channelName);
      if (there < 0) continue;
      if (c.deviceLoc.line == 0) {
        c.device = static_cast<int>(d), found = there;
      } else {
        diags.error(c.loc, deviceText(static_cast<size_t>(c.device)) + " has no channel named '" + c.channelName +
                               "'; " + deviceText(d) + " has it: write \"device\": " + std::to_string(d));
        found = -2;
      }
    }
    if (found == -1) {
      std::string message = deviceText(static_cast<size_t>(c.device)) + " has no channel named '" + c.channelName + "'";
      if (devices.size() > 1 && c.deviceLoc.line == 0)
        message = "no device of the session has a channel named '" + c.channelName + "'";
      std::string guess;
      size_t guessDevice = 0;
      for (size_t d = 0; d < devices.size() && guess.empty(); ++d)
        if (c.deviceLoc.line == 0 || d == static_cast<size_t>(c.device))
          guess = closestMatch(c.channelName, devices[d]->channelNames), guessDevice = d;
      if (!guess.empty())
        message +=
            "; did you mean '" + guess + "'" + (devices.size() > 1 ? " (" + deviceText(guessDevice) + ")" : "") + "?";
      diags.error(c.loc, message);
    }
    c.channel = found < 0 ? -1 : found;
  }
  std::map<std::pair<int, int>, size_t> byIndex;          // (device, channel index) -> its first mapping
  std::map<std::pair<int, std::string>, size_t> byName;   // (device, unresolved channel name) -> its first mapping
  for (size_t i = 0; i < map.channels.size(); ++i) {
    const ChannelMap& c = map.channels[i];
    const drivers::DeviceInfo* own =
        static_cast<size_t>(c.device) < devices.size() ? devices[static_cast<size_t>(c.device)] : nullptr;
    if (own && c.channel >= own->channelCount)
      diags.error(c.loc, "channel " + std::to_string(c.channel) + " is out of range: " +
                             deviceText(static_cast<size_t>(c.device)) + " has " + std::to_string(own->channelCount) +
                             " channels (0.." + std::to_string(own->channelCount - 1) + ")");
    if (c.channel >= drivers::kMaxChannels)
      diags.error(c.loc, "channel " + std::to_string(c.channel) + " is out of range: armatures have at most " +
                             std::to_string(drivers::kMaxChannels) + " channels (0.." +
                             std::to_string(drivers::kMaxChannels - 1) + ")");
    // The first mapping of the same channel (by index, or by name while unresolved), found by hash: linear time.
    size_t first = i;
    if (c.channel >= 0) first = byIndex.try_emplace({c.device, c.channel}, i).first->second;
    else if (!c.channelName.empty()) first = byName.try_emplace({c.device, c.channelName}, i).first->second;
    if (first != i) {
      const ChannelMap& o = map.channels[first];
      diags.error(c.loc, channelText(c) + " is mapped twice: it already drives " + o.joint + " " + toString(o.axis) +
                             " (line " + std::to_string(o.loc.line) + ")");
    }
    if (ctx.requireOffsets && !c.offset)
      diags.error(c.loc, "missing field 'offset' for " + channelText(c) +
                             ": a calibration needs every channel's offset (run `puppeteer calibrate`)");
  }
  std::vector<std::string> jointNames;
  if (ctx.character)
    for (const Joint& j : ctx.character->joints()) jointNames.push_back(j.name);
  std::unordered_map<std::string, size_t> jointEntries;  // joint name -> its first entry
  for (size_t ji = 0; ji < map.joints.size(); ++ji) {
    const JointMap& jm = map.joints[ji];
    if (const auto [first, fresh] = jointEntries.try_emplace(jm.joint, ji); !fresh)
      diags.error(jm.loc, "joint '" + jm.joint + "' is listed twice (first at line " +
                              std::to_string(map.joints[first->second].loc.line) +
                              "): put all its channels in one entry");
    if (ctx.character && ctx.character->findJoint(jm.joint) < 0) {
      std::string message = "unknown joint '" + jm.joint + "'";
      const std::string guess = closestMatch(jm.joint, jointNames);
      if (!guess.empty()) message += "; did you mean '" + guess + "'?";
      diags.error(jm.loc, message);
    }
  }
}

// Where a channel's scale and limit values are in the file, for messages about them.
struct ScaleLocs {
  SourceLoc range, min, max, deadband;
};

// Rotation channels: gain explicit, or from the range the full 2^bits counts cover, or (absolute encoders) one
// full turn; limits and deadband in radians or degrees.
void parseRotationScale(const ObjectReader& r, int bits, ChannelMap& c, ScaleLocs& at, Diagnostics& diags) {
  const std::optional<double> gain = r.number("gain");
  const std::optional<double> range = r.angle("range", &at.range);
  const double turn = static_cast<double>(uint64_t{1} << bits);
  if (r.get("metres_per_count"))
    diags.error(r.locOf("metres_per_count"), "'metres_per_count' is for translation axes (tx, ty, tz)");
  if (r.get("gain") && (r.get("range") || r.get("range_deg"))) {
    diags.error(r.locOf("gain"), "give either 'gain' (counts per radian) or 'range'/'range_deg', not both");
  } else if (gain) {
    c.gain = *gain;
  } else if (range) {
    if (!(*range > 0)) diags.error(at.range, "the range must be positive");
    else c.gain = turn / *range;
  } else if (!r.get("gain") && !r.get("range") && !r.get("range_deg")) {
    if (c.encoder == EncoderKind::Absolute) c.gain = turn / (2 * std::numbers::pi);
    else r.missing("gain' (or 'range_deg'; a linear sensor has no natural full scale)");
  }
  if (auto m = r.angle("min", &at.min)) c.minAngle = *m;
  if (auto m = r.angle("max", &at.max)) c.maxAngle = *m;
  if (auto d = r.angle("deadband", &at.deadband)) c.deadband = *d;
}

// Translation channels: 'metres_per_count' (or 'gain' in counts per metre), limits and deadband in metres.
void parseTranslationScale(const ObjectReader& r, ChannelMap& c, ScaleLocs& at, Diagnostics& diags) {
  for (const char* degrees : {"range", "range_deg", "min_deg", "max_deg", "deadband_deg"})
    if (r.get(degrees))
      diags.error(r.locOf(degrees), std::string("'") + degrees + "' is for rotation axes: a translation axis takes "
                                    "'metres_per_count' and 'min'/'max'/'deadband' in metres");
  const std::optional<double> gain = r.number("gain");
  const std::optional<double> metres = r.number("metres_per_count");
  at.range = r.locOf("metres_per_count");
  if (r.get("gain") && r.get("metres_per_count")) {
    diags.error(r.locOf("gain"), "give either 'gain' (counts per metre) or 'metres_per_count', not both");
  } else if (gain) {
    c.gain = *gain;
  } else if (metres) {
    if (!(*metres > 0) || !std::isfinite(*metres)) diags.error(at.range, "'metres_per_count' must be positive");
    else c.gain = 1.0 / *metres;
  } else if (!r.get("gain") && !r.get("metres_per_count")) {
    r.missing("metres_per_count' (a translation axis has no natural full scale)");
  }
  at.min = r.locOf("min"), at.max = r.locOf("max"), at.deadband = r.locOf("deadband");
  if (auto m = r.number("min")) c.minAngle = *m;
  if (auto m = r.number("max")) c.maxAngle = *m;
  if (auto d = r.number("deadband")) c.deadband = *d;
}

// Parses one channel object of a joint entry.
void parseChannel(const JsonValue& v, const std::string& joint, int bits, RigMap& map, Diagnostics& diags) {
  if (v.kind != JsonValue::Kind::Object) {
    diags.error(v.loc, std::string("a channel must be an object, not ") + detail::describe(v.kind));
    return;
  }
  static const std::vector<std::string> kKeys = {
      "channel", "axis",     "sign",         "gain",         "range",       "range_deg", "offset",  "min", "min_deg",
      "max",     "max_deg",  "deadband",     "deadband_deg", "smoothing_ms", "encoder", "metres_per_count",
      "device"};
  const size_t errorsBefore = static_cast<size_t>(diags.errorCount());
  ObjectReader r(v, "a channel of joint '" + joint + "'", kKeys, diags);
  ChannelMap c;
  c.joint = joint;
  c.loc = v.loc;
  if (const JsonValue* ch = r.get("channel")) {
    c.loc = ch->loc;
    if (ch->kind == JsonValue::Kind::String) {
      c.channelName = ch->string;
      if (c.channelName.empty()) diags.error(ch->loc, "'channel' name must not be empty");
    } else if (ch->kind == JsonValue::Kind::Number && ch->integral && ch->number >= 0 && ch->number < 1e6) {
      c.channel = static_cast<int>(ch->number);
    } else {
      diags.error(ch->loc, "'channel' must be a channel index (0, 1, …) or a device channel name");
    }
  } else {
    r.missing("channel");
  }
  if (const JsonValue* d = r.get("device")) {
    if (d->kind == JsonValue::Kind::Number && d->integral && d->number >= 0 && d->number < 65536) {
      c.device = static_cast<int>(d->number);
      c.deviceLoc = d->loc;
    } else {
      diags.error(d->loc, "'device' must be a device index (0, 1, …) of the session");
    }
  }
  if (const JsonValue* a = r.typed("axis", JsonValue::Kind::String, "a string")) {
    std::string name = a->string;
    for (char& ch : name) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    c.translation = name.size() == 2 && name[0] == 't';
    if (c.translation) name.erase(0, 1);
    if (name == "x") c.axis = Axis::X;
    else if (name == "y") c.axis = Axis::Y;
    else if (name == "z") c.axis = Axis::Z;
    else diags.error(a->loc, "bad axis '" + a->string + "': expected 'x', 'y' or 'z' (rotations) or 'tx', 'ty' or 'tz' "
                             "(translations)");
  } else if (!r.get("axis")) {
    r.missing("axis");
  }
  if (const JsonValue* s = r.typed("sign", JsonValue::Kind::Number, "a number")) {
    if (s->number == 1 || s->number == -1) c.sign = static_cast<int>(s->number);
    else diags.error(s->loc, "'sign' must be 1 or -1");
  } else if (!r.get("sign")) {
    r.missing("sign");
  }
  if (const JsonValue* e = r.typed("encoder", JsonValue::Kind::String, "a string")) {
    if (e->string == "absolute") c.encoder = EncoderKind::Absolute;
    else if (e->string == "linear") c.encoder = EncoderKind::Linear;
    else diags.error(e->loc, "bad encoder '" + e->string + "': expected 'absolute' or 'linear'");
  } else if (c.translation) {
    c.encoder = EncoderKind::Linear;  // a slide or string potentiometer does not wrap
  }
  ScaleLocs at{r.loc(), r.loc(), r.loc(), r.loc()};
  if (c.translation) parseTranslationScale(r, c, at, diags);
  else parseRotationScale(r, bits, c, at, diags);
  if (r.get("offset")) c.offset = r.number("offset");
  if (auto s = r.number("smoothing_ms")) c.smoothingMs = *s;
  if (static_cast<size_t>(diags.errorCount()) == errorsBefore) {
    checkChannelValues(
        c, bits,
        [&](std::string_view field) -> SourceLoc {
          if (field == "min") return at.min;
          if (field == "max") return at.max;
          if (field == "deadband") return at.deadband;
          if (field == "gain" && !r.get("gain")) return at.range;
          return r.locOf(field);
        },
        diags);
  }
  map.channels.push_back(std::move(c));
}

void parseJoint(const JsonValue& v, RigMap& map, Diagnostics& diags) {
  if (v.kind != JsonValue::Kind::Object) {
    diags.error(v.loc, std::string("a joint entry must be an object, not ") + detail::describe(v.kind));
    return;
  }
  ObjectReader r(v, "a joint entry", {"joint", "order", "channels"}, diags);
  JointMap jm;
  jm.loc = v.loc;
  if (const JsonValue* name = r.typed("joint", JsonValue::Kind::String, "a string")) {
    jm.joint = name->string;
    jm.loc = name->loc;
  } else if (!r.get("joint")) {
    r.missing("joint");
    return;
  } else {
    return;
  }
  const size_t first = map.channels.size();
  if (const JsonValue* chans = r.typed("channels", JsonValue::Kind::Array, "an array")) {
    if (chans->items.empty()) diags.error(chans->loc, "joint '" + jm.joint + "' has no channels");
    for (const JsonValue& c : chans->items) parseChannel(c, jm.joint, map.bits, map, diags);
  } else if (!r.get("channels")) {
    r.missing("channels");
  }
  for (size_t i = first; i < map.channels.size(); ++i) jm.mappings.push_back(i);
  // The composition order must name exactly the driven axes.
  std::string used, moved;  // rotation axes, translation axes
  for (size_t i : jm.mappings) {
    const ChannelMap& c = map.channels[i];
    const char a = static_cast<char>('X' + static_cast<int>(c.axis));
    std::string& seen = c.translation ? moved : used;
    if (seen.find(a) != std::string::npos) {
      diags.error(c.loc, "joint '" + jm.joint + "' axis " + (c.translation ? "t" : "") + toString(c.axis) +
                             " is driven by two channels");
    }
    seen += a;
  }
  if (const JsonValue* order = r.typed("order", JsonValue::Kind::String, "a string")) {
    std::string o;
    for (char ch : order->string) o += static_cast<char>(ch >= 'a' && ch <= 'z' ? ch - 'a' + 'A' : ch);
    bool ok = o.size() == used.size() && !o.empty();
    for (char a : used) ok = ok && std::count(o.begin(), o.end(), a) == 1;
    if (!ok)
      diags.error(order->loc, "order '" + order->string + "' of joint '" + jm.joint +
                                  "' must list each driven axis once (driven: " + (used.empty() ? "none" : used) + ")");
    jm.order = o;
  } else if (!r.get("order")) {
    if (used.size() > 1)
      diags.error(jm.loc, "joint '" + jm.joint + "' is driven on " + std::to_string(used.size()) +
                              " axes: add \"order\" (e.g. \"" + used + "\") to say how they compose");
    jm.order = used;
  }
  map.joints.push_back(std::move(jm));
}

}  // namespace

std::expected<RigMap, Diagnostics> parseRigMap(std::string_view json, std::string_view fileName,
                                               const RigMapContext& context, Diagnostics* warnings) {
  Diagnostics diags;
  JsonValue root;
  if (!detail::parseJson(json, fileName, root, diags)) return std::unexpected(diags);
  if (root.kind != JsonValue::Kind::Object) {
    diags.error(root.loc, std::string("a rig map must be a JSON object, not ") + detail::describe(root.kind));
    return std::unexpected(diags);
  }
  RigMap map;
  map.file = std::string(fileName);
  // The version first: a newer file may mean anything, so nothing else is reported for it.
  const JsonValue* version = root.find("version");
  if (!version) {
    diags.error(root.loc, "missing field 'version' (this program writes \"version\": " +
                              std::to_string(kRigMapVersion) + ")");
    return std::unexpected(diags);
  }
  if (version->kind != JsonValue::Kind::Number || !version->integral || version->number < 1) {
    diags.error(version->loc, "'version' must be a positive integer");
    return std::unexpected(diags);
  }
  if (version->number > kRigMapVersion) {
    diags.error(version->loc, "file format version " + detail::integerText(version->number) +
                                  " is newer than this program reads (" + std::to_string(kRigMapVersion) +
                                  "); update puppeteer");
    return std::unexpected(diags);
  }
  ObjectReader r(root, "the rig map", {"version", "bits", "device", "joints", "info"}, diags);
  if (const JsonValue* bits = r.typed("bits", JsonValue::Kind::Number, "a number")) {
    map.bitsLoc = bits->loc;
    if (!bits->integral || bits->number < 1 || bits->number > 32) {
      diags.error(bits->loc, "'bits' must be an integer from 1 to 32");
      return std::unexpected(diags);
    }
    map.bits = static_cast<int>(bits->number);
  } else {
    if (!r.get("bits")) r.missing("bits");
    return std::unexpected(diags);
  }
  if (const JsonValue* dev = r.typed("device", JsonValue::Kind::String, "a string")) map.device = dev->string;
  if (const JsonValue* info = r.typed("info", JsonValue::Kind::Object, "an object")) {
    // Kept verbatim: re-parse the object's text through nlohmann for a compact canonical form.
    (void)info;
  }
  if (const JsonValue* joints = r.typed("joints", JsonValue::Kind::Array, "an array")) {
    for (const JsonValue& j : joints->items) parseJoint(j, map, diags);
  } else if (!r.get("joints")) {
    r.missing("joints");
  }
  if (r.get("info") && !diags.hasErrors()) {
    try {
      const nlohmann::ordered_json whole = nlohmann::ordered_json::parse(json);
      map.info = whole.at("info").dump();
    } catch (const std::exception&) {
      // Our reader accepted it, so nlohmann will too; keep going without the info on the impossible path.
    }
  }
  checkMap(map, context, diags);
  if (diags.hasErrors()) return std::unexpected(diags);
  if (warnings && context.device && !map.device.empty() && map.device != context.device->name)
    warnings->warning(r.locOf("device"), "written for device '" + map.device + "' but used with '" +
                                             context.device->name + "'");
  return map;
}

std::expected<RigMap, Diagnostics> readRigMapFile(const std::filesystem::path& path, const RigMapContext& context,
                                                  Diagnostics* warnings) {
  auto text = detail::readJsonFileText(path, "rig map");
  if (!text) return std::unexpected(text.error());
  return parseRigMap(*text, path.string(), context, warnings);
}

bool validateRigMap(RigMap& map, const RigMapContext& context, Diagnostics& diags) {
  const int before = diags.errorCount();
  if (map.bits < 1 || map.bits > 32) {
    diags.error(map.bitsLoc, "'bits' must be an integer from 1 to 32");
    return false;
  }
  for (const ChannelMap& c : map.channels)
    checkChannelValues(
        c, map.bits, [&](std::string_view) { return c.loc; }, diags);
  // The structure the parser guarantees by construction: mappings in range and on their joint, orders that list
  // exactly the driven axes.
  for (const JointMap& jm : map.joints) {
    std::string used;
    bool ok = !jm.mappings.empty();
    for (size_t i : jm.mappings) {
      if (i >= map.channels.size() || map.channels[i].joint != jm.joint) {
        ok = false;
        continue;
      }
      if (map.channels[i].translation) continue;  // the order composes rotations only
      used += static_cast<char>('X' + static_cast<int>(map.channels[i].axis));
    }
    ok = ok && jm.order.size() == used.size();
    for (char a : used) ok = ok && std::count(jm.order.begin(), jm.order.end(), a) == 1;
    if (!ok)
      diags.error(jm.loc, "joint '" + jm.joint + "': its channels and order '" + jm.order +
                              "' do not match (each driven axis once, driven: " + used + ")");
  }
  checkMap(map, context, diags);
  return diags.errorCount() == before;
}

namespace {

// A JSON string for text from a device or a file: ill-formed UTF-8 (a device name is whatever bytes the device
// sent) becomes U+FFFD instead of making the writer throw.
std::string jsonString(std::string_view text) { return nlohmann::ordered_json(toValidUtf8(text)).dump(); }

// Angles are written in degrees: that is what a technician reads and edits.
nlohmann::ordered_json degrees(double radians) { return radians / kDegree; }

// {"a": 1, "b": "x"} on one line: a technician reads and edits one channel per line.
std::string inlineObject(const nlohmann::ordered_json& o) {
  std::string s = "{";
  bool first = true;
  for (const auto& [key, value] : o.items()) {
    if (!first) s += ", ";
    first = false;
    s += jsonString(key) + ": " + value.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
  }
  return s + "}";
}

}  // namespace

std::string toJson(const RigMap& map) {
  using nlohmann::ordered_json;
  std::string out = "{\n  \"version\": " + std::to_string(kRigMapVersion) + ",\n  \"bits\": " +
                    std::to_string(map.bits) + ",\n";
  if (!map.device.empty()) out += "  \"device\": " + jsonString(map.device) + ",\n";
  if (!map.info.empty()) out += "  \"info\": " + inlineObject(ordered_json::parse(toValidUtf8(map.info))) + ",\n";
  out += "  \"joints\": [";
  for (size_t ji = 0; ji < map.joints.size(); ++ji) {
    const JointMap& jm = map.joints[ji];
    out += ji ? ",\n" : "\n";
    out += "    {\"joint\": " + jsonString(jm.joint);
    if (jm.mappings.size() > 1) out += ", \"order\": " + jsonString(jm.order);
    out += ", \"channels\": [";
    for (size_t k = 0; k < jm.mappings.size(); ++k) {
      const ChannelMap& c = map.channels[jm.mappings[k]];
      ordered_json o;
      if (c.channel >= 0) o["channel"] = c.channel;
      else o["channel"] = toValidUtf8(c.channelName);
      if (c.device != 0) o["device"] = c.device;
      o["axis"] = (c.translation ? "t" : "") + std::string(toString(c.axis));
      o["sign"] = c.sign;
      if (c.encoder == EncoderKind::Linear && !c.translation) o["encoder"] = "linear";
      if (c.encoder == EncoderKind::Absolute && c.translation) o["encoder"] = "absolute";
      o["gain"] = c.gain;  // counts per radian or per metre; exact, so the file round-trips
      if (c.offset) o["offset"] = *c.offset;
      // Rotation limits are written in degrees, translation limits in metres.
      const char* minKey = c.translation ? "min" : "min_deg";
      const char* maxKey = c.translation ? "max" : "max_deg";
      const auto value = [&](double v) { return c.translation ? nlohmann::ordered_json(v) : degrees(v); };
      if (std::isfinite(c.minAngle)) o[minKey] = value(c.minAngle);
      if (std::isfinite(c.maxAngle)) o[maxKey] = value(c.maxAngle);
      if (c.deadband > 0) o[c.translation ? "deadband" : "deadband_deg"] = value(c.deadband);
      if (c.smoothingMs > 0) o["smoothing_ms"] = c.smoothingMs;
      out += (k ? ",\n      " : "\n      ") + inlineObject(o);
    }
    out += "\n    ]}";
  }
  out += map.joints.empty() ? "]\n}\n" : "\n  ]\n}\n";
  return out;
}


}  // namespace imps::calibration
