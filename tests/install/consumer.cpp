// Reads a scene, compiles the character and meshes it with Marching Cubes through the installed headers and
// library; prints "closed TRIANGLES" when the mesh is a closed 2-manifold.
#include <cstdio>

#include "imps/character.h"
#include "imps/marching_cubes.h"
#include "imps/mesh.h"
#include "imps/scene_reader.h"
#include "imps/skeleton_cache.h"

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  auto scene = imps::readSceneFile(argv[1]);
  if (!scene) return std::fprintf(stderr, "%s\n", scene.error().str().c_str()), 1;
  auto character = imps::Character::fromScene(*scene);
  if (!character) return std::fprintf(stderr, "%s\n", character.error().str().c_str()), 1;
  imps::SkeletonCache cache(*character);
  imps::MarchingCubesOptions options;
  options.resolution = 32;
  const imps::Mesh mesh = imps::polygonize(cache.field(), options);
  const bool closed = imps::analyzeTopology(mesh).closedManifold();
  std::printf("%s %zu\n", closed ? "closed" : "open", mesh.triangleCount());
  return closed && mesh.triangleCount() > 0 ? 0 : 1;
}
