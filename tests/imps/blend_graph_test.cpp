// SPDX-License-Identifier: MIT
// The blend graph (blend_graph.h): two primitives blend only if they are blend neighbours, under every blend, in
// flat and hierarchical scenes; BlendGroups add and remove pairs; the field agrees with a brute-force reference.
#include "imps/blend_graph.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "examples.h"
#include "imps/character.h"
#include "imps/marching_cubes.h"
#include "imps/mesh.h"
#include "imps/scene_reader.h"
#include "imps/skeleton_cache.h"

namespace imps {
namespace {

using Sets = std::vector<std::vector<uint32_t>>;

// Every maximal clique of the graph `adj` (n <= 16) by enumerating all subsets.
Sets bruteForceMaximalCliques(const std::vector<std::vector<bool>>& adj) {
  const size_t n = adj.size();
  auto isClique = [&](uint32_t mask) {
    for (size_t a = 0; a < n; ++a)
      for (size_t b = a + 1; b < n; ++b)
        if ((mask >> a & 1) && (mask >> b & 1) && !adj[a][b]) return false;
    return true;
  };
  Sets out;
  for (uint32_t mask = 1; mask < (1u << n); ++mask) {
    if (!isClique(mask)) continue;
    bool maximal = true;
    for (size_t v = 0; v < n && maximal; ++v)
      if (!(mask >> v & 1) && isClique(mask | (1u << v))) maximal = false;
    if (!maximal) continue;
    std::vector<uint32_t> set;
    for (size_t v = 0; v < n; ++v)
      if (mask >> v & 1) set.push_back(static_cast<uint32_t>(v));
    out.push_back(set);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(BlendGraph, MaximalCliquesMatchBruteForceOnRandomGraphs) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const size_t n = 1 + rng() % 12;
    const double density = double(rng() % 100) / 100.0;
    std::vector<uint32_t> classOf(n);
    for (size_t i = 0; i < n; ++i) classOf[i] = static_cast<uint32_t>(i);
    BlendGraph g(classOf, n);
    std::vector<std::vector<bool>> adj(n, std::vector<bool>(n, false));
    for (size_t a = 0; a < n; ++a)
      for (size_t b = a + 1; b < n; ++b)
        if (std::uniform_real_distribution<double>(0, 1)(rng) < density) {
          adj[a][b] = adj[b][a] = true;
          g.setBlend(uint32_t(a), uint32_t(b), true);
        }
    auto cliques = g.maximalCliques(100000);
    ASSERT_TRUE(cliques.has_value());
    EXPECT_EQ(*cliques, bruteForceMaximalCliques(adj)) << "trial " << trial << ", n " << n;
  }
}

TEST(BlendGraph, ClassWhoseMembersDoNotBlendGivesOneCliquePerMember) {
  // Primitives 0,1,2 are twins that do not blend with each other; all three blend with 3 and 4 (one class).
  BlendGraph g({0, 0, 0, 1, 1}, 2);
  g.setSelfBlend(0, false);
  g.setBlend(0, 1, true);
  EXPECT_FALSE(g.complete());
  EXPECT_EQ(g.neighbours(0), (std::vector<uint32_t>{3, 4}));
  EXPECT_EQ(g.neighbours(3), (std::vector<uint32_t>{0, 1, 2, 4}));
  auto cliques = g.maximalCliques(100);
  ASSERT_TRUE(cliques.has_value());
  EXPECT_EQ(*cliques, (Sets{{0, 3, 4}, {1, 3, 4}, {2, 3, 4}}));
}

TEST(BlendGraph, TooManyCliquesIsReportedNotEnumeratedForever) {
  // The complement of a perfect matching on 2k vertices has 2^k maximal cliques.
  const size_t k = 12, n = 2 * k;
  std::vector<uint32_t> classOf(n);
  for (size_t i = 0; i < n; ++i) classOf[i] = static_cast<uint32_t>(i);
  BlendGraph g(classOf, n);
  for (size_t a = 0; a < n; ++a)
    for (size_t b = a + 1; b < n; ++b) g.setBlend(uint32_t(a), uint32_t(b), b != a + 1 || a % 2 == 1);
  auto all = g.maximalCliques(1u << k);
  ASSERT_TRUE(all.has_value());
  EXPECT_EQ(all->size(), size_t{1} << k);
  auto capped = g.maximalCliques(1000);
  ASSERT_FALSE(capped.has_value());
  EXPECT_EQ(capped.error(), 1000u);
}

Character compile(const std::string& text) {
  auto scene = readScene(text, "test.wrl");
  EXPECT_TRUE(scene.has_value()) << (scene ? "" : scene.error().str());
  auto c = Character::fromScene(*scene);
  EXPECT_TRUE(c.has_value()) << (c ? "" : c.error().str());
  return std::move(*c);
}

size_t primitiveNamed(const Character& c, const std::string& name) {
  for (size_t i = 0; i < c.primitives().size(); ++i)
    if (c.primitives()[i].name == name) return i;
  ADD_FAILURE() << "no primitive " << name;
  return 0;
}

bool inOneSet(const Character& c, size_t a, size_t b) {
  for (size_t s = 0; s < c.blendSets().count(); ++s) {
    const auto set = c.blendSets().set(s);
    if (std::binary_search(set.begin(), set.end(), uint32_t(a)) &&
        std::binary_search(set.begin(), set.end(), uint32_t(b)))
      return true;
  }
  return false;
}

// A random scene of `n` metaballs: flat (everything blends) or a random tree of joints with one or two metaballs
// each; then random BlendGroups. `reference` receives the pairs that blend, worked out from the rule directly.
std::string randomScene(std::mt19937& rng, bool flat, const char* blend, std::vector<std::vector<bool>>& reference) {
  const size_t joints = 3 + rng() % 4;
  std::vector<int> parent(joints, -1);
  std::vector<std::vector<std::string>> shapes(joints);
  std::vector<int> jointOf;
  std::uniform_real_distribution<float> pos(-0.5f, 0.5f), radius(0.25f, 0.45f);
  std::vector<std::string> text(joints);
  for (size_t j = 0; j < joints; ++j) {
    parent[j] = j == 0 ? -1 : int(rng() % j);
    const int count = 1 + int(rng() % 2);
    for (int k = 0; k < count; ++k) {
      const std::string name = "p" + std::to_string(jointOf.size());
      jointOf.push_back(int(j));
      shapes[j].push_back(name);
      char buf[160];
      std::snprintf(buf, sizeof buf, "DEF %s Metaball { center %.3f %.3f %.3f radius %.3f }\n", name.c_str(), pos(rng),
                    pos(rng), pos(rng), radius(rng));
      text[j] += buf;
    }
  }
  // Children's text nested inside their parents' (children have higher indices).
  for (size_t j = joints; j-- > 1;) {
    text[parent[j]] += "DEF J" + std::to_string(j) + " RigidTransform { children [\n" + text[j] + "] }\n";
  }
  const size_t n = jointOf.size();
  reference.assign(n, std::vector<bool>(n, false));
  for (size_t a = 0; a < n; ++a)
    for (size_t b = 0; b < n; ++b) {
      const int ja = jointOf[a], jb = jointOf[b];
      reference[a][b] = a != b && (flat || ja == jb || parent[ja] == jb || parent[jb] == ja);
    }
  std::string groups;
  const int groupCount = int(rng() % 4);
  for (int g = 0; g < groupCount; ++g) {
    std::vector<size_t> members;
    std::string names;
    const int m = 2 + int(rng() % 3);
    for (int k = 0; k < m; ++k) {
      const bool byJoint = rng() % 3 == 0 && !flat;
      if (byJoint) {
        const size_t j = 1 + rng() % (joints - 1);
        names += " \"J" + std::to_string(j) + "\"";
        for (size_t i = 0; i < n; ++i)
          if (jointOf[i] == int(j)) members.push_back(i);
      } else {
        const size_t i = rng() % n;
        names += " \"p" + std::to_string(i) + "\"";
        members.push_back(i);
      }
    }
    const bool on = rng() % 2 == 0;
    groups += "BlendGroup { members [" + names + " ] blend " + (on ? "TRUE" : "FALSE") + " }\n";
    for (size_t a : members)
      for (size_t b : members)
        if (a != b) reference[a][b] = on;
  }
  if (flat)
    return std::string("#VRML V2.0 utf8\n") + blend + " { children [\n" + text[0] + "] }\n" + groups;
  return std::string("#VRML V2.0 utf8\nMarchingCubes { blendingFunction ") + blend +
         " { } sceneGraph DEF J0 RigidTransform { children [\n" + text[0] + "] } }\n" + groups;
}

// F by brute force: the maximum over every clique of `reference` (every subset whose pairs all blend) of the
// clique's blend, summing or folding terms in ascending primitive order as the field does.
float bruteForceValue(const Field& field, const std::vector<std::vector<bool>>& reference, const glm::vec3& x) {
  const size_t n = field.size();
  const BlendFunction& blend = field.blend();
  std::vector<float> t(n);
  for (size_t i = 0; i < n; ++i) {
    const float d = field.primitive(i).distance(x);
    t[i] = d < field.supportDistance(i) ? blend.term(d, field.param(i)) : (blend.additive() ? 0.0f : -1.0f);
  }
  float best = 0.0f;
  for (uint32_t mask = 1; mask < (1u << n); ++mask) {
    bool clique = true;
    for (size_t a = 0; a < n && clique; ++a)
      for (size_t b = a + 1; b < n && clique; ++b)
        if ((mask >> a & 1) && (mask >> b & 1) && !reference[a][b]) clique = false;
    if (!clique) continue;
    float v;
    if (blend.additive()) {
      v = 0.0f;
      for (size_t i = 0; i < n; ++i)
        if (mask >> i & 1) v += t[i];
    } else {
      float g = -1.0f;
      for (size_t i = 0; i < n; ++i)
        if (mask >> i & 1) g = g <= -1.0f ? t[i] : (t[i] <= -1.0f ? g : BlendFunction::roundedUnion(g, t[i]));
      v = g > -1.0f ? std::max(1.0f + g, 0.0f) : 0.0f;
    }
    best = std::max(best, v);
  }
  return best;
}

TEST(BlendGraph, FieldIsTheBruteForceMaximumOverPairwiseBlendingCliques) {
  std::mt19937 rng(11);
  const char* blends[] = {"ExponentialBlend", "BlancSchlickBlend", "EllipticalBlend"};
  for (int trial = 0; trial < 60; ++trial) {
    const bool flat = trial % 2 == 0;
    const char* blend = blends[trial % 3];
    std::vector<std::vector<bool>> reference;
    const std::string text = randomScene(rng, flat, blend, reference);
    const Character c = compile(text);
    const size_t n = c.primitives().size();
    ASSERT_EQ(reference.size(), n) << text;
    // The reference numbers primitives as generated ("pK"); the character, in file order.
    std::vector<std::vector<bool>> inFileOrder(n, std::vector<bool>(n));
    for (size_t a = 0; a < n; ++a)
      for (size_t b = 0; b < n; ++b)
        inFileOrder[a][b] = reference[std::stoul(c.primitives()[a].name.substr(1))]
                                     [std::stoul(c.primitives()[b].name.substr(1))];
    reference = inFileOrder;
    for (size_t a = 0; a < n; ++a)
      for (size_t b = 0; b < n; ++b)
        if (a != b) {
          ASSERT_EQ(c.blends(a, b), reference[a][b]) << text << a << " " << b;
          EXPECT_EQ(inOneSet(c, a, b), bool(reference[a][b])) << "a pair shares a blend set iff it blends\n" << text;
        }
    SkeletonCache cache(c);
    cache.update();
    const Field& field = cache.field();
    std::uniform_real_distribution<float> u(-0.9f, 0.9f);
    for (int k = 0; k < 150; ++k) {
      const glm::vec3 x(u(rng), u(rng), u(rng));
      const float want = bruteForceValue(field, reference, x);
      EXPECT_NEAR(field.value(x), want, 2e-5f * std::max(1.0f, want))
          << blend << (flat ? " flat\n" : " tree\n") << text;
    }
  }
}

// Thesis 3.7 and the issue's chain: torso -> shoulder -> arm, the arm hanging beside the torso with a 7 cm gap. The
// shoulder blends with both, but torso and arm never blend, so the gap stays open below the shoulder.
const char* kChain = R"(#VRML V2.0 utf8
MarchingCubes { blendingFunction ExponentialBlend { variance 2 } sceneGraph DEF Torso RigidTransform { children [
  DEF torso LineSeg { point1 0 0 0 point2 0 0.6 0 radius1 0.12 radius2 0.12 }
  DEF Shoulder RigidTransform { translation 0.24 0.6 0 children [
    DEF shoulder Metaball { radius 0.1 }
    DEF Arm RigidTransform { translation 0 -0.02 0 children [
      DEF arm LineSeg { point1 0 0 0 point2 0 -0.5 0 radius1 0.05 radius2 0.05 }
    ] }
  ] }
] } }
)";

TEST(BlendGraph, ChainKeepsTheGapBetweenGrandparentAndGrandchild) {
  const Character c = compile(kChain);
  const size_t torso = primitiveNamed(c, "torso"), shoulder = primitiveNamed(c, "shoulder"),
               arm = primitiveNamed(c, "arm");
  EXPECT_TRUE(c.blends(torso, shoulder));
  EXPECT_TRUE(c.blends(shoulder, arm));
  EXPECT_FALSE(c.blends(torso, arm));
  EXPECT_FALSE(inOneSet(c, torso, arm)) << "the shoulder's neighbourhood is not a blend set";
  SkeletonCache cache(c);
  cache.update();
  const Field& field = cache.field();
  // The old rule (one set holding the shoulder and all its neighbours) is this flat field: it closes the gap.
  std::vector<float> params;
  std::vector<glm::vec3> colors;
  for (size_t i = 0; i < field.size(); ++i) params.push_back(field.param(i)), colors.push_back(field.color(i));
  const Field everything(field.primitives(), params, colors, field.blend(), BlendSets::all(field.size()));
  int closedByEverything = 0;
  for (float y = 0.1f; y <= 0.38f; y += 0.01f) {
    const glm::vec3 gap(0.155f, y, 0.0f);  // halfway between the torso's surface (0.12) and the arm's (0.19)
    EXPECT_LT(field.value(gap), 1.0f) << "y " << y;
    closedByEverything += everything.value(gap) >= 1.0f;
  }
  EXPECT_GT(closedByEverything, 20) << "the test scene must be one a global blend would close";

  MarchingCubesOptions o;
  o.cellSize = 0.01f;
  const Mesh mesh = polygonize(field, o);
  EXPECT_TRUE(analyzeTopology(mesh).closedManifold());
  int inGap = 0;
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    const glm::vec3 p = mesh.position(v);
    inGap += p.x > 0.135f && p.x < 0.175f && p.y > 0.1f && p.y < 0.38f && std::abs(p.z) < 0.03f;
  }
  EXPECT_EQ(inGap, 0) << "no surface in the gap";
}

TEST(BlendGraph, BipedCalvesNeverBlendWithThePelvis) {
  const Character& c = test::exampleCharacter("simple_biped");
  const size_t pelvis = primitiveNamed(c, "Pelvis_SEG");
  for (const char* name : {"L_Calf_SEG", "R_Calf_SEG", "L_Forearm_SEG", "R_Forearm_SEG"}) {
    const size_t other = primitiveNamed(c, name);
    EXPECT_FALSE(c.blends(pelvis, other)) << name;
    EXPECT_FALSE(inOneSet(c, pelvis, other)) << name << " shares a blend set with the pelvis";
  }
  // Every set is a clique: all its pairs blend.
  for (size_t s = 0; s < c.blendSets().count(); ++s) {
    const auto set = c.blendSets().set(s);
    for (uint32_t a : set)
      for (uint32_t b : set) {
        if (a != b) {
          EXPECT_TRUE(c.blends(a, b)) << c.primitives()[a].name << " " << c.primitives()[b].name;
        }
      }
  }
}

// Two metaballs 1.1 apart with radius 0.5: blended they fuse (F at the midpoint is 2 e^(B (1.21 - 1)) > 1 for
// B = -1); with the pair removed by a BlendGroup they are two blobs.
void expectSeparatedOnlyWithTheGroup(const std::string& before, const std::string& after) {
  for (const bool removed : {false, true}) {
    const Character c = compile(before + (removed ? after : ""));
    SkeletonCache cache(c);
    cache.update();
    const float mid = cache.field().value(glm::vec3(0.55f, 0, 0));
    MarchingCubesOptions o;
    o.cellSize = 0.03f;
    const MeshTopology topo = analyzeTopology(polygonize(cache.field(), o));
    EXPECT_TRUE(topo.closedManifold());
    if (removed) {
      EXPECT_LT(mid, 1.0f);
      EXPECT_EQ(topo.components, 2u);
    } else {
      EXPECT_GT(mid, 1.0f);
      EXPECT_EQ(topo.components, 1u);
    }
  }
}

TEST(BlendGraph, RemovingASiblingPairSeparatesTouchingMetaballs) {
  expectSeparatedOnlyWithTheGroup(R"(#VRML V2.0 utf8
MarchingCubes { sceneGraph RigidTransform { children [
  DEF a Metaball { radius 0.5 } DEF b Metaball { center 1.1 0 0 radius 0.5 } ] } }
)", "BlendGroup { members [ \"a\" \"b\" ] blend FALSE }\n");
  expectSeparatedOnlyWithTheGroup(R"(#VRML V2.0 utf8
ExponentialBlend { children [ DEF a Metaball { radius 0.5 } DEF b Metaball { center 1.1 0 0 radius 0.5 } ] }
)", "BlendGroup { members [ \"a\" \"b\" ] blend FALSE }\n");
}

// Appendix A.2.2's mcSimpleBip01.wrl style: a blend node wrapping a joint's shapes inside the hierarchy.
TEST(BlendGraph, BlendNodesInsideAHierarchyScopeTheirParameters) {
  const Character c = compile(R"(#VRML V2.0 utf8
DEF Hip RigidTransform { children [
  ExponentialBlend { variance 0.5 children [ DEF hip Metaball { radius 0.3 } ] }
  DEF Knee RigidTransform { translation 0 -0.5 0 children [
    ExponentialBlend { variance 0.25 children [ DEF knee Metaball { radius 0.2 } DEF kneecap Metaball { blendParam -3 } ] }
    DEF Foot RigidTransform { translation 0 -0.5 0 children [ ExponentialBlend { variance 0.5 children [ DEF foot Metaball { } ] } ] }
  ] }
] }
)");
  EXPECT_TRUE(c.hierarchical());
  EXPECT_EQ(c.blend().kind, BlendKind::Exponential);
  EXPECT_FLOAT_EQ(c.primitives()[primitiveNamed(c, "hip")].blendParam, -2.0f);
  EXPECT_FLOAT_EQ(c.primitives()[primitiveNamed(c, "knee")].blendParam, -4.0f);
  EXPECT_FLOAT_EQ(c.primitives()[primitiveNamed(c, "kneecap")].blendParam, -3.0f) << "a shape's own value wins";
  EXPECT_EQ(c.primitives()[primitiveNamed(c, "knee")].joint, c.findJoint("Knee"));
  EXPECT_TRUE(c.blends(primitiveNamed(c, "hip"), primitiveNamed(c, "knee")));
  EXPECT_FALSE(c.blends(primitiveNamed(c, "hip"), primitiveNamed(c, "foot"))) << "the rule still holds";
}

TEST(BlendGraph, ABlendNodeOfAnotherTypeThanTheCharactersSaysWhatToWrite) {
  auto scene = readScene(R"(#VRML V2.0 utf8
MarchingCubes { blendingFunction ExponentialBlend { } sceneGraph RigidTransform { children [
  Metaball { }
  BlancSchlickBlend { children [ Metaball { center 1 0 0 } ] }
] } }
)", "mixed.wrl");
  ASSERT_TRUE(scene.has_value()) << scene.error().str();
  auto c = Character::fromScene(*scene);
  ASSERT_FALSE(c.has_value());
  const std::string msg = c.error().str();
  EXPECT_NE(msg.find("mixed.wrl:4:3: error:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("BlancSchlickBlend"), std::string::npos) << msg;
  EXPECT_NE(msg.find("blendingFunction BlancSchlickBlend"), std::string::npos) << msg;
}

}  // namespace
}  // namespace imps
