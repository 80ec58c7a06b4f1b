// SPDX-License-Identifier: MIT
// writeScene / saveSceneFile: the canonical text of a scene, and saving it atomically.
#include "imps/scene_writer.h"

#include "imps/atomic_file.h"


#include <cerrno>
#include <charconv>
#include <cstring>
#include <optional>
#include <vector>

namespace imps {

namespace {

std::string number(float f) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, f);  // shortest form that reads back exactly
  return std::string(buffer, result.ptr);
}
std::string vec3(const glm::vec3& v) { return number(v.x) + " " + number(v.y) + " " + number(v.z); }
std::string rotation(const Rotation& r) { return vec3(r.axis) + " " + number(r.angle); }
std::string boolean(bool b) { return b ? "TRUE" : "FALSE"; }
std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

class Writer {
 public:
  std::string take() { return std::move(out_); }

  void scene(const Scene& s) {
    out_ += "#VRML V2.0 utf8\n";
    if (const auto* t = std::get_if<Tesselator3MPNode>(&s.polygonizer)) {
      out_ += "\n";
      tesselator(*t);
    } else if (const auto* m = std::get_if<MarchingCubesNode>(&s.polygonizer)) {
      out_ += "\n";
      marchingCubes(*m);
    } else if (s.root) {
      out_ += "\n";
      sceneNode(*s.root);
    }
    for (const BlendGroupNode& g : s.blendGroups) {
      out_ += "\n";
      open("", "", "BlendGroup");
      std::string members = "[";
      for (const std::string& m : g.members) members += (members.size() > 1 ? " " : "") + quoted(m);
      field("members", members + "]");
      field("blend", boolean(g.blend));
      close();
    }
  }

 private:
  void line(const std::string& text) {
    out_.append(2 * static_cast<size_t>(depth_), ' ');
    out_ += text;
    out_ += '\n';
  }
  void field(const char* name, const std::string& value) { line(std::string(name) + " " + value); }

  // Starts a node (the caller has written `fieldName ` when it is a field's value), or writes `USE NAME` and
  // returns false.
  bool open(const std::string& name, const std::string& useOf, const char* type) {
    if (!useOf.empty()) {
      out_ += "USE " + useOf + "\n";
      return false;
    }
    out_ += (name.empty() ? std::string() : "DEF " + name + " ") + type + " {\n";
    ++depth_;
    return true;
  }
  void close() {
    --depth_;
    line("}");
  }
  // Writes `name ` and leaves the node that follows to finish the line.
  void nodeField(const char* name) {
    out_.append(2 * static_cast<size_t>(depth_), ' ');
    out_ += name;
    out_ += ' ';
  }

  void tesselator(const Tesselator3MPNode& t) {
    open("", "", "Tesselator3MP");
    field("deltaT", number(t.deltaT));
    field("desiredRadius", number(t.desiredRadius));
    field("queryRadius", number(t.queryRadius));
    field("energyCoeff", number(t.energyCoeff));
    field("surfaceCoeff", number(t.surfaceCoeff));
    field("fissioningFrac", number(t.fissioningFrac));
    field("isoValue", number(t.isoValue));
    field("useSimpleRadii", boolean(t.useSimpleRadii));
    field("numThreads", std::to_string(t.numThreads));
    field("updatesPerRender", std::to_string(t.updatesPerRender));
    field("colorWidth", number(t.colorWidth));
    field("doDifferentialTransforms", boolean(t.doDifferentialTransforms));
    field("seed", std::to_string(t.seed));
    if (t.textureMode == TextureMode::Carried) field("textureMode", "\"carried\"");  // projective: the default
    const bool functionFirst = !usesLater(t.blendingFunction);
    if (functionFirst) blendingFunction(t.blendingFunction);
    nodeField("spatialSubdivision");
    open("", "", "UniformHash");
    field("cubeSize", number(t.spatialSubdivision.cubeSize));
    field("bitsPerDim", std::to_string(t.spatialSubdivision.bitsPerDim));
    close();
    if (t.sceneGraph) {
      nodeField("sceneGraph");
      sceneNode(*t.sceneGraph);
    }
    if (!functionFirst) blendingFunction(t.blendingFunction);
    close();
  }

  void marchingCubes(const MarchingCubesNode& m) {
    open("", "", "MarchingCubes");
    if (m.cellSize != 0.0f) field("cellSize", number(m.cellSize));  // 0 means unset and is not a valid value
    field("xResolution", std::to_string(m.xResolution));
    field("yResolution", std::to_string(m.yResolution));
    field("zResolution", std::to_string(m.zResolution));
    field("isoValue", number(m.isoValue));
    field("numThreads", std::to_string(m.numThreads));
    const bool functionFirst = !usesLater(m.blendingFunction);
    if (functionFirst) blendingFunction(m.blendingFunction);
    if (m.sceneGraph) {
      nodeField("sceneGraph");
      sceneNode(*m.sceneGraph);
    }
    if (!functionFirst) blendingFunction(m.blendingFunction);
    close();
  }

  // A blendingFunction written `USE NAME` can only name a node DEF'd in the sceneGraph (nothing else in a file
  // comes before it), so it is written after the sceneGraph; otherwise before it, as in thesis figure A-1.
  static bool usesLater(const std::optional<BlendNode>& function) { return function && !function->useOf.empty(); }
  void blendingFunction(const std::optional<BlendNode>& function) {
    if (!function) return;
    nodeField("blendingFunction");
    blend(*function, false);
  }

  void sceneNode(const SceneNode& node) {
    if (const auto* s = std::get_if<ShapeNode>(&node)) shape(*s);
    if (const auto* t = std::get_if<TransformNode>(&node)) transform(*t);
    if (const auto* b = std::get_if<BlendNode>(&node)) blend(*b, true);
  }

  void children(const std::vector<SceneNode>& nodes) {
    if (nodes.empty()) return line("children []");
    line("children [");
    ++depth_;
    for (const SceneNode& c : nodes) {
      out_.append(2 * static_cast<size_t>(depth_), ' ');
      sceneNode(c);
    }
    --depth_;
    line("]");
  }

  // A polygonizer's blendingFunction has no children and is written without the field.
  void blend(const BlendNode& b, bool inSceneGraph) {
    const char* type = b.kind == BlendKind::Exponential    ? "ExponentialBlend"
                       : b.kind == BlendKind::BlancSchlick ? "BlancSchlickBlend"
                                                           : "EllipticalBlend";
    if (!open(b.name, b.useOf, type)) return;
    switch (b.kind) {
      case BlendKind::Exponential:
        field("variance", number(b.variance));
        field("fastExp", boolean(b.fastExp));
        break;
      case BlendKind::BlancSchlick: field("hardness", number(b.hardness)); break;
      case BlendKind::Elliptical: field("blendRange", number(b.blendRange)); break;
    }
    if (inSceneGraph || !b.children.empty()) children(b.children);
    close();
  }

  void transform(const TransformNode& t) {
    if (!open(t.name, t.useOf, "RigidTransform")) return;
    field("translation", vec3(t.translation));
    field("rotation", rotation(t.rotation));
    children(t.children);
    close();
  }

  void shape(const ShapeNode& s) {
    switch (s.kind) {
      case ShapeKind::Metaball:
        if (!open(s.name, s.useOf, "Metaball")) return;
        field("center", vec3(s.center));
        field("radius", number(s.radius));
        break;
      case ShapeKind::Ellipsoid:
        if (!open(s.name, s.useOf, "Ellipsoid")) return;
        field("center", vec3(s.center));
        field("orientation", rotation(s.orientation));
        field("radii", vec3(s.radii));
        break;
      case ShapeKind::LineSeg:
        if (!open(s.name, s.useOf, "LineSeg")) return;
        field("point1", vec3(s.point1));
        field("point2", vec3(s.point2));
        field("radius1", number(s.radius1));
        field("radius2", number(s.radius2));
        break;
    }
    if (s.blendParam) field("blendParam", number(*s.blendParam));
    if (s.material) {
      nodeField("material");
      material(*s.material);
    }
    if (s.texGen) {
      nodeField("texGen");
      texGen(*s.texGen);
    }
    if (s.texture) {
      nodeField("texture");
      open("", "", "ImageTexture");
      field("url", quoted(s.texture->url));
      close();
    }
    close();
  }

  void texGen(const TexGenNode& g) {
    const bool plane = g.kind == TexGenKind::Plane;
    open("", "", plane ? "TexGenPlane" : "TexGenSphere");
    field("translation", vec3(g.translation));
    field("rotation", rotation(g.rotation));
    if (plane) {
      field("width", number(g.width));
      field("height", number(g.height));
    }
    close();
  }

  void material(const Material& m) {
    if (!open(m.name, m.useOf, "Material")) return;
    const Material defaults;
    field("diffuseColor", vec3(m.diffuseColor));
    if (m.emissiveColor != defaults.emissiveColor) field("emissiveColor", vec3(m.emissiveColor));
    if (m.specularColor != defaults.specularColor) field("specularColor", vec3(m.specularColor));
    if (m.ambientIntensity != defaults.ambientIntensity) field("ambientIntensity", number(m.ambientIntensity));
    if (m.shininess != defaults.shininess) field("shininess", number(m.shininess));
    if (m.transparency != defaults.transparency) field("transparency", number(m.transparency));
    close();
  }

  std::string out_;
  int depth_ = 0;
};

}  // namespace

std::string writeScene(const Scene& scene) {
  Writer writer;
  writer.scene(scene);
  return writer.take();
}

IoResult<void> saveSceneFile(const Scene& scene, const std::string& path) {
  return writeFileAtomically(path, writeScene(scene));
}

}  // namespace imps
