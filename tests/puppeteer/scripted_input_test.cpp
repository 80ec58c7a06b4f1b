// SPDX-License-Identifier: MIT
// Scripted input: --keys and --drag parse into the events the headless app delivers, and bad text is refused with
// the option's name.
#include "scripted_input.h"

#include <gtest/gtest.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

namespace imps::app {
namespace {

TEST(ScriptedInput, Keys) {
  auto keys = parseScriptedKeys("o@5,k@10,P@0,F12@3,Esc@40,[@1,]@2,7@8,backspace@9");
  ASSERT_TRUE(keys) << keys.error().str();
  ASSERT_EQ(keys->size(), 9u);
  EXPECT_EQ((*keys)[0].key, GLFW_KEY_O);
  EXPECT_EQ((*keys)[0].frame, 5);
  EXPECT_EQ((*keys)[1].key, GLFW_KEY_K);
  EXPECT_EQ((*keys)[2].key, GLFW_KEY_P);
  EXPECT_EQ((*keys)[2].frame, 0);
  EXPECT_EQ((*keys)[3].key, GLFW_KEY_F12);
  EXPECT_EQ((*keys)[4].key, GLFW_KEY_ESCAPE);
  EXPECT_EQ((*keys)[5].key, GLFW_KEY_LEFT_BRACKET);
  EXPECT_EQ((*keys)[6].key, GLFW_KEY_RIGHT_BRACKET);
  EXPECT_EQ((*keys)[7].key, GLFW_KEY_7);
  EXPECT_EQ((*keys)[8].key, GLFW_KEY_BACKSPACE);
  EXPECT_EQ((*keys)[0].kind, ScriptedEvent::Kind::Key);
}

TEST(ScriptedInput, KeysWithModifiers) {
  auto keys = parseScriptedKeys("ctrl+z@3,Ctrl+Shift+Z@4,z@5,shift+w@6");
  ASSERT_TRUE(keys) << keys.error().str();
  ASSERT_EQ(keys->size(), 4u);
  EXPECT_EQ((*keys)[0].key, GLFW_KEY_Z);
  EXPECT_EQ((*keys)[0].mods, GLFW_MOD_CONTROL);
  EXPECT_EQ((*keys)[1].mods, GLFW_MOD_CONTROL | GLFW_MOD_SHIFT);
  EXPECT_EQ((*keys)[1].keyName, "Ctrl+Shift+Z");
  EXPECT_EQ((*keys)[2].mods, 0);
  EXPECT_EQ((*keys)[3].mods, GLFW_MOD_SHIFT);
  EXPECT_EQ((*keys)[3].key, GLFW_KEY_W);
}

TEST(ScriptedInput, BadKeys) {
  for (const char* bad : {"", "o", "o@", "@5", "o@-1", "o@x", "ctrl@3", "o@5,", "o@5,,k@6", "F13@1", "ctrl+@3",
                          "ctrl+shift+@3", "alt+z@3", "ctrl+zz@3"}) {
    auto keys = parseScriptedKeys(bad);
    ASSERT_FALSE(keys) << bad;
    EXPECT_NE(keys.error().str().find("--keys"), std::string::npos) << keys.error().str();
  }
}

TEST(ScriptedInput, Drag) {
  auto d = parseScriptedDrag("320,200.5,380,260@5");
  ASSERT_TRUE(d) << d.error().str();
  EXPECT_EQ(d->kind, ScriptedEvent::Kind::Drag);
  EXPECT_EQ(d->frame, 5);
  EXPECT_FLOAT_EQ(d->x0, 320);
  EXPECT_FLOAT_EQ(d->y0, 200.5f);
  EXPECT_FLOAT_EQ(d->x1, 380);
  EXPECT_FLOAT_EQ(d->y1, 260);
  EXPECT_FALSE(d->shift);
  auto twist = parseScriptedDrag("1,2,3,4@0+shift");
  ASSERT_TRUE(twist) << twist.error().str();
  EXPECT_TRUE(twist->shift);
  for (const char* bad : {"1,2,3@4", "1,2,3,4", "1,2,3,4,5@6", "1,2,3,x@4", "1,2,3,4@5+ctrl", "-1,2,3,4@5"}) {
    auto e = parseScriptedDrag(bad);
    ASSERT_FALSE(e) << bad;
    EXPECT_NE(e.error().str().find("--drag"), std::string::npos);
  }
}

TEST(ScriptedInput, EventsAtAFrame) {
  auto keys = parseScriptedKeys("o@5,k@10,p@5");
  ASSERT_TRUE(keys);
  const auto at5 = eventsAt(*keys, 5);
  ASSERT_EQ(at5.size(), 2u);
  EXPECT_EQ(at5[0].key, GLFW_KEY_O);
  EXPECT_EQ(at5[1].key, GLFW_KEY_P);
  EXPECT_TRUE(eventsAt(*keys, 6).empty());
}

}  // namespace
}  // namespace imps::app
