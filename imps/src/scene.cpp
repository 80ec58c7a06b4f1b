// SPDX-License-Identifier: MIT
// Scene document: equality (ignoring source locations) and accessors.
#include <utility>

#include "imps/scene.h"

namespace imps {

bool Material::operator==(const Material& o) const {
  return name == o.name && diffuseColor == o.diffuseColor && emissiveColor == o.emissiveColor &&
         specularColor == o.specularColor && ambientIntensity == o.ambientIntensity && shininess == o.shininess &&
         transparency == o.transparency && useOf == o.useOf;
}

bool TexGenNode::operator==(const TexGenNode& o) const {
  if (kind != o.kind || translation != o.translation || rotation != o.rotation) return false;
  return kind == TexGenKind::Sphere || (width == o.width && height == o.height);
}

bool ShapeNode::operator==(const ShapeNode& o) const {
  if (kind != o.kind || name != o.name || blendParam != o.blendParam || material != o.material || useOf != o.useOf ||
      texGen != o.texGen || texture != o.texture)
    return false;
  switch (kind) {
    case ShapeKind::Metaball: return center == o.center && radius == o.radius;
    case ShapeKind::Ellipsoid: return center == o.center && orientation == o.orientation && radii == o.radii;
    case ShapeKind::LineSeg:
      return point1 == o.point1 && point2 == o.point2 && radius1 == o.radius1 && radius2 == o.radius2;
  }
  return false;
}

bool BlendNode::operator==(const BlendNode& o) const {
  if (kind != o.kind || name != o.name || children != o.children || useOf != o.useOf) return false;
  switch (kind) {
    case BlendKind::Exponential: return variance == o.variance && fastExp == o.fastExp;
    case BlendKind::BlancSchlick: return hardness == o.hardness;
    case BlendKind::Elliptical: return blendRange == o.blendRange;
  }
  return false;
}

bool TransformNode::operator==(const TransformNode& o) const {
  return name == o.name && translation == o.translation && rotation == o.rotation && children == o.children &&
         useOf == o.useOf;
}

bool Tesselator3MPNode::operator==(const Tesselator3MPNode& o) const {
  return deltaT == o.deltaT && desiredRadius == o.desiredRadius && queryRadius == o.queryRadius &&
         energyCoeff == o.energyCoeff && surfaceCoeff == o.surfaceCoeff && fissioningFrac == o.fissioningFrac &&
         isoValue == o.isoValue && useSimpleRadii == o.useSimpleRadii && numThreads == o.numThreads &&
         updatesPerRender == o.updatesPerRender && colorWidth == o.colorWidth && textureMode == o.textureMode &&
         doDifferentialTransforms == o.doDifferentialTransforms && seed == o.seed &&
         blendingFunction == o.blendingFunction && spatialSubdivision == o.spatialSubdivision &&
         sceneGraph == o.sceneGraph;
}

bool MarchingCubesNode::operator==(const MarchingCubesNode& o) const {
  return cellSize == o.cellSize && xResolution == o.xResolution && yResolution == o.yResolution &&
         zResolution == o.zResolution && isoValue == o.isoValue && numThreads == o.numThreads &&
         blendingFunction == o.blendingFunction && sceneGraph == o.sceneGraph;
}

const SceneNode* Scene::sceneGraph() const {
  if (const auto* t = std::get_if<Tesselator3MPNode>(&polygonizer)) return t->sceneGraph ? &*t->sceneGraph : nullptr;
  if (const auto* m = std::get_if<MarchingCubesNode>(&polygonizer)) return m->sceneGraph ? &*m->sceneGraph : nullptr;
  return root ? &*root : nullptr;
}

SceneNode* Scene::sceneGraph() { return const_cast<SceneNode*>(std::as_const(*this).sceneGraph()); }

const BlendNode* Scene::blendingFunction() const {
  if (const auto* t = std::get_if<Tesselator3MPNode>(&polygonizer))
    return t->blendingFunction ? &*t->blendingFunction : nullptr;
  if (const auto* m = std::get_if<MarchingCubesNode>(&polygonizer))
    return m->blendingFunction ? &*m->blendingFunction : nullptr;
  return nullptr;
}

bool Scene::operator==(const Scene& o) const {
  return polygonizer == o.polygonizer && root == o.root && blendGroups == o.blendGroups;
}

const char* blendTypeName(BlendKind kind) {
  switch (kind) {
    case BlendKind::Exponential: return "ExponentialBlend";
    case BlendKind::BlancSchlick: return "BlancSchlickBlend";
    case BlendKind::Elliptical: return "EllipticalBlend";
  }
  return "?";
}

}  // namespace imps
