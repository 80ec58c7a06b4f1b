// SPDX-License-Identifier: MIT
// The scene document's own code (imps/src/scene.cpp): operator== compares every field a file can say (names and USE
// references included) and nothing else (not source locations, not the fields of another shape or blend kind, not a
// TexGenSphere's slide size, not the file name); sceneGraph() and blendingFunction() find what they name wherever
// the file put it; blendTypeName spells the node types.
#include "imps/scene.h"

#include <gtest/gtest.h>

#include <functional>
#include <vector>

namespace imps {
namespace {

// Each change of `matters` makes a copy of `base` unequal to it; each change of `ignored` leaves it equal.
template <typename T>
void expectCompared(const T& base, const std::vector<std::function<void(T&)>>& matters,
                    const std::vector<std::function<void(T&)>>& ignored) {
  ASSERT_TRUE(base == base);
  for (size_t k = 0; k < matters.size(); ++k) {
    T changed = base;
    matters[k](changed);
    EXPECT_FALSE(changed == base) << "change " << k << " is not seen";
    EXPECT_FALSE(base == changed) << "change " << k << " is not seen (other side)";
  }
  for (size_t k = 0; k < ignored.size(); ++k) {
    T changed = base;
    ignored[k](changed);
    EXPECT_TRUE(changed == base) << "ignored change " << k << " is seen";
  }
}

const SourceLoc kElsewhere{"other.wrl", 9, 9};
const ShapeNode kBall;  // a child to add

TEST(Scene, MaterialComparesEveryFieldButItsLocation) {
  expectCompared<Material>(
      Material{},
      {[](Material& m) { m.name = "M"; }, [](Material& m) { m.diffuseColor.y = 0.1f; },
       [](Material& m) { m.emissiveColor.z = 0.1f; }, [](Material& m) { m.specularColor.x = 0.1f; },
       [](Material& m) { m.ambientIntensity = 0.5f; }, [](Material& m) { m.shininess = 0.9f; },
       [](Material& m) { m.transparency = 0.5f; }, [](Material& m) { m.useOf = "M"; }},
      {[](Material& m) { m.loc = kElsewhere; }});
}

TEST(Scene, TexGenPlaneComparesItsSlideASphereDoesNot) {
  TexGenNode plane;
  plane.kind = TexGenKind::Plane;
  const std::vector<std::function<void(TexGenNode&)>> frame = {[](TexGenNode& t) { t.translation.x = 1; },
                                                               [](TexGenNode& t) { t.rotation.angle = 1; },
                                                               [](TexGenNode& t) {
                                                                 t.rotation.axis = {1, 0, 0};
                                                               }};
  auto planeMatters = frame;
  planeMatters.push_back([](TexGenNode& t) { t.width = 3; });
  planeMatters.push_back([](TexGenNode& t) { t.height = 3; });
  planeMatters.push_back([](TexGenNode& t) { t.kind = TexGenKind::Sphere; });
  expectCompared<TexGenNode>(plane, planeMatters, {[](TexGenNode& t) { t.loc = kElsewhere; }});
  expectCompared<TexGenNode>(TexGenNode{}, frame,
                             {[](TexGenNode& t) { t.width = 3; }, [](TexGenNode& t) { t.height = 3; },
                              [](TexGenNode& t) { t.loc = kElsewhere; }});
}

TEST(Scene, ShapeComparesTheFieldsOfItsKindOnly) {
  const std::vector<std::function<void(ShapeNode&)>> common = {
      [](ShapeNode& s) { s.name = "S"; },
      [](ShapeNode& s) { s.blendParam = -2.0f; },
      [](ShapeNode& s) { s.material = Material{}; },
      [](ShapeNode& s) { s.texGen = TexGenNode{}; },
      [](ShapeNode& s) {
        s.texture = ImageTextureNode{"a.png", {}};
      },
      [](ShapeNode& s) { s.useOf = "S"; },
  };
  auto with = [&](std::vector<std::function<void(ShapeNode&)>> own) {
    own.insert(own.end(), common.begin(), common.end());
    return own;
  };
  auto center = [](ShapeNode& s) { s.center.x = 2; };
  auto radius = [](ShapeNode& s) { s.radius = 2; };
  auto orientation = [](ShapeNode& s) { s.orientation.angle = 1; };
  auto radii = [](ShapeNode& s) { s.radii.z = 2; };
  auto point1 = [](ShapeNode& s) { s.point1.x = 2; };
  auto point2 = [](ShapeNode& s) { s.point2.x = 2; };
  auto radius1 = [](ShapeNode& s) { s.radius1 = 2; };
  auto radius2 = [](ShapeNode& s) { s.radius2 = 2; };
  auto loc = [](ShapeNode& s) { s.loc = kElsewhere; };

  ShapeNode metaball;
  expectCompared<ShapeNode>(metaball, with({center, radius, [](ShapeNode& s) { s.kind = ShapeKind::Ellipsoid; }}),
                            {orientation, radii, point1, point2, radius1, radius2, loc});
  ShapeNode ellipsoid;
  ellipsoid.kind = ShapeKind::Ellipsoid;
  expectCompared<ShapeNode>(ellipsoid, with({center, orientation, radii}),
                            {radius, point1, point2, radius1, radius2, loc});
  ShapeNode seg;
  seg.kind = ShapeKind::LineSeg;
  expectCompared<ShapeNode>(seg, with({point1, point2, radius1, radius2}), {center, radius, orientation, radii, loc});
  // Nested nodes compare by their own rules: a material's location is not compared either.
  ShapeNode a, b;
  a.material = Material{};
  b.material = Material{};
  b.material->loc = kElsewhere;
  EXPECT_TRUE(a == b);
}

TEST(Scene, BlendComparesTheParameterOfItsKindAndTheChildren) {
  auto variance = [](BlendNode& n) { n.variance = 2; };
  auto fastExp = [](BlendNode& n) { n.fastExp = true; };
  auto hardness = [](BlendNode& n) { n.hardness = 2; };
  auto blendRange = [](BlendNode& n) { n.blendRange = 0.25f; };
  auto children = [](BlendNode& n) { n.children.push_back(kBall); };
  auto name = [](BlendNode& n) { n.name = "B"; };
  auto useOf = [](BlendNode& n) { n.useOf = "B"; };
  auto loc = [](BlendNode& n) { n.loc = kElsewhere; };
  BlendNode exponential;
  expectCompared<BlendNode>(exponential, {variance, fastExp, children, name, useOf}, {hardness, blendRange, loc});
  BlendNode blanc;
  blanc.kind = BlendKind::BlancSchlick;
  expectCompared<BlendNode>(blanc, {hardness, children, name, useOf}, {variance, fastExp, blendRange, loc});
  BlendNode elliptical;
  elliptical.kind = BlendKind::Elliptical;
  expectCompared<BlendNode>(elliptical, {blendRange, children, name, useOf}, {variance, fastExp, hardness, loc});
  EXPECT_FALSE(exponential == blanc);
  // Children compare deeply.
  BlendNode one, two;
  one.children = {kBall};
  two.children = {kBall};
  std::get<ShapeNode>(two.children[0]).radius = 3;
  EXPECT_FALSE(one == two);
}

TEST(Scene, TransformAndPolygonizersCompareEveryField) {
  expectCompared<TransformNode>(
      TransformNode{},
      {[](TransformNode& t) { t.name = "J"; }, [](TransformNode& t) { t.translation.y = 1; },
       [](TransformNode& t) { t.rotation.angle = 1; }, [](TransformNode& t) { t.children.push_back(kBall); },
       [](TransformNode& t) { t.useOf = "J"; }},
      {[](TransformNode& t) { t.loc = kElsewhere; }});
  using T = Tesselator3MPNode;
  expectCompared<T>(
      T{},
      {[](T& t) { t.deltaT = 0.1f; }, [](T& t) { t.desiredRadius = 0.1f; }, [](T& t) { t.queryRadius = 0.1f; },
       [](T& t) { t.energyCoeff = 1; }, [](T& t) { t.surfaceCoeff = 1; }, [](T& t) { t.fissioningFrac = 0.25f; },
       [](T& t) { t.isoValue = 0.5f; }, [](T& t) { t.useSimpleRadii = false; }, [](T& t) { t.numThreads = 4; },
       [](T& t) { t.updatesPerRender = 2; }, [](T& t) { t.colorWidth = 1; },
       [](T& t) { t.doDifferentialTransforms = false; }, [](T& t) { t.seed = 2; },
       [](T& t) { t.blendingFunction = BlendNode{}; }, [](T& t) { t.spatialSubdivision.cubeSize = 1; },
       [](T& t) { t.spatialSubdivision.bitsPerDim = 4; }, [](T& t) { t.sceneGraph = ShapeNode{}; }},
      {[](T& t) { t.desiredRadiusLoc = kElsewhere; }});
  using M = MarchingCubesNode;
  expectCompared<M>(M{},
                    {[](M& m) { m.cellSize = 0.1f; }, [](M& m) { m.xResolution = 8; }, [](M& m) { m.yResolution = 8; },
                     [](M& m) { m.zResolution = 8; }, [](M& m) { m.isoValue = 0.5f; }, [](M& m) { m.numThreads = 2; },
                     [](M& m) { m.blendingFunction = BlendNode{}; }, [](M& m) { m.sceneGraph = ShapeNode{}; }},
                    {[](M& m) { m.resolutionLoc = kElsewhere; }});
}

TEST(Scene, SceneComparesPolygonizerRootAndGroupsButNotTheFileName) {
  expectCompared<Scene>(Scene{},
                        {[](Scene& s) { s.polygonizer = MarchingCubesNode{}; }, [](Scene& s) { s.root = ShapeNode{}; },
                         [](Scene& s) { s.blendGroups.push_back({}); }},
                        {[](Scene& s) { s.fileName = "x.wrl"; }});
  BlendGroupNode g;
  g.members = {"A"};
  expectCompared<BlendGroupNode>(
      g, {[](BlendGroupNode& x) { x.members.push_back("B"); }, [](BlendGroupNode& x) { x.blend = false; }},
      {[](BlendGroupNode& x) { x.loc = kElsewhere; }});
}

TEST(Scene, SceneGraphAndBlendingFunctionAreFoundWhereverTheyLive) {
  Scene bare;
  EXPECT_EQ(bare.sceneGraph(), nullptr);
  EXPECT_EQ(bare.blendingFunction(), nullptr);
  bare.root = TransformNode{};
  ASSERT_EQ(std::as_const(bare).sceneGraph(), &*bare.root);
  EXPECT_EQ(bare.blendingFunction(), nullptr) << "a bare root has no polygonizer's blend";

  Scene tess;
  Tesselator3MPNode t;
  tess.polygonizer = t;
  tess.root = ShapeNode{};  // not used with a polygonizer
  EXPECT_EQ(tess.sceneGraph(), nullptr);
  auto& tp = std::get<Tesselator3MPNode>(tess.polygonizer);
  tp.sceneGraph = ShapeNode{};
  tp.blendingFunction = BlendNode{};
  EXPECT_EQ(tess.sceneGraph(), &*tp.sceneGraph);
  EXPECT_EQ(tess.blendingFunction(), &*tp.blendingFunction);
  // The mutable accessor gives the same node, for editing in place.
  std::get<ShapeNode>(*tess.sceneGraph()).radius = 4;
  EXPECT_EQ(std::get<ShapeNode>(*tp.sceneGraph).radius, 4);

  Scene cubes;
  cubes.polygonizer = MarchingCubesNode{};
  auto& mp = std::get<MarchingCubesNode>(cubes.polygonizer);
  EXPECT_EQ(cubes.sceneGraph(), nullptr);
  EXPECT_EQ(cubes.blendingFunction(), nullptr);
  mp.sceneGraph = BlendNode{};
  mp.blendingFunction = BlendNode{};
  EXPECT_EQ(cubes.sceneGraph(), &*mp.sceneGraph);
  EXPECT_EQ(cubes.blendingFunction(), &*mp.blendingFunction);
}

TEST(Scene, BlendTypeNames) {
  EXPECT_STREQ(blendTypeName(BlendKind::Exponential), "ExponentialBlend");
  EXPECT_STREQ(blendTypeName(BlendKind::BlancSchlick), "BlancSchlickBlend");
  EXPECT_STREQ(blendTypeName(BlendKind::Elliptical), "EllipticalBlend");
}

}  // namespace
}  // namespace imps
