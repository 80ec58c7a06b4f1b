// SPDX-License-Identifier: MIT
// `puppeteer check` for VRML 97 worlds and clips (see cli_world.h).
#include "cli_world.h"

#include <cctype>
#include <cstdio>
#include <set>
#include <string_view>

#include "cli.h"
#include "imps/file_read.h"
#include "imps/gzip.h"
#include "imps/vrml_clip.h"
#include "imps/vrml_file.h"
#include "imps/world.h"
#include "json_output.h"

namespace imps::app {

namespace {

// A Shape found in the world, with the DEF names of the Transforms above it.
struct PropInfo {
  std::string path;      // "Bip01/Box01" ("" at the top level)
  std::string geometry;  // "IndexedFaceSet", "Box", …, "none"
  std::string size;      // "8 points, 12 faces" / "size 1 2 3"
};

constexpr size_t kMaxListedProps = 1000;

std::string numbersText(const VrmlField* f) {
  std::string out;
  if (f == nullptr) return out;
  char buf[32];
  for (double v : f->numbers) {
    std::snprintf(buf, sizeof buf, "%s%g", out.empty() ? "" : " ", v);
    out += buf;
  }
  return out;
}

size_t faceCount(const VrmlField* coordIndex) {
  if (coordIndex == nullptr) return 0;
  size_t faces = 0;
  bool open = false;
  for (double i : coordIndex->numbers) {
    if (i < 0) {
      faces += open ? 1 : 0;
      open = false;
    } else {
      open = true;
    }
  }
  return faces + (open ? 1 : 0);  // the last face may omit its -1
}

PropInfo propOf(const VrmlNode& shape, const std::string& path) {
  PropInfo p{path, "none", ""};
  const VrmlField* geometry = shape.field("geometry");
  if (geometry == nullptr || geometry->nodes.empty()) return p;
  const VrmlNode& g = geometry->nodes[0]->resolved();
  p.geometry = g.type;
  if (g.type == "IndexedFaceSet") {
    const VrmlField* coord = g.field("coord");
    const VrmlField* point = coord != nullptr && !coord->nodes.empty() ? coord->nodes[0]->field("point") : nullptr;
    p.size = std::to_string(point != nullptr ? point->numbers.size() / 3 : 0) + " points, " +
             std::to_string(faceCount(g.field("coordIndex"))) + " faces";
  } else if (g.type == "Box") {
    p.size = "size " + (g.field("size") ? numbersText(g.field("size")) : std::string("2 2 2"));
  } else if (g.type == "Sphere") {
    p.size = "radius " + (g.field("radius") ? numbersText(g.field("radius")) : std::string("1"));
  } else if (g.type == "Cylinder" || g.type == "Cone") {
    const char* radius = g.type == "Cone" ? "bottomRadius" : "radius";
    p.size = std::string(radius) + " " + (g.field(radius) ? numbersText(g.field(radius)) : std::string("1")) +
             ", height " + (g.field("height") ? numbersText(g.field("height")) : std::string("2"));
  }
  return p;
}

// Every Shape under `node`, depth first; a USE'd subtree is listed where it is used (at most kMaxListedProps).
void collectProps(const VrmlNode& node, const std::string& path, std::vector<PropInfo>& props, int depth) {
  if (props.size() >= kMaxListedProps || depth > 256) return;
  const VrmlNode& n = node.resolved();
  if (n.type == "Shape") {
    props.push_back(propOf(n, path));
    return;
  }
  std::string here = path;
  if ((n.type == "Transform" || node.protoBody) && !node.defName.empty())
    here = path.empty() ? node.defName : path + "/" + node.defName;
  for (const VrmlField& f : n.fields)
    for (const VrmlNodeRef& child : f.nodes) collectProps(*child, here, props, depth + 1);
}

Json worldJson(const std::string& path, const Clips& clips, const std::vector<PropInfo>& props) {
  Json clipList = Json::array();
  for (const Clip& c : clips.clips) {
    Json tracks = Json::array();
    for (const ClipTrack& t : c.tracks)
      tracks.push_back({{"interpolator", t.interpolator}, {"type", t.interpolatorType}, {"target", t.target},
                        {"field", clipPropertyName(t.property)}, {"keys", t.keys.size()}});
    clipList.push_back({{"timeSensor", c.name}, {"duration", c.cycleInterval}, {"loop", c.loop},
                        {"targets", c.targets()}, {"tracks", std::move(tracks)}});
  }
  Json propList = Json::array();
  for (const PropInfo& p : props) propList.push_back({{"path", p.path}, {"geometry", p.geometry}, {"size", p.size}});
  return Json{{"file", path}, {"valid", true}, {"kind", "world"}, {"clips", std::move(clipList)},
              {"props", std::move(propList)}};
}

}  // namespace

bool isWorldFile(const std::string& path) {
  const std::string ext = extensionOf(path);
  if (ext != ".wrl" && ext != ".wrz" && ext != ".gz") return false;
  auto bytes = readFileText(path, size_t{256} << 20);
  if (!bytes) return false;
  std::string text = std::move(*bytes);
  if (isGzip(text)) {
    auto inflated = gunzip(text, size_t{256} << 20);
    if (!inflated) return true;  // a compressed file that does not decompress: the world reader says why
    text = std::move(*inflated);
  }
  if (!text.starts_with("#VRML") && !text.starts_with("\xEF\xBB\xBF#VRML")) return false;
  return !namesImpsNodes(text);
}

int runWorldCheck(const std::string& path, bool json) {
  Diagnostics warnings;
  auto file = readVrmlFile(path, &warnings);
  if (!file) {
    std::fputs(file.error().str().c_str(), stderr);
    return kExitInvalidInput;
  }
  auto clips = readClips(*file, &warnings);
  std::fputs(warnings.str().c_str(), stderr);
  if (!clips) {
    std::fputs(clips.error().str().c_str(), stderr);
    return kExitInvalidInput;
  }
  std::vector<PropInfo> props;
  for (const VrmlNodeRef& root : file->roots) collectProps(*root, "", props, 0);
  // The characters its Inlines place (docs/world-format.md#worlds), with their errors.
  Diagnostics worldWarnings;
  auto world = readWorldFile(path, &worldWarnings);
  if (!world) {
    std::fputs(world.error().str().c_str(), stderr);
    return kExitInvalidInput;
  }
  Json characters = Json::array();
  for (const WorldCharacter& c : world->characters) {
    const glm::vec3 t = c.placement.translation;
    characters.push_back({{"name", c.name}, {"scene", c.scenePath}, {"translation", {t.x, t.y, t.z}},
                          {"clip", c.clip ? Json(c.clip->name) : Json(nullptr)},
                          {"joints", c.character.joints().size()}});
  }
  if (json) {
    Json report = worldJson(path, *clips, props);
    report["characters"] = std::move(characters);
    printJson(report);
    return kExitOk;
  }
  std::printf("%s: valid VRML 97 world, %zu clip%s, %zu prop%s\n", path.c_str(), clips->clips.size(),
              clips->clips.size() == 1 ? "" : "s", props.size(), props.size() == 1 ? "" : "s");
  std::printf("clips (%zu):\n", clips->clips.size());
  for (const Clip& c : clips->clips) {
    std::string targets;
    for (const std::string& t : c.targets()) targets += " " + t;
    std::printf("  %s: TimeSensor, %g s%s, targets%s\n", c.name.c_str(), c.cycleInterval, c.loop ? ", loop" : "",
                targets.c_str());
    for (const ClipTrack& t : c.tracks)
      std::printf("    %-24s %-24s -> %s.%s, %zu keys\n", t.interpolator.c_str(), t.interpolatorType.c_str(),
                  t.target.c_str(), clipPropertyName(t.property), t.keys.size());
  }
  for (const ScalarTrack& s : clips->scalars)
    std::printf("  (not played) %s -> %s.%s, %zu keys, driven by %s\n", s.interpolator.c_str(), s.target.c_str(),
                s.field.c_str(), s.keys, s.timeSensor.c_str());
  std::printf("props (%zu%s):\n", props.size(), props.size() >= kMaxListedProps ? ", listing stopped" : "");
  for (const PropInfo& p : props)
    std::printf("  %-30s %-16s %s\n", p.path.empty() ? "(top level)" : p.path.c_str(), p.geometry.c_str(),
                p.size.c_str());
  if (!world->characters.empty()) {
    std::printf("characters (%zu):\n", world->characters.size());
    for (const WorldCharacter& c : world->characters) {
      const glm::vec3 t = c.placement.translation;
      std::printf("  %-16s %s at %g %g %g, %zu joints%s\n", c.name.c_str(), c.scenePath.c_str(), double(t.x),
                  double(t.y), double(t.z), c.character.joints().size(),
                  c.clip ? (", clip " + c.clip->name + " from " + c.clipPath).c_str() : "");
    }
  }
  return kExitOk;
}

}  // namespace imps::app
