// SPDX-License-Identifier: MIT
// Scripted input for the headless app (see scripted_input.h).
#include "scripted_input.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>

namespace imps::app {
namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = char(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// GLFW key code of a key name, or 0.
int keyCode(std::string_view name) {
  if (name.size() == 1) {
    const char c = char(std::tolower(static_cast<unsigned char>(name[0])));
    if (c >= 'a' && c <= 'z') return GLFW_KEY_A + (c - 'a');
    if (c >= '0' && c <= '9') return GLFW_KEY_0 + (c - '0');
    if (c == '[') return GLFW_KEY_LEFT_BRACKET;
    if (c == ']') return GLFW_KEY_RIGHT_BRACKET;
    return 0;
  }
  const std::string n = lower(name);
  if (n == "f12") return GLFW_KEY_F12;
  if (n == "esc" || n == "escape") return GLFW_KEY_ESCAPE;
  if (n == "backspace") return GLFW_KEY_BACKSPACE;
  return 0;
}

bool parseInt(std::string_view s, int* out) {
  if (s.empty()) return false;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), *out);
  return ec == std::errc() && end == s.data() + s.size() && *out >= 0;
}

bool parseFloat(std::string_view s, float* out) {
  if (s.empty()) return false;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), *out);
  return ec == std::errc() && end == s.data() + s.size() && std::isfinite(*out) && *out >= 0.0f;
}

// A bad argument: one diagnostic without a position, its message naming the option.
std::unexpected<Diagnostics> argumentError(std::string message) {
  Diagnostics d;
  d.error({}, std::move(message));
  return std::unexpected(std::move(d));
}

}  // namespace

std::expected<std::vector<ScriptedEvent>, Diagnostics> parseScriptedKeys(std::string_view text) {
  std::vector<ScriptedEvent> events;
  size_t start = 0;
  while (start <= text.size()) {
    size_t end = text.find(',', start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view item = text.substr(start, end - start);
    // "[" and "]" cannot be confused with '@'; split at the last '@'.
    const size_t at = item.rfind('@');
    ScriptedEvent e;
    std::string_view key = at == std::string_view::npos ? std::string_view() : item.substr(0, at);
    for (bool more = true; more;) {
      const std::string prefix = lower(key.substr(0, std::min<size_t>(key.size(), 6)));
      more = key.size() > 5 && prefix.starts_with("ctrl+");
      if (more) e.mods |= GLFW_MOD_CONTROL, key.remove_prefix(5);
      if (!more && key.size() > 6 && prefix == "shift+") e.mods |= GLFW_MOD_SHIFT, key.remove_prefix(6), more = true;
    }
    if (at == std::string_view::npos || at == 0 || !parseInt(item.substr(at + 1), &e.frame) ||
        (e.key = keyCode(key)) == 0)
      return argumentError("--keys: '" + std::string(item) +
                           "': expected [ctrl+][shift+]KEY@FRAME (KEY: a-z, 0-9, [, ], F12, Esc, Backspace; "
                           "FRAME >= 0)");
    e.keyName = std::string(item.substr(0, at));
    events.push_back(std::move(e));
    start = end + 1;
  }
  return events;
}

std::expected<ScriptedEvent, Diagnostics> parseScriptedDrag(std::string_view text) {
  auto fail = [&] {
    return argumentError("--drag: '" + std::string(text) + "': expected X0,Y0,X1,Y1@FRAME[+shift] (window pixels)");
  };
  ScriptedEvent e;
  e.kind = ScriptedEvent::Kind::Drag;
  std::string_view rest = text;
  if (const size_t plus = rest.rfind('+'); plus != std::string_view::npos) {
    if (lower(rest.substr(plus + 1)) != "shift") return fail();
    e.shift = true;
    rest = rest.substr(0, plus);
  }
  const size_t at = rest.rfind('@');
  if (at == std::string_view::npos || !parseInt(rest.substr(at + 1), &e.frame)) return fail();
  float* coords[4] = {&e.x0, &e.y0, &e.x1, &e.y1};
  std::string_view list = rest.substr(0, at);
  for (int i = 0; i < 4; ++i) {
    const size_t comma = i < 3 ? list.find(',') : list.size();
    if (comma == std::string_view::npos || !parseFloat(list.substr(0, comma), coords[i])) return fail();
    list = i < 3 ? list.substr(comma + 1) : std::string_view();
  }
  return e;
}

std::vector<ScriptedEvent> eventsAt(const std::vector<ScriptedEvent>& events, int frame) {
  std::vector<ScriptedEvent> out;
  for (const ScriptedEvent& e : events)
    if (e.frame == frame) out.push_back(e);
  return out;
}

}  // namespace imps::app
