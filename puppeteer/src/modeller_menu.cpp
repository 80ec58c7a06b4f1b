// SPDX-License-Identifier: MIT
// The modeller's in-window menu (see modeller_menu.h), drawn with Dear ImGui 1.86.
#include "modeller_menu.h"

#include <imgui.h>

#include <algorithm>
#include <cmath>

#include <string>

namespace imps::app {
namespace {

using Actions = std::vector<std::function<void(ViewerPipeline&, Modeller&)>>;

// A document slider: live while dragged, one undoable edit when released.
void documentSlider(const char* label, float value, float lo, float hi, const char* format, bool logarithmic,
                    void (*set)(Scene&, float), Actions& actions) {
  float v = value;
  const bool changed = ImGui::SliderFloat(label, &v, lo, hi, format,
                                          logarithmic ? ImGuiSliderFlags_Logarithmic : ImGuiSliderFlags_None);
  const bool done = ImGui::IsItemDeactivatedAfterEdit();
  if (changed || done)
    actions.push_back([set, v, done](ViewerPipeline&, Modeller& m) {
      m.editDocument([&](Scene& s) { set(s, v); }, done);
    });
}

void blendSection(const Scene& scene, Actions& actions) {
  const BlendNode* blend = blendInForce(scene);
  if (!blend) {
    ImGui::TextDisabled("blend: default exponential (no blend node)");
    return;
  }
  switch (blend->kind) {
    case BlendKind::Exponential:
      documentSlider("variance", blend->variance, 0.05f, 20.0f, "%.3f", true,
                     [](Scene& s, float v) { blendInForce(s)->variance = v; }, actions);
      break;
    case BlendKind::BlancSchlick:
      documentSlider("hardness", blend->hardness, 0.05f, 20.0f, "%.3f", true,
                     [](Scene& s, float v) { blendInForce(s)->hardness = v; }, actions);
      break;
    case BlendKind::Elliptical:
      documentSlider("blend range", blend->blendRange, 0.01f, 2.0f, "%.3f", true,
                     [](Scene& s, float v) { blendInForce(s)->blendRange = v; }, actions);
      break;
  }
}

}  // namespace

void drawModellerMenu(const ViewerPipeline& pipeline, const Modeller& modeller, MenuSettings& settings,
                      Actions& actions) {
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(display.x - 6, 6), ImGuiCond_Always, ImVec2(1, 0));
  ImGui::SetNextWindowSize(ImVec2(300, 0), ImGuiCond_Always);
  ImGui::SetNextWindowBgAlpha(0.72f);
  const ImGuiWindowFlags flags = ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoMove |
                                 ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoFocusOnAppearing;
  if (ImGui::Begin("Modeller", nullptr, flags)) {
    ImGui::PushItemWidth(130);
    int polygonizer = pipeline.polygonizer() == Polygonizer::Particles ? 0 : 1;
    if (ImGui::Combo("polygonizer", &polygonizer, "particles\0Marching Cubes\0"))
      actions.push_back([polygonizer](ViewerPipeline& p, Modeller&) {
        p.setPolygonizer(polygonizer == 0 ? Polygonizer::Particles : Polygonizer::MarchingCubes);
      });
    ImGui::Checkbox("show particles", &settings.showParticles);
    float size = settings.pointSize > 0.0f ? settings.pointSize : 4.0f;
    if (ImGui::SliderFloat("point size", &size, 1.0f, 16.0f, "%.0f px")) settings.pointSize = size;
    ImGui::Separator();
    blendSection(pipeline.scene(), actions);
    if (const float* iso = isoValueOf(pipeline.scene()))
      documentSlider("iso-value", *iso, 0.05f, 5.0f, "%.3f", true, [](Scene& s, float v) { *isoValueOf(s) = v; },
                     actions);
    else
      ImGui::TextDisabled("iso-value 1 (no polygonizer node)");
    ImGui::Separator();
    int mode = static_cast<int>(modeller.mode());
    const bool a = ImGui::RadioButton("move (w)", &mode, 0);
    ImGui::SameLine();
    const bool b = ImGui::RadioButton("turn (e)", &mode, 1);
    ImGui::SameLine();
    const bool c = ImGui::RadioButton("scale (x)", &mode, 2);
    if (a || b || c)
      actions.push_back([mode](ViewerPipeline&, Modeller& m) { m.setMode(static_cast<ManipulatorMode>(mode)); });
    if (ImGui::Button("undo")) actions.push_back([](ViewerPipeline&, Modeller& m) { m.undo(); });
    ImGui::SameLine();
    if (ImGui::Button("redo")) actions.push_back([](ViewerPipeline&, Modeller& m) { m.redo(); });
    ImGui::SameLine();
    ImGui::TextDisabled("%zu / %zu", modeller.history().undoCount(), modeller.history().redoCount());
    ImGui::PopItemWidth();
  }
  ImGui::End();
}

void drawBrushWindow(Brush& brush) {
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  if (ImGui::Begin("Brush", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    float rgb[3] = {brush.color[0] / 255.0f, brush.color[1] / 255.0f, brush.color[2] / 255.0f};
    if (ImGui::ColorPicker3("colour", rgb, ImGuiColorEditFlags_NoSidePreview | ImGuiColorEditFlags_PickerHueWheel))
      for (int k = 0; k < 3; ++k) brush.color[k] = uint8_t(std::lround(std::clamp(rgb[k], 0.0f, 1.0f) * 255.0f));
    int size = brush.size == 0 ? 10 : brush.size;
    if (ImGui::SliderInt("size", &size, 1, 10)) brush.size = size % 10;
    ImGui::Text("radius %.0f texels (keys 1-9, 0 largest)", double(brush.radiusTexels()));
  }
  ImGui::End();
}

}  // namespace imps::app
