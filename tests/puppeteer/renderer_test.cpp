// SPDX-License-Identifier: MIT
// The live app's GL renderer in a hidden window under Xvfb (Mesa's software GL): the background gradient has the
// snapshot's colours, a mesh covers the same pixels as the software rasteriser's picture through the same camera
// (the two share camera.h's matrices and basis), overlays land on the window pixels they name, and readPixels gives
// rows from the top. Skipped without a display (gl_display.h).
#include "renderer.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <vector>

#include "gl_display.h"
#include "octahedron.h"
#include "snapshot.h"

namespace imps::app {
namespace {

constexpr int kWidth = 160, kHeight = 120;

// A hidden, fixed-size window with a current GL 3.3 core context (no multisampling, so pixels are exact).
class HiddenWindow {
 public:
  HiddenWindow() {
    if (glfwInit() != GLFW_TRUE) return;
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
    glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
    glfwWindowHint(GLFW_SAMPLES, 0);
    window_ = glfwCreateWindow(kWidth, kHeight, "renderer_test", nullptr, nullptr);
    if (window_) glfwMakeContextCurrent(window_);
  }
  ~HiddenWindow() {
    if (window_) glfwDestroyWindow(window_);
    glfwTerminate();
  }
  bool ok() const { return window_ != nullptr; }

 private:
  GLFWwindow* window_ = nullptr;
};

uint8_t srgbByte(float linear) {
  const float c = std::clamp(linear, 0.0f, 1.0f);
  const float s = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
  return uint8_t(std::lround(s * 255.0f));
}

const uint8_t* pixel(const std::vector<uint8_t>& rgba, int x, int y) {
  return &rgba[(size_t(y) * kWidth + size_t(x)) * 4];
}

// Which pixels differ from the background picture.
std::vector<bool> coverage(const std::vector<uint8_t>& image, const std::vector<uint8_t>& background) {
  std::vector<bool> covered(size_t(kWidth) * kHeight);
  for (size_t i = 0; i < covered.size(); ++i) {
    int d = 0;
    for (size_t k = 0; k < 3; ++k) d = std::max(d, std::abs(int(image[4 * i + k]) - int(background[4 * i + k])));
    covered[i] = d > 6;
  }
  return covered;
}

TEST(RendererGl, BackgroundGradientHasTheSnapshotsColours) {
  IMPS_NEED_DISPLAY();
  HiddenWindow window;
  ASSERT_TRUE(window.ok()) << "no GL 3.3 core context";
  Renderer renderer;
  ASSERT_TRUE(renderer.ok()) << renderer.error();
  renderer.draw(Camera{}, kWidth, kHeight, false);
  const std::vector<uint8_t> rgba = Renderer::readPixels(kWidth, kHeight);
  ASSERT_EQ(rgba.size(), size_t(kWidth) * kHeight * 4);
  const SnapshotOptions look;
  // Top row near backgroundTop, bottom row near backgroundBottom (the gradient runs between them), opaque.
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(pixel(rgba, 80, 0)[k], srgbByte(look.backgroundTop[k]), 3) << k;
    EXPECT_NEAR(pixel(rgba, 80, kHeight - 1)[k], srgbByte(look.backgroundBottom[k]), 3) << k;
  }
  EXPECT_EQ(pixel(rgba, 0, 0)[3], 255);
  EXPECT_GT(pixel(rgba, 80, 0)[0], pixel(rgba, 80, kHeight - 1)[0]) << "lighter at the top: rows come from the top";
}

TEST(RendererGl, AMeshCoversWhatTheSnapshotCovers) {
  IMPS_NEED_DISPLAY();
  HiddenWindow window;
  ASSERT_TRUE(window.ok());
  Renderer renderer;
  ASSERT_TRUE(renderer.ok()) << renderer.error();
  const Mesh mesh = test::octahedronMesh(glm::vec3(0.3f, 1.0f, -0.2f), 0.5f);
  const Camera camera = frameMesh(mesh, kFrontThreeQuarter, float(kWidth) / float(kHeight));
  renderer.setSceneRadius(sceneRadius(bounds(mesh)));
  renderer.draw(camera, kWidth, kHeight, false);
  const std::vector<uint8_t> glBackground = Renderer::readPixels(kWidth, kHeight);
  renderer.uploadMesh(mesh);
  renderer.draw(camera, kWidth, kHeight, false);
  const std::vector<uint8_t> glImage = Renderer::readPixels(kWidth, kHeight);

  SnapshotOptions options;
  options.width = kWidth, options.height = kHeight;
  options.camera = camera;
  options.supersampling = 1;
  const std::vector<bool> gl = coverage(glImage, glBackground);
  const std::vector<bool> soft = coverage(renderMesh(mesh, options), renderMesh(Mesh{}, options));
  size_t both = 0, either = 0, glCount = 0;
  for (size_t i = 0; i < gl.size(); ++i) {
    both += gl[i] && soft[i];
    either += gl[i] || soft[i];
    glCount += gl[i];
  }
  EXPECT_GT(glCount, gl.size() / 25) << "the framed mesh is not lost in the distance";
  EXPECT_GT(double(both) / double(either), 0.95) << "GL and software pictures disagree on where the mesh is";
}

TEST(RendererGl, OverlaysLandOnTheirWindowPixels) {
  IMPS_NEED_DISPLAY();
  HiddenWindow window;
  ASSERT_TRUE(window.ok());
  Renderer renderer;
  ASSERT_TRUE(renderer.ok()) << renderer.error();
  renderer.draw(Camera{}, kWidth, kHeight, false);
  // A red square over window pixels x, y in [10, 30) (origin top-left, y down).
  const glm::vec3 red(1, 0, 0);
  const std::vector<OverlayVertex> square = {{{10, 10}, red}, {{30, 10}, red}, {{30, 30}, red},
                                             {{10, 10}, red}, {{30, 30}, red}, {{10, 30}, red}};
  renderer.drawOverlay(square, kWidth, kHeight);
  const std::vector<uint8_t> rgba = Renderer::readPixels(kWidth, kHeight);
  EXPECT_EQ(pixel(rgba, 20, 20)[0], 255);
  EXPECT_EQ(pixel(rgba, 20, 20)[1], 0);
  EXPECT_EQ(pixel(rgba, 20, 20)[2], 0);
  // Not below it, nor mirrored to the bottom of the window.
  EXPECT_NE(pixel(rgba, 20, 40)[1], 0);
  EXPECT_NE(pixel(rgba, 20, kHeight - 21)[1], 0);
}

}  // namespace
}  // namespace imps::app
