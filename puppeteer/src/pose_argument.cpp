// SPDX-License-Identifier: MIT
// `--pose` arguments: parsing (degrees by default) and applying them to the skeleton cache.
#include "pose_argument.h"

#include <charconv>
#include <cmath>
#include <numbers>
#include <vector>

namespace imps::app {
namespace {

constexpr const char* kExpected =
    "expected JOINT=AX,AY,AZ,ANGLE (ANGLE in degrees, or e.g. 1.2rad) with a non-zero axis, or JOINT=TX,TY,TZ "
    "(metres)";

std::unexpected<Diagnostics> badArgument() {
  Diagnostics d;
  d.error({}, kExpected);
  return std::unexpected(std::move(d));
}

// A finite number filling `text` exactly.
bool readNumber(std::string_view text, double* value) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), *value);
  return ec == std::errc() && end == text.data() + text.size() && std::isfinite(*value);
}

// An angle: degrees, or with a "deg" / "rad" suffix.
bool readAngle(std::string_view text, double* radians) {
  double scale = std::numbers::pi / 180.0;
  if (text.ends_with("rad")) {
    text.remove_suffix(3);
    scale = 1.0;
  } else if (text.ends_with("deg")) {
    text.remove_suffix(3);
  }
  double v = 0;
  if (!readNumber(text, &v)) return false;
  *radians = v * scale;
  return true;
}

std::vector<std::string_view> splitCommas(std::string_view text) {
  std::vector<std::string_view> parts;
  for (size_t start = 0;;) {
    const size_t comma = text.find(',', start);
    parts.push_back(text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
    if (comma == std::string_view::npos) return parts;
    start = comma + 1;
  }
}

}  // namespace

std::expected<PoseArgument, Diagnostics> parsePoseArgument(std::string_view text) {
  const size_t eq = text.find('=');
  if (eq == std::string_view::npos || eq == 0) return badArgument();
  PoseArgument p;
  p.joint = std::string(text.substr(0, eq));
  const std::vector<std::string_view> parts = splitCommas(text.substr(eq + 1));
  double v[3] = {0, 0, 0};
  if (parts.size() != 3 && parts.size() != 4) return badArgument();
  for (size_t i = 0; i < 3; ++i)
    if (!readNumber(parts[i], &v[i])) return badArgument();
  if (parts.size() == 3) {
    p.translation = true;
    p.offset = glm::vec3(static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2]));
    return p;
  }
  double radians = 0;
  if (!readAngle(parts[3], &radians)) return badArgument();
  p.axis = glm::vec3(static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2]));
  if (!(glm::length(p.axis) > 0.0f)) return badArgument();
  p.radians = static_cast<float>(radians);
  return p;
}

void applyPoseArgument(const PoseArgument& p, int joint, SkeletonCache& skeleton) {
  const Rigid local = skeleton.local(joint);
  if (p.translation) skeleton.setTranslation(joint, local.translation + p.offset);
  else skeleton.setRotation(joint, glm::angleAxis(p.radians, glm::normalize(p.axis)) * local.rotation);
}

}  // namespace imps::app
