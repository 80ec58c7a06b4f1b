// SPDX-License-Identifier: MIT
// Uses every installed library through the installed headers: meshes a scene with Marching Cubes (imps), maps a clip
// joint onto its character (calibration), turns a BVH clip into a session and back (sim), and lists serial ports
// through libserialport (drivers). Prints "closed TRIANGLES FRAMES" when the mesh is a closed 2-manifold, the
// joint map names the character's joint and the clip survives the round trip.
#include <cstdio>

#include "calibration/joint_map.h"
#include "drivers/serial_transport.h"
#include "imps/character.h"
#include "imps/marching_cubes.h"
#include "imps/mesh.h"
#include "imps/scene_reader.h"
#include "imps/skeleton_cache.h"
#include "sim/bvh.h"
#include "sim/bvh_session.h"

namespace {

constexpr const char* kClip =
    "HIERARCHY\nROOT LeftArm\n{\n\tOFFSET 0 0 0\n\tCHANNELS 3 Zrotation Xrotation Yrotation\n}\n"
    "MOTION\nFrames: 2\nFrame Time: 0.5\n10 20 30\n-10 -20 -30\n";

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  auto scene = imps::readSceneFile(argv[1]);
  if (!scene) return std::fprintf(stderr, "%s", scene.error().str().c_str()), 1;
  auto character = imps::Character::fromScene(*scene);
  if (!character) return std::fprintf(stderr, "%s", character.error().str().c_str()), 1;
  imps::SkeletonCache cache(*character);
  imps::MarchingCubesOptions options;
  options.resolution = 32;
  const imps::Mesh mesh = imps::polygonize(cache.field(), options);
  const bool closed = imps::analyzeTopology(mesh).closedManifold();

  // calibration: a joint map checked against the clip's joints and the character's.
  auto map = imps::calibration::parseJointMap(R"({"version": 1, "joints": {"LeftArm": "L_UpperArm"}})", "map.json",
                                              {"LeftArm"}, &*character);
  if (!map) return std::fprintf(stderr, "%s", map.error().str().c_str()), 1;
  if (map->size() != 1 || (*map)[0].character != "L_UpperArm") return std::fprintf(stderr, "wrong joint map\n"), 1;

  // sim: a clip becomes a session of encoder counts and comes back as the same motion.
  auto clip = imps::sim::readBvhText(kClip, "arm.bvh");
  if (!clip) return std::fprintf(stderr, "%s", clip.error().str().c_str()), 1;
  auto session = imps::sim::bvhToSession(*clip, "arm.bvh");
  if (!session) return std::fprintf(stderr, "%s", session.error().str().c_str()), 1;
  auto back = imps::sim::sessionToBvh(*session);
  if (!back) return std::fprintf(stderr, "%s", back.error().str().c_str()), 1;
  if (back->joints != clip->joints || back->frames.size() != clip->frames.size())
    return std::fprintf(stderr, "the clip did not survive the session round trip\n"), 1;

  // drivers: enumerating serial ports runs libserialport (a machine may have none; an error is a message, not a crash).
  auto ports = imps::drivers::listSerialPorts();
  if (!ports) std::fprintf(stderr, "note: %s\n", imps::drivers::errorText(ports.error()).c_str());

  std::printf("%s %zu %zu\n", closed ? "closed" : "open", mesh.triangleCount(), back->frames.size());
  return closed && mesh.triangleCount() > 0 ? 0 : 1;
}
