// SPDX-License-Identifier: MIT
// VRML 97 Shapes to flat-shaded triangle meshes (see vrml_props.h).
#include "imps/vrml_props.h"

#include <cmath>
#include <numbers>

#include "imps/vrml_clip.h"  // TransformValues

namespace imps {

namespace {

constexpr size_t kMaxTriangles = 10'000'000;
constexpr int kRoundSegments = 32;  // around a Sphere, Cylinder or Cone
constexpr int kSphereRings = 16;

// Appends the triangle (a, b, c), counter-clockwise seen from outside, with its face normal and `color`.
void addTriangle(Mesh& m, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, const glm::vec3& color) {
  glm::vec3 n = glm::cross(b - a, c - a);
  const float length = glm::length(n);
  n = length > 0.0f ? n / length : glm::vec3(0, 1, 0);
  for (const glm::vec3& p : {a, b, c}) {
    m.indices.push_back(static_cast<uint32_t>(m.vertexCount()));
    m.positions.insert(m.positions.end(), {p.x, p.y, p.z});
    m.normals.insert(m.normals.end(), {n.x, n.y, n.z});
    m.colors.insert(m.colors.end(), {color.r, color.g, color.b});
  }
}

void addQuad(Mesh& m, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, const glm::vec3& d,
             const glm::vec3& color) {
  addTriangle(m, a, b, c, color);
  addTriangle(m, a, c, d, color);
}

glm::vec3 around(float radius, float y, int i) {
  const float angle = 2.0f * std::numbers::pi_v<float> * static_cast<float>(i) / kRoundSegments;
  return {radius * std::sin(angle), y, radius * std::cos(angle)};
}

const glm::vec3 kGrey(0.8f);

float numberOr(const VrmlNode& node, const char* field, float fallback) {
  const VrmlField* f = node.field(field);
  return f != nullptr && f->numbers.size() == 1 ? static_cast<float>(f->numbers[0]) : fallback;
}

bool flagOr(const VrmlNode& node, const char* field, bool fallback) {
  const VrmlField* f = node.field(field);
  return f != nullptr && f->numbers.size() == 1 ? f->numbers[0] != 0.0 : fallback;
}

const VrmlNode* childNode(const VrmlNode& node, const char* field) {
  const VrmlField* f = node.field(field);
  return f != nullptr && !f->nodes.empty() ? &f->nodes[0]->resolved() : nullptr;
}

glm::vec3 colorOf(const VrmlNode& shape) {
  const VrmlNode* appearance = childNode(shape, "appearance");
  const VrmlNode* material = appearance != nullptr ? childNode(*appearance, "material") : nullptr;
  const VrmlField* diffuse = material != nullptr ? material->field("diffuseColor") : nullptr;
  if (diffuse == nullptr || diffuse->numbers.size() != 3) return kGrey;
  return {static_cast<float>(diffuse->numbers[0]), static_cast<float>(diffuse->numbers[1]),
          static_cast<float>(diffuse->numbers[2])};
}

// A node's MFVec3f/MFColor field (`vector`, `color`) as triples; empty when absent or not whole triples (warned).
std::vector<glm::vec3> triplesOf(const VrmlNode* node, const char* field, Diagnostics& d) {
  std::vector<glm::vec3> out;
  const VrmlField* f = node != nullptr ? node->field(field) : nullptr;
  if (f == nullptr) return out;
  if (f->numbers.size() % 3 != 0) {
    d.warning(f->loc, std::string(field) + " has " + std::to_string(f->numbers.size()) +
                          " numbers, not a multiple of 3; it is ignored");
    return out;
  }
  for (size_t i = 0; i + 2 < f->numbers.size(); i += 3)
    out.emplace_back(float(f->numbers[i]), float(f->numbers[i + 1]), float(f->numbers[i + 2]));
  return out;
}

// An IndexedFaceSet's per-face or per-vertex values (Color or Normal, ISO/IEC 14772-1 6.23): which entry of `values`
// the corner `corner` (its place in coordIndex) of face `face` takes, or -1 when there is none.
struct PerFaceOrVertex {
  const std::vector<glm::vec3>* values = nullptr;
  bool perVertex = true;
  const VrmlField* index = nullptr;  // colorIndex / normalIndex (empty: coordIndex for per vertex, faces in order)
  const VrmlField* coordIndex = nullptr;
  long at(size_t face, size_t corner) const {
    if (values == nullptr || values->empty()) return -1;
    const bool indexed = index != nullptr && !index->numbers.empty();
    double i = -1;
    if (perVertex) {
      const VrmlField* from = indexed ? index : coordIndex;
      if (corner < from->numbers.size()) i = from->numbers[corner];
    } else {
      i = indexed ? (face < index->numbers.size() ? index->numbers[face] : -1) : double(face);
    }
    return i >= 0 && i < double(values->size()) ? long(i) : -1;
  }
};

// IndexedFaceSet: faces split at -1 (the last may omit it), fan-triangulated. Colours from its Color node (per face
// or per vertex, colorIndex) over the Material's; normals from its Normal node (per face or per vertex,
// normalIndex), else smoothed across edges whose faces meet at less than creaseAngle, else the face's own.
// *ownColors says whether a Color node coloured it.
Mesh faceSetMesh(const VrmlNode& g, const glm::vec3& color, Diagnostics& d, bool* ownColors) {
  Mesh m;
  *ownColors = false;
  const VrmlNode* coord = childNode(g, "coord");
  const VrmlField* point = coord != nullptr ? coord->field("point") : nullptr;
  const VrmlField* index = g.field("coordIndex");
  if (point == nullptr || index == nullptr) return m;
  if (point->numbers.size() % 3 != 0) {
    d.warning(point->loc, "Coordinate point has " + std::to_string(point->numbers.size()) +
                              " numbers, not a multiple of 3; the IndexedFaceSet is left out");
    return m;
  }
  const size_t points = point->numbers.size() / 3;
  auto at = [&](size_t i) {
    return glm::vec3(point->numbers[3 * i], point->numbers[3 * i + 1], point->numbers[3 * i + 2]);
  };
  const bool ccw = flagOr(g, "ccw", true);

  // Pass 1: the faces (point indices and where each corner is in coordIndex), bad ones left out with a warning.
  struct Face {
    std::vector<size_t> points, corners;
    size_t ordinal = 0;  // the face's number among all faces, bad ones included (colorIndex counts them)
    glm::vec3 normal{0.0f};
  };
  std::vector<Face> faces;
  Face face;
  size_t ordinal = 0;
  bool warned = false;
  auto flush = [&] {
    if (face.points.empty()) return;
    bool ok = face.points.size() >= 3;
    for (size_t i : face.points) ok = ok && i < points;
    if (!ok && !warned) {
      warned = true;
      d.warning(index->loc, "coordIndex has a face with fewer than 3 points or an index beyond the " +
                                std::to_string(points) + " points; such faces are left out");
    }
    face.ordinal = ordinal++;
    if (ok) {
      // Newell's normal of the polygon, facing the side ccw says is the outside.
      glm::vec3 n(0.0f);
      for (size_t k = 0; k < face.points.size(); ++k)
        n += glm::cross(at(face.points[k]), at(face.points[(k + 1) % face.points.size()]));
      const float length = glm::length(n);
      face.normal = length > 0.0f ? (ccw ? n : -n) / length : glm::vec3(0, 1, 0);
      faces.push_back(std::move(face));
    }
    face = Face{};
  };
  for (size_t k = 0; k < index->numbers.size(); ++k) {
    const double i = index->numbers[k];
    if (i < 0) {
      flush();
    } else {
      face.points.push_back(i < 4e9 ? static_cast<size_t>(i) : points);
      face.corners.push_back(k);
    }
  }
  flush();

  // Pass 2: colours and normals the file gives.
  const VrmlNode* colorNode = childNode(g, "color");
  const std::vector<glm::vec3> colors = triplesOf(colorNode, "color", d);
  const PerFaceOrVertex colorOf{&colors, flagOr(g, "colorPerVertex", true), g.field("colorIndex"), index};
  *ownColors = !colors.empty();
  const VrmlNode* normalNode = childNode(g, "normal");
  const std::vector<glm::vec3> normals = triplesOf(normalNode, "vector", d);
  const PerFaceOrVertex normalOf{&normals, flagOr(g, "normalPerVertex", true), g.field("normalIndex"), index};
  const float crease = numberOr(g, "creaseAngle", 0.0f);
  const float cosCrease = std::cos(std::min(crease, std::numbers::pi_v<float>));

  // Faces around each point, for smoothing below the crease angle.
  std::vector<std::vector<uint32_t>> facesAt;
  if (normals.empty() && crease > 0.0f) {
    facesAt.resize(points);
    for (size_t f = 0; f < faces.size(); ++f)
      for (size_t p : faces[f].points)
        if (facesAt[p].empty() || facesAt[p].back() != f) facesAt[p].push_back(uint32_t(f));
  }
  auto cornerNormal = [&](const Face& f, size_t k) {
    if (const long i = normalOf.at(f.ordinal, f.corners[k]); i >= 0) {
      const glm::vec3 n = (*normalOf.values)[size_t(i)];
      const float length = glm::length(n);
      return length > 0.0f ? n / length : f.normal;  // as the file gives it, whatever ccw says
    }
    if (facesAt.empty()) return f.normal;
    glm::vec3 sum(0.0f);
    for (uint32_t other : facesAt[f.points[k]])
      if (glm::dot(faces[other].normal, f.normal) >= cosCrease - 1e-6f) sum += faces[other].normal;
    const float length = glm::length(sum);
    return length > 0.0f ? sum / length : f.normal;
  };
  auto cornerColor = [&](const Face& f, size_t k) {
    const long i = colorOf.at(f.ordinal, f.corners[k]);
    return i >= 0 ? colors[size_t(i)] : color;
  };

  // Pass 3: fan triangles, three vertices of their own each.
  for (const Face& f : faces) {
    for (size_t k = 1; k + 1 < f.points.size() && m.triangleCount() < kMaxTriangles; ++k) {
      const size_t corners[3] = {0, ccw ? k : k + 1, ccw ? k + 1 : k};
      for (size_t c : corners) {
        const glm::vec3 p = at(f.points[c]), n = cornerNormal(f, c), rgb = cornerColor(f, c);
        m.indices.push_back(static_cast<uint32_t>(m.vertexCount()));
        m.positions.insert(m.positions.end(), {p.x, p.y, p.z});
        m.normals.insert(m.normals.end(), {n.x, n.y, n.z});
        m.colors.insert(m.colors.end(), {rgb.r, rgb.g, rgb.b});
      }
    }
  }
  return m;
}

Mesh transformedBy(const Mesh& mesh, const glm::mat4& matrix) {
  Mesh out = mesh;
  const glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(matrix)));
  const bool mirrored = glm::determinant(glm::mat3(matrix)) < 0.0f;
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    const glm::vec3 p = glm::vec3(matrix * glm::vec4(mesh.position(v), 1.0f));
    glm::vec3 n = normalMatrix * mesh.normal(v);
    const float length = glm::length(n);
    n = length > 0.0f ? n / length : n;
    for (int k = 0; k < 3; ++k) {
      out.positions[3 * v + k] = p[k];
      out.normals[3 * v + k] = n[k];
    }
  }
  if (mirrored)
    for (size_t t = 0; t < out.triangleCount(); ++t) std::swap(out.indices[3 * t + 1], out.indices[3 * t + 2]);
  return out;
}

void recolor(Mesh& m, const glm::vec3& color) {
  for (size_t v = 0; v < m.vertexCount(); ++v)
    for (int k = 0; k < 3; ++k) m.colors[3 * v + k] = color[k];
}

struct Walker {
  std::vector<Prop>& props;
  Diagnostics& d;
  size_t triangles = 0;
  bool warnedLimit = false;

  void shape(const VrmlNode& node, const std::string& name, const glm::mat4& matrix) {
    const VrmlNode* g = childNode(node, "geometry");
    if (g == nullptr) return;
    const glm::vec3 color = colorOf(node);
    Mesh local;
    bool ownColors = false;  // an IndexedFaceSet's Color node coloured it
    const float positive = 1e-9f;
    if (g->type == "IndexedFaceSet") {
      local = faceSetMesh(*g, color, d, &ownColors);
    } else if (g->type == "Box") {
      const VrmlField* size = g->field("size");
      const glm::vec3 s = size != nullptr && size->numbers.size() == 3
                              ? glm::vec3(size->numbers[0], size->numbers[1], size->numbers[2])
                              : glm::vec3(2.0f);
      if (s.x > positive && s.y > positive && s.z > positive) local = boxMesh(s);
    } else if (g->type == "Sphere") {
      const float r = numberOr(*g, "radius", 1.0f);
      if (r > positive) local = sphereMesh(r);
    } else if (g->type == "Cylinder") {
      const float r = numberOr(*g, "radius", 1.0f), h = numberOr(*g, "height", 2.0f);
      if (r > positive && h > positive) local = cylinderMesh(r, h);
    } else if (g->type == "Cone") {
      const float r = numberOr(*g, "bottomRadius", 1.0f), h = numberOr(*g, "height", 2.0f);
      if (r > positive && h > positive) local = coneMesh(r, h);
    } else {
      d.warning(g->loc, g->type + " geometry is not drawn as a prop (IndexedFaceSet, Box, Sphere, Cylinder and Cone "
                                  "are)");
      return;
    }
    if (local.triangleCount() == 0) {
      d.warning(g->loc, g->type + " has no triangles (sizes must be > 0); the prop is left out");
      return;
    }
    if (triangles + local.triangleCount() > kMaxTriangles) {
      if (!warnedLimit) d.warning(node.loc, "more than 10,000,000 prop triangles; the rest are left out");
      warnedLimit = true;
      return;
    }
    triangles += local.triangleCount();
    if (!ownColors) recolor(local, color);
    std::string propName = !node.defName.empty() ? node.defName : !g->defName.empty() ? g->defName : name;
    if (propName.empty()) propName = "prop" + std::to_string(props.size() + 1);
    props.push_back({propName, g->type, transformedBy(local, matrix), node.loc});
  }

  void walk(const VrmlNode& written, const std::string& name, const glm::mat4& matrix, int depth) {
    if (depth > 256 || warnedLimit) return;
    const VrmlNode& node = written.resolved();
    if (node.type == "Shape") {
      shape(node, name, matrix);
      return;
    }
    glm::mat4 here = matrix;
    std::string nearest = written.defName.empty() ? name : written.defName;
    if (node.type == "Transform") {
      TransformValues v;
      const VrmlField* f = nullptr;
      auto vec = [&](const char* field, glm::vec3 fallback) {
        f = node.field(field);
        return f != nullptr && f->numbers.size() == 3 ? glm::vec3(f->numbers[0], f->numbers[1], f->numbers[2])
                                                      : fallback;
      };
      auto rot = [&](const char* field) {
        f = node.field(field);
        if (f == nullptr || f->numbers.size() != 4) return glm::quat(1, 0, 0, 0);
        const glm::vec3 axis(f->numbers[0], f->numbers[1], f->numbers[2]);
        const float length = glm::length(axis);
        return length > 0.0f ? glm::angleAxis(static_cast<float>(f->numbers[3]), axis / length) : glm::quat(1, 0, 0, 0);
      };
      v.translation = vec("translation", v.translation);
      v.center = vec("center", v.center);
      v.scale = vec("scale", v.scale);
      v.rotation = rot("rotation");
      v.scaleOrientation = rot("scaleOrientation");
      here = matrix * v.matrix();
    }
    if (node.type != "Transform" && node.type != "Group" && node.type != "Anchor" && node.type != "Billboard" &&
        node.type != "Collision" && !written.protoBody)
      return;  // sensors, interpolators, lights …: no Shapes below
    for (const VrmlField& field : node.fields) {
      if (field.name != "children") continue;
      for (const VrmlNodeRef& child : field.nodes) walk(*child, nearest, here, depth + 1);
    }
  }
};

}  // namespace

Mesh boxMesh(const glm::vec3& size) {
  Mesh m;
  const glm::vec3 h = size * 0.5f;
  auto c = [&](float x, float y, float z) { return glm::vec3(x * h.x, y * h.y, z * h.z); };
  addQuad(m, c(-1, -1, 1), c(1, -1, 1), c(1, 1, 1), c(-1, 1, 1), kGrey);      // +z
  addQuad(m, c(1, -1, -1), c(-1, -1, -1), c(-1, 1, -1), c(1, 1, -1), kGrey);  // -z
  addQuad(m, c(1, -1, 1), c(1, -1, -1), c(1, 1, -1), c(1, 1, 1), kGrey);      // +x
  addQuad(m, c(-1, -1, -1), c(-1, -1, 1), c(-1, 1, 1), c(-1, 1, -1), kGrey);  // -x
  addQuad(m, c(-1, 1, 1), c(1, 1, 1), c(1, 1, -1), c(-1, 1, -1), kGrey);      // +y
  addQuad(m, c(-1, -1, -1), c(1, -1, -1), c(1, -1, 1), c(-1, -1, 1), kGrey);  // -y
  return m;
}

Mesh sphereMesh(float radius) {
  Mesh m;
  auto at = [&](int ring, int i) {
    const float theta = std::numbers::pi_v<float> * static_cast<float>(ring) / kSphereRings;
    return glm::vec3(around(radius * std::sin(theta), radius * std::cos(theta), i));
  };
  for (int ring = 0; ring < kSphereRings; ++ring) {
    for (int i = 0; i < kRoundSegments; ++i) {
      const glm::vec3 a = at(ring, i), b = at(ring + 1, i), c = at(ring + 1, i + 1), d = at(ring, i + 1);
      if (ring > 0) addTriangle(m, a, b, d, kGrey);
      if (ring + 1 < kSphereRings) addTriangle(m, b, c, d, kGrey);
    }
  }
  return m;
}

Mesh cylinderMesh(float radius, float height) {
  Mesh m;
  const float y = height * 0.5f;
  for (int i = 0; i < kRoundSegments; ++i) {
    const glm::vec3 b0 = around(radius, -y, i), b1 = around(radius, -y, i + 1);
    const glm::vec3 t0 = around(radius, y, i), t1 = around(radius, y, i + 1);
    addQuad(m, b0, b1, t1, t0, kGrey);
    addTriangle(m, glm::vec3(0, y, 0), t0, t1, kGrey);
    addTriangle(m, glm::vec3(0, -y, 0), b1, b0, kGrey);
  }
  return m;
}

Mesh coneMesh(float bottomRadius, float height) {
  Mesh m;
  const float y = height * 0.5f;
  for (int i = 0; i < kRoundSegments; ++i) {
    const glm::vec3 b0 = around(bottomRadius, -y, i), b1 = around(bottomRadius, -y, i + 1);
    addTriangle(m, b0, b1, glm::vec3(0, y, 0), kGrey);
    addTriangle(m, glm::vec3(0, -y, 0), b1, b0, kGrey);
  }
  return m;
}

Mesh transformed(const Mesh& mesh, const Rigid& pose) {
  Mesh out = mesh;
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    const glm::vec3 p = pose.apply(mesh.position(v));
    for (int k = 0; k < 3; ++k) out.positions[3 * v + k] = p[k];
    if (!mesh.normals.empty()) {
      const glm::vec3 n = pose.rotation * mesh.normal(v);
      for (int k = 0; k < 3; ++k) out.normals[3 * v + k] = n[k];
    }
  }
  return out;
}

Mesh transformed(const Mesh& mesh, const glm::mat4& matrix) { return transformedBy(mesh, matrix); }

std::vector<Prop> readProps(const VrmlFile& file, Diagnostics* warnings) {
  std::vector<Prop> props;
  Diagnostics d;
  Walker walker{props, d};
  for (const VrmlNodeRef& root : file.roots) walker.walk(*root, "", glm::mat4(1.0f), 0);
  if (warnings != nullptr) warnings->append(d);
  return props;
}

}  // namespace imps
