// SPDX-License-Identifier: MIT
// The modeller's menu in a headless Dear ImGui context (no window, no GL: ImGui only needs a display size and its
// font atlas built): drawn without input it changes nothing, it sits in the top-right corner, and a click on a
// widget found by hovering queues the change it names, which the frame loop then applies to the modeller while
// the pipeline is idle; the checkbox and the brush window change their settings at once.
#include "modeller_menu.h"

#include <imgui.h>
#include <imgui_internal.h>

#include <gtest/gtest.h>

#include <functional>
#include <optional>
#include <string>

#include "imps/character.h"
#include "imps/scene_reader.h"

namespace imps::app {
namespace {

using Actions = std::vector<std::function<void(ViewerPipeline&, Modeller&)>>;

std::unique_ptr<ViewerPipeline> biped() {
  auto scene = readSceneFile(std::string(IMPS_SOURCE_DIR) + "/examples/simple_biped.wrl");
  EXPECT_TRUE(scene.has_value());
  auto character = Character::fromScene(*scene);
  EXPECT_TRUE(character.has_value());
  PipelineOptions o;
  o.polygonizer = Polygonizer::MarchingCubes;  // the menu needs no mesh
  return std::make_unique<ViewerPipeline>(std::move(*scene), std::move(*character), o);
}

// A Dear ImGui context with an 800 x 600 display, as the HUD's, but without a window or a renderer.
class HeadlessImGui {
 public:
  HeadlessImGui() {
    context_ = ImGui::CreateContext();
    ImGuiIO& io = ImGui::GetIO();
    io.DisplaySize = ImVec2(800, 600);
    io.DeltaTime = 1.0f / 60.0f;
    io.IniFilename = nullptr;
    unsigned char* pixels = nullptr;
    int w = 0, h = 0;
    io.Fonts->GetTexDataAsRGBA32(&pixels, &w, &h);
  }
  ~HeadlessImGui() { ImGui::DestroyContext(context_); }
  // One frame with the mouse at `mouse` (button down or not), drawing `draw`.
  void frame(const std::function<void()>& draw, ImVec2 mouse = ImVec2(-1, -1), bool down = false) {
    ImGuiIO& io = ImGui::GetIO();
    io.MousePos = mouse;
    io.MouseDown[0] = down;
    ImGui::NewFrame();
    draw();
    ImGui::Render();
  }
  // Where the item `label` of window `window` is: the first mouse position (on a 3-pixel grid over the window)
  // that hovers it, or nullopt.
  std::optional<ImVec2> find(const char* window, const char* label, const std::function<void()>& draw) {
    frame(draw);
    ImGuiWindow* w = ImGui::FindWindowByName(window);
    if (!w) return std::nullopt;
    const ImGuiID id = w->GetID(label);
    for (float y = w->Pos.y; y < w->Pos.y + w->Size.y; y += 3.0f) {
      for (float x = w->Pos.x; x < w->Pos.x + w->Size.x; x += 3.0f) {
        frame(draw, ImVec2(x, y));
        if (GImGui->HoveredId == id) return ImVec2(x, y);
      }
    }
    return std::nullopt;
  }
  // Presses and releases the left button at `at`.
  void click(ImVec2 at, const std::function<void()>& draw) {
    frame(draw, at, false);
    frame(draw, at, true);
    frame(draw, at, false);
  }

 private:
  ImGuiContext* context_;
};

TEST(ModellerMenu, DrawnWithoutInputItChangesNothing) {
  auto pipeline = biped();
  Modeller modeller(*pipeline);
  HeadlessImGui imgui;
  MenuSettings settings{false, 0.0f};
  Actions actions;
  auto draw = [&] { drawModellerMenu(*pipeline, modeller, settings, actions); };
  for (int i = 0; i < 3; ++i) imgui.frame(draw);
  EXPECT_TRUE(actions.empty());
  EXPECT_FALSE(settings.showParticles);
  EXPECT_EQ(settings.pointSize, 0.0f);
  // Top-right corner, 6 pixels in, 300 wide.
  ImGuiWindow* w = ImGui::FindWindowByName("Modeller");
  ASSERT_NE(w, nullptr);
  EXPECT_FLOAT_EQ(w->Pos.x + w->Size.x, 800.0f - 6.0f);
  EXPECT_FLOAT_EQ(w->Pos.y, 6.0f);
  EXPECT_FLOAT_EQ(w->Size.x, 300.0f);
}

TEST(ModellerMenu, AClickQueuesTheChangeForTheFrameLoop) {
  auto pipeline = biped();
  Modeller modeller(*pipeline);
  ASSERT_NE(modeller.mode(), ManipulatorMode::Scale);
  HeadlessImGui imgui;
  MenuSettings settings{false, 0.0f};
  Actions actions;
  auto draw = [&] { drawModellerMenu(*pipeline, modeller, settings, actions); };
  const auto scale = imgui.find("Modeller", "scale (x)", draw);
  ASSERT_TRUE(scale.has_value()) << "no 'scale (x)' radio button in the menu";
  actions.clear();
  imgui.click(*scale, draw);
  ASSERT_EQ(actions.size(), 1u);
  EXPECT_NE(modeller.mode(), ManipulatorMode::Scale) << "the menu only queues; the frame loop applies";
  for (auto& action : actions) action(*pipeline, modeller);
  EXPECT_EQ(modeller.mode(), ManipulatorMode::Scale);

  // The checkbox is the menu's own setting: it changes at once, nothing is queued.
  actions.clear();
  const auto particles = imgui.find("Modeller", "show particles", draw);
  ASSERT_TRUE(particles.has_value());
  actions.clear();
  imgui.click(*particles, draw);
  EXPECT_TRUE(settings.showParticles);
  EXPECT_TRUE(actions.empty());
}

TEST(ModellerMenu, UndoAndRedoButtonsReachTheModeller) {
  auto pipeline = biped();
  Modeller modeller(*pipeline);
  // One document edit to undo: the iso-value (or any change the document accepts).
  const std::string refused = modeller.editDocument([](Scene& s) {
    if (float* iso = isoValueOf(s)) *iso *= 1.1f;
    if (BlendNode* blend = blendInForce(s)) blend->variance *= 1.1f;
  });
  ASSERT_EQ(refused, "");
  ASSERT_EQ(modeller.history().undoCount(), 1u);
  HeadlessImGui imgui;
  MenuSettings settings;
  Actions actions;
  auto draw = [&] { drawModellerMenu(*pipeline, modeller, settings, actions); };
  const auto undo = imgui.find("Modeller", "undo", draw);
  ASSERT_TRUE(undo.has_value());
  actions.clear();
  imgui.click(*undo, draw);
  ASSERT_EQ(actions.size(), 1u);
  actions.front()(*pipeline, modeller);
  EXPECT_EQ(modeller.history().undoCount(), 0u);
  EXPECT_EQ(modeller.history().redoCount(), 1u);
}

TEST(ModellerMenu, TheBrushWindowSetsTheSize) {
  HeadlessImGui imgui;
  Brush brush;
  brush.size = 3;
  auto draw = [&] { drawBrushWindow(brush); };
  imgui.frame(draw);
  EXPECT_EQ(brush.size, 3) << "drawing alone changes nothing";
  ImGuiWindow* w = ImGui::FindWindowByName("Brush");
  ASSERT_NE(w, nullptr);
  // Click the size slider's right end: the largest size, which the brush stores as 0 (keys: 0 = largest).
  const auto slider = imgui.find("Brush", "size", draw);
  ASSERT_TRUE(slider.has_value());
  ImVec2 rightEnd = *slider;
  // Walk right along the slider while it stays hovered, then click its last pixel.
  while (true) {
    imgui.frame(draw, ImVec2(rightEnd.x + 3.0f, rightEnd.y));
    if (GImGui->HoveredId != w->GetID("size")) break;
    rightEnd.x += 3.0f;
  }
  imgui.click(rightEnd, draw);
  EXPECT_EQ(brush.size, 0);
}

}  // namespace
}  // namespace imps::app
