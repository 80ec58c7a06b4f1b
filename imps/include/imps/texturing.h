// SPDX-License-Identifier: MIT
// Texture layers of a polygonized mesh (thesis 3.9, without its seams): per vertex, the two textured primitives
// that contribute most, weighted by their normalised field contributions, as colours are blended.
//
// Based on: K. Russell, "IMPS: Implicit Surfaces for Interactive Animated Characters", MIT 1999, section 3.9
//           (per-primitive generators, ownership) and 3.10.1 (Zonenschein et al.'s normalised contributions, used
//           here for the blend weights of the textures instead of the thesis's hard Voronoi cut).
#pragma once

#include <cstdint>
#include <span>

#include "imps/field.h"
#include "imps/mesh.h"
#include "imps/skeleton_cache.h"
#include "imps/texgen.h"

namespace imps {

// Fills mesh's texture layers (mesh.h) from the field. `gens[i]` is primitive i's generator in the mesh's space or
// null (size: field.size()); `images[i]` its image (-1: none; same size). Every primitive with a generator is one
// layer, in primitive order. At each vertex the members of the field's winning blend set weigh in by their
// contributions (Field::contributions), normalised over all of them: the two textured primitives with the largest
// weights become the vertex's layers (ties: the lower index first), their weights scaled up so that the textured
// share of the vertex stays what all textured members contribute; untextured members' share is the colour alone.
// A mesh of a field without generators gets no layers (and the pass costs one scan of `gens`). `threads` as
// parallelFor's. The result does not depend on the thread count.
void textureMesh(Mesh& mesh, const Field& field, std::span<const TexGen* const> gens, std::span<const int32_t> images,
                 int threads = 0);
// The same for a posed character: its world-space generators and images (a no-op when it has none).
void textureMesh(Mesh& mesh, const SkeletonCache& cache, int threads = 0);

// A textured mesh cut for formats with one texture per material (glTF, OBJ): each triangle goes to the part of the
// layer that weighs most in it (summed over its corners; a triangle without layers, or whose heaviest layer has no
// image, goes to the untextured part, image -1). Each part has its own vertices (positions, normals and colours
// copied) with the part's layer's (u, v) (Mesh::layerUv: carried, or from its generator); a triangle spanning a
// sphere generator's seam gets its own corners with u unwrapped, so no triangle smears the whole image. Parts come
// in ascending image order, the untextured one first; empty parts are left out. The blend between layers is lost:
// formats with one texture per material show the heaviest one (the renderers blend).
struct TexturedPart {
  int32_t image = -1;
  Mesh mesh;                  // positions, normals, colors, indices; no layers
  std::vector<float> uvs;     // 2 per vertex of `mesh`: (u, v), v up
};
std::vector<TexturedPart> splitByTexture(const Mesh& mesh);

}  // namespace imps
