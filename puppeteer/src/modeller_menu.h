// SPDX-License-Identifier: MIT
// The modeller's in-window menu (Dear ImGui): what the thesis viewer's right-click popup held — the polygonizer,
// the particle display, the blend's parameters, the iso-value — plus the manipulator mode and undo/redo.
#pragma once

#include <functional>
#include <vector>

#include "modeller.h"
#include "painter.h"
#include "viewer_pipeline.h"

namespace imps::app {

// What the menu shows and changes besides the pipeline and the document.
struct MenuSettings {
  bool showParticles = false;
  float pointSize = 0.0f;  // pixels; 0: the renderer's default
};

// Draws the menu as an ImGui window in the top-right corner; call inside an ImGui frame (Hud::draw's `extra`).
// Reads the pipeline and the modeller; every change is queued in `actions` (run them while the pipeline is idle:
// with --overlap the menu is drawn while a worker polygonizes). Document changes are undoable edits; a slider is
// one edit from press to release, shown live.
void drawModellerMenu(const ViewerPipeline& pipeline, const Modeller& modeller, MenuSettings& settings,
                      std::vector<std::function<void(ViewerPipeline&, Modeller&)>>& actions);

// The painter's brush window (paint mode, `t`): a colour chooser and the size (keys 1-9 and 0 set it too). Call
// inside an ImGui frame.
void drawBrushWindow(Brush& brush);

}  // namespace imps::app
