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

bool Hud::wantsMouse() const { return ImGui::GetIO().WantCaptureMouse; }

void Hud::draw(const HudInfo& info) {
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_Always);
  ImGui::SetNextWindowBgAlpha(0.55f);
  const ImGuiWindowFlags flags = ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize |
                                 ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoFocusOnAppearing |
                                 ImGuiWindowFlags_NoNav | ImGuiWindowFlags_NoMove;
  if (ImGui::Begin("IMPS Puppeteer", &visible_, flags)) {
    ImGui::Text("%.1f FPS  (%.1f ms/frame)", info.fps, info.frameMs);
    ImGui::Separator();
    ImGui::Text("polygonizer: %s", info.polygonizer.c_str());
    if (info.polygonizer == "particles")
      ImGui::Text("simulate %.2f  add/delete %.2f ms (x%d)  mesh %.2f ms", info.simulateMs, info.addDeleteMs,
                  info.updatesPerRender, info.meshMs);
    else
      ImGui::Text("Marching Cubes %.2f ms", info.marchingCubesMs);
    ImGui::Text("particles %zu  triangles %zu", info.particles, info.triangles);
    ImGui::Separator();
    ImGui::Text("source: %s  [%s]", info.source.c_str(), info.state.c_str());
    if (!info.mapping.empty()) ImGui::Text("mapping: %s", info.mapping.c_str());
    if (info.sampleRateHz >= 0.0) {
      ImGui::Text("sample rate %.0f Hz  dropped %llu  corrupt %llu  not shown %llu", info.sampleRateHz,
                  static_cast<unsigned long long>(info.dropped), static_cast<unsigned long long>(info.corrupt),
                  static_cast<unsigned long long>(info.overwritten));
      if (info.sampleAgeMs >= 0.0) ImGui::Text("sample age %.1f ms", info.sampleAgeMs);
      if (info.latencyMedianMs >= 0.0)
        ImGui::Text("sample-to-screen %.1f ms median, %.1f ms p99", info.latencyMedianMs, info.latencyP99Ms);
    }
    if (!info.selectedJoint.empty()) ImGui::Text("joint: %s (drag to rotate)", info.selectedJoint.c_str());
    if (!info.message.empty()) ImGui::TextUnformatted(info.message.c_str());
    ImGui::Separator();
    ImGui::TextDisabled("drag: orbit / rotate picked joint   wheel: zoom   1-9,[,]: pick joint");
    ImGui::TextDisabled("r reset  s save  p particles  m MC/particles  F12 screenshot  Esc quit");
  }
  ImGui::End();
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

}  // namespace imps::app
