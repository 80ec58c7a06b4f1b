// SPDX-License-Identifier: MIT
// Character: joints, primitives and the hierarchy's blending rule (thesis 3.7), BlendGroups, blend sets.
#include "imps/character.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "imps/scene_reader.h"

namespace imps {
namespace {

Character compile(const std::string& text) {
  auto scene = readScene(text, "test.wrl");
  EXPECT_TRUE(scene.has_value()) << (scene ? "" : scene.error().str());
  auto c = Character::fromScene(*scene);
  EXPECT_TRUE(c.has_value()) << (c ? "" : c.error().str());
  return std::move(*c);
}

bool blends(const Character& c, const std::string& a, const std::string& b) {
  size_t ia = 0, ib = 0;
  for (size_t i = 0; i < c.primitives().size(); ++i) {
    if (c.primitives()[i].name == a) ia = i;
    if (c.primitives()[i].name == b) ib = i;
  }
  const auto& n = c.blendNeighbours(ia);
  return std::find(n.begin(), n.end(), uint32_t(ib)) != n.end();
}

// A chain A -> B -> C -> D with one metaball each, plus a sibling of A's metaball and a shapeless joint between C
// and D.
const char* kChain = R"(#VRML V2.0 utf8
DEF A RigidTransform { children [
  DEF a Metaball { radius 0.5 }
  DEF a2 Metaball { center 0.3 0 0 radius 0.4 }
  DEF B RigidTransform { translation 1 0 0 children [
    DEF b Metaball { radius 0.5 }
    DEF C RigidTransform { translation 1 0 0 children [
      DEF c Metaball { radius 0.5 }
      DEF OFFSET RigidTransform { translation 0.5 0 0 children [
        DEF D RigidTransform { translation 0.5 0 0 children [ DEF d Metaball { radius 0.5 } ] }
      ] }
    ] }
  ] }
] }
)";

TEST(Character, HierarchyDefinesJointsAndPrimitives) {
  const Character c = compile(kChain);
  EXPECT_TRUE(c.hierarchical());
  ASSERT_EQ(c.joints().size(), 5u);
  EXPECT_EQ(c.joints()[0].name, "A");
  EXPECT_EQ(c.joints()[c.findJoint("D")].parent, c.findJoint("OFFSET"));
  ASSERT_EQ(c.primitives().size(), 5u);
  EXPECT_EQ(c.primitives()[0].joint, c.findJoint("A"));
  EXPECT_EQ(c.findJoint("nope"), -1);
}

TEST(Character, PrimitivesBlendWithSiblingsParentsAndChildrenOnly) {
  const Character c = compile(kChain);
  EXPECT_TRUE(blends(c, "a", "a2")) << "siblings";
  EXPECT_TRUE(blends(c, "a", "b")) << "parent and child";
  EXPECT_TRUE(blends(c, "b", "c"));
  EXPECT_FALSE(blends(c, "a", "c")) << "grandparent and grandchild";
  EXPECT_TRUE(blends(c, "c", "d")) << "a joint without primitives in between does not count as a generation";
  EXPECT_FALSE(blends(c, "b", "d"));
}

TEST(Character, BlendGroupsAddAndRemovePairs) {
  const Character c = compile(std::string(kChain) + R"(
BlendGroup { members [ "a" "C" ] }
BlendGroup { members [ "b" "c" ] blend FALSE }
)");
  EXPECT_TRUE(blends(c, "a", "c")) << "a joint name stands for its primitives";
  EXPECT_TRUE(blends(c, "c", "a"));
  EXPECT_FALSE(blends(c, "b", "c"));
  EXPECT_TRUE(blends(c, "a", "b")) << "untouched pairs keep the hierarchy's rule";
}

TEST(Character, BlendGroupWithUnknownNameIsAnError) {
  auto scene = readScene(std::string(kChain) + "BlendGroup { members [ \"a\" \"cc\" ] }\n", "test.wrl");
  if (!scene) {
    // The reader already rejects it, with a location.
    EXPECT_NE(scene.error().str().find("cc"), std::string::npos);
    return;
  }
  auto c = Character::fromScene(*scene);
  ASSERT_FALSE(c.has_value());
  EXPECT_NE(c.error().str().find("did you mean"), std::string::npos);
}

TEST(Character, BlendSetsAreTheMaximalCliquesOfTheBlendGraph) {
  const Character c = compile(kChain);
  const BlendSets& sets = c.blendSets();
  const size_t n = c.primitives().size();
  auto contains = [&](size_t s, size_t i) {
    return std::binary_search(sets.set(s).begin(), sets.set(s).end(), uint32_t(i));
  };
  for (size_t s = 0; s < sets.count(); ++s) {
    // A clique: every pair of members blends ...
    for (uint32_t a : sets.set(s))
      for (uint32_t b : sets.set(s)) {
        if (a != b) {
          EXPECT_TRUE(c.blends(a, b)) << s;
        }
      }
    // ... and maximal: no other primitive blends with all of them.
    for (size_t i = 0; i < n; ++i) {
      if (contains(s, i)) continue;
      bool all = true;
      for (uint32_t m : sets.set(s)) all = all && c.blends(i, m);
      EXPECT_FALSE(all) << "set " << s << " could take primitive " << i;
    }
  }
  // Every blending pair shares a set; no other pair does.
  for (size_t a = 0; a < n; ++a)
    for (size_t b = a + 1; b < n; ++b) {
      bool shared = false;
      for (size_t s = 0; s < sets.count(); ++s) shared = shared || (contains(s, a) && contains(s, b));
      EXPECT_EQ(shared, c.blends(a, b)) << a << " " << b;
    }
}

TEST(Character, FlatSceneBlendsEverything) {
  const Character c = compile(R"(#VRML V2.0 utf8
BlancSchlickBlend { hardness 2 children [ Metaball { } Metaball { center 3 0 0 } RigidTransform { translation 0 3 0 children [ LineSeg { } ] } ] }
)");
  EXPECT_FALSE(c.hierarchical());
  EXPECT_EQ(c.blend().kind, BlendKind::BlancSchlick);
  EXPECT_FLOAT_EQ(c.primitives()[0].blendParam, 2.0f);
  ASSERT_EQ(c.blendSets().count(), 1u);
  EXPECT_EQ(c.blendSets().set(0).size(), 3u);
}

TEST(Character, DefaultBlobbinessComesFromTheVariance) {
  const Character c = compile(R"(#VRML V2.0 utf8
MarchingCubes { blendingFunction ExponentialBlend { variance 0.5 } sceneGraph RigidTransform { children [
  Metaball { } Metaball { blendParam -7 } ] } }
)");
  EXPECT_FLOAT_EQ(c.primitives()[0].blendParam, -2.0f);
  EXPECT_FLOAT_EQ(c.primitives()[1].blendParam, -7.0f);
}

}  // namespace
}  // namespace imps
