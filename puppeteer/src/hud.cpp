// SPDX-License-Identifier: MIT
// The HUD, drawn with Debian's Dear ImGui 1.86 and its GLFW / OpenGL 3 backends (libimgui).
#include "hud.h"

#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

namespace imps::app {

Hud::Hud(GLFWwindow* window) {
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini next to the user's files
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
}

Hud::~Hud() {
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
}

std::string keyHelp(bool deviceKeys) {
  return std::string("drag: handle/limb/orbit  w e x move/turn/scale  ctrl+z undo  ctrl+shift+z redo  r reset  "
                     "s save  t paint  p particles  m MC  ") +
         (deviceKeys ? "o record  k calibrate  " : "") + "F12 shot  Esc quit";
}

std::string standInText(const HudInfo& info) {
  if (info.standIns == 0) return {};
  const std::string counts = std::to_string(info.standIns) + " of " + std::to_string(info.particleMeshes) + " meshes";
  if (!info.standIn) return "MC stand-ins: " + counts;
  return std::string("MC stand-in (") + (info.standInCutOff ? "part cut off" : "hole or pinch") + ")  " + counts;
}

bool Hud::wantsMouse() const { return ImGui::GetIO().WantCaptureMouse; }

void Hud::draw(const HudInfo& info, const std::function<void()>& extra) {
  const ImVec4 kDim(0.78f, 0.80f, 0.84f, 1.0f);  // secondary text, readable over the grey panel
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  const ImGuiWindowFlags flags = ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize |
                                 ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoFocusOnAppearing |
                                 ImGuiWindowFlags_NoNav | ImGuiWindowFlags_NoMove;
  // A compact panel in the top-left corner, at most 390 pixels wide (long lines wrap), so the character framed in
  // the middle of a 1280x720 window stays clear of it; the key help sits on one line at the bottom.
  ImGui::SetNextWindowPos(ImVec2(6, 6), ImGuiCond_Always);
  ImGui::SetNextWindowSizeConstraints(ImVec2(0, 0), ImVec2(390, 10000));
  ImGui::SetNextWindowBgAlpha(0.72f);
  ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(6, 4));
  ImGui::PushStyleVar(ImGuiStyleVar_ItemSpacing, ImVec2(6, 1));
  if (ImGui::Begin("IMPS Puppeteer", &visible_, flags)) {
    ImGui::PushTextWrapPos(380.0f);
    ImGui::Text("%.1f FPS  %.1f ms/frame", info.fps, info.frameMs);
    ImGui::TextColored(kDim, "pose %.1f poly %.1f up %.1f draw %.1f hud %.1f swap %.1f", info.poseMs,
                        info.polygonizeMs, info.uploadMs, info.drawMs, info.hudMs, info.swapMs);
    if (info.polygonizer == "particles")
      ImGui::Text("particles: sim %.1f add/del %.1f (x%d) mesh %.1f ms", info.simulateMs, info.addDeleteMs,
                  info.updatesPerRender, info.meshMs);
    else
      ImGui::Text("Marching Cubes: %.2f ms", info.marchingCubesMs);
    ImGui::Text("%zu particles  %zu triangles", info.particles, info.triangles);
    const ImVec4 kProblem(1.0f, 0.45f, 0.25f, 1.0f);  // orange-red: reads as "something is wrong" on the grey panel
    if (const std::string standIn = standInText(info); !standIn.empty()) {
      if (info.standIn)
        ImGui::TextColored(kProblem, "%s", standIn.c_str());
      else
        ImGui::TextColored(kDim, "%s", standIn.c_str());
    }
    ImGui::Separator();
    if (info.problem) {
      ImGui::PushStyleColor(ImGuiCol_Text, kProblem);
      ImGui::TextWrapped("source: %s [%s]", info.source.c_str(), info.state.c_str());
      if (!info.lastError.empty()) ImGui::TextWrapped("%s", info.lastError.c_str());
      ImGui::PopStyleColor();
    } else {
      ImGui::TextWrapped("source: %s [%s]", info.source.c_str(), info.state.c_str());
    }
    if (!info.mapping.empty()) ImGui::TextWrapped("mapping: %s", info.mapping.c_str());
    if (info.sampleRateHz >= 0.0) {
      ImGui::Text("%.0f Hz  dropped %llu  corrupt %llu  not shown %llu", info.sampleRateHz,
                  static_cast<unsigned long long>(info.dropped), static_cast<unsigned long long>(info.corrupt),
                  static_cast<unsigned long long>(info.overwritten));
      if (!info.faults.empty()) ImGui::TextColored(kProblem, "%s", info.faults.c_str());
      if (info.latencyMedianMs >= 0.0)
        ImGui::Text("age %.1f ms  to screen %.1f / %.1f ms (p50/p99)", info.sampleAgeMs, info.latencyMedianMs,
                    info.latencyP99Ms);
      else if (info.sampleAgeMs >= 0.0)
        ImGui::Text("sample age %.1f ms", info.sampleAgeMs);
    }
    if (info.recording) {
      const int minutes = static_cast<int>(info.recordSeconds / 60.0);
      ImGui::TextColored(ImVec4(1.0f, 0.38f, 0.32f, 1.0f), "REC %d:%04.1f  %llu samples", minutes,
                         info.recordSeconds - 60.0 * minutes, static_cast<unsigned long long>(info.recordSamples));
      ImGui::TextWrapped("%s", info.recordPath.c_str());
    }
    if (!info.calibrationProgress.empty())
      ImGui::TextColored(ImVec4(1.0f, 0.85f, 0.3f, 1.0f), "%s", info.calibrationProgress.c_str());
    if (!info.selectedJoint.empty()) ImGui::Text("selected: %s", info.selectedJoint.c_str());
    if (!info.message.empty()) ImGui::TextWrapped("%s", info.message.c_str());
    ImGui::PopTextWrapPos();
  }
  ImGui::End();
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(6, display.y - 6), ImGuiCond_Always, ImVec2(0, 1));
  ImGui::SetNextWindowBgAlpha(0.6f);
  if (ImGui::Begin("IMPS Puppeteer keys", nullptr, flags)) {
    ImGui::TextColored(kDim, "%s", keyHelp(info.deviceKeys).c_str());
  }
  ImGui::End();
  ImGui::PopStyleVar(2);
  if (extra) extra();
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

}  // namespace imps::app
