// SPDX-License-Identifier: MIT
// Prints a hash of every mesh the two polygonizers make of the examples, so that two builds can be compared for
// bit-identical output (used to check refactors that must not change behaviour):
//   g++ -std=c++23 -O2 -Iimps/include scripts/mesh_identity.cpp build/imps/libimps.a -ltbb -o mesh_identity
//   ./mesh_identity /path/to/examples > hashes.txt   (then diff the files of two builds)
// Marching Cubes at a few cell sizes (the B = -2 swarm at 0.05 and 0.025 m), the tesselator for 60 updates with a joint
// moving every update and a triangulation every 10; each with 1 and 2 threads. One line per mesh: name, vertices,
// triangles, FNV-1a of the position, normal, colour and index bytes.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "imps/character.h"
#include "imps/marching_cubes.h"
#include "imps/scene_reader.h"
#include "imps/skeleton_cache.h"
#include "imps/tesselator.h"

namespace {

uint64_t fnv(uint64_t h, const void* data, size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}

void print(const std::string& name, const imps::Mesh& m) {
  uint64_t h = 0xcbf29ce484222325ull;
  h = fnv(h, m.positions.data(), m.positions.size() * sizeof(float));
  h = fnv(h, m.normals.data(), m.normals.size() * sizeof(float));
  h = fnv(h, m.colors.data(), m.colors.size() * sizeof(float));
  h = fnv(h, m.indices.data(), m.indices.size() * sizeof(uint32_t));
  std::printf("%-48s %8zu %8zu %016llx\n", name.c_str(), m.positions.size() / 3, m.indices.size() / 3,
              static_cast<unsigned long long>(h));
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : "examples";
  for (const char* name :
       {"transformed_blobs", "textured_blobs", "beanito", "flubber", "simple_biped", "swarm_1000", "swarm_1000_b2"}) {
    auto scene = imps::readSceneFile(dir + "/" + name + ".wrl");
    if (!scene) {
      std::fprintf(stderr, "%s", scene.error().str().c_str());
      return 1;
    }
    auto ch = imps::Character::fromScene(*scene);
    if (!ch) return 1;
    for (int threads : {1, 2}) {
      imps::SkeletonCache skel(*ch);
      for (float cell : {0.1f, 0.05f, 0.025f}) {
        if (std::string(name) == "swarm_1000" && cell < 0.05f) continue;
        if (std::string(name) == "swarm_1000_b2" && cell > 0.05f) continue;
        imps::MarchingCubesOptions o;
        o.cellSize = cell;
        o.threads = threads;
        print(std::string(name) + " mc cell " + std::to_string(cell) + " t" + std::to_string(threads),
              imps::polygonize(skel.field(), o));
      }
      imps::MarchingCubesOptions plain;
      plain.threads = threads;
      plain.preserveThinFeatures = false;
      plain.resolution = 40;
      print(std::string(name) + " mc res 40 no-thin t" + std::to_string(threads),
            imps::polygonize(skel.field(), plain));
      if (std::string(name).starts_with("swarm")) continue;
      imps::TesselatorOptions to;
      if (const auto* node = std::get_if<imps::Tesselator3MPNode>(&scene->polygonizer))
        to = imps::TesselatorOptions::fromNode(*node);
      to.threads = threads;
      imps::Tesselator tess(to);
      imps::Mesh mesh;
      const int joint = ch->joints().empty() ? -1 : int(ch->joints().size() / 2);
      for (int u = 1; u <= 60; ++u) {
        if (joint >= 0) {
          skel.setRotation(joint, glm::angleAxis(0.01f * float(u), glm::vec3(0, 0, 1)));
          skel.update();
        }
        tess.update(skel);
        if (u % 10 == 0) {
          tess.triangulate(mesh);
          print(std::string(name) + " tess update " + std::to_string(u) + " t" + std::to_string(threads), mesh);
        }
      }
    }
  }
  return 0;
}
