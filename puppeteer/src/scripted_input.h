// SPDX-License-Identifier: MIT
// Scripted input for the headless app: key presses and mouse drags injected at given frames (`--keys "k@10,o@20"`,
// `--drag "320,200,380,260@5"`), so tests and documentation runs exercise every key and the manipulators exactly as
// a user would, through the same handlers as the window's callbacks.
#pragma once

#include <expected>
#include <string>
#include <string_view>
#include <vector>

#include "imps/diagnostic.h"

namespace imps::app {

// One injected event, delivered at the start of frame `frame` (0 = the first rendered frame).
struct ScriptedEvent {
  enum class Kind { Key, Drag } kind = Kind::Key;
  int frame = 0;
  int key = 0;             // Kind::Key: a GLFW key code (GLFW_KEY_K …)
  int mods = 0;            // Kind::Key: GLFW modifier bits (GLFW_MOD_CONTROL, GLFW_MOD_SHIFT)
  std::string keyName;     // as written ("k", "F12", "Esc", "ctrl+z" …)
  float x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // Kind::Drag: window pixels, from (x0, y0) to (x1, y1)
  bool shift = false;      // Kind::Drag: with Shift held (the twist manipulator)
  int steps = 8;           // Kind::Drag: cursor moves between press and release
};

// Parses a --keys list: comma-separated KEY@FRAME, KEY one of a–z, 0–9, "[", "]", F12, Esc, Backspace, optionally
// after modifiers "ctrl+" and "shift+" (ctrl+z, ctrl+shift+z); case insensitive for the names. Errors: one
// diagnostic without a position, "--keys: 'x@': expected KEY@FRAME …".
std::expected<std::vector<ScriptedEvent>, Diagnostics> parseScriptedKeys(std::string_view text);

// Parses one --drag: X0,Y0,X1,Y1@FRAME, optionally followed by "+shift". Coordinates are window pixels (non-negative
// numbers); the drag presses the left button at (X0, Y0), moves in `steps` steps to (X1, Y1) and releases, all
// before frame FRAME is drawn. Errors: one diagnostic without a position, "--drag: 'TEXT': expected …".
std::expected<ScriptedEvent, Diagnostics> parseScriptedDrag(std::string_view text);

// The events of `events` due at `frame`, in the order given (stable by frame).
std::vector<ScriptedEvent> eventsAt(const std::vector<ScriptedEvent>& events, int frame);

}  // namespace imps::app
