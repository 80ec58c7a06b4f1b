// SPDX-License-Identifier: MIT
// A take as a skinned, animated glTF 2.0 binary (.glb): the character's rest mesh (Marching Cubes), a skin whose
// joints are the character's hierarchy, per-vertex weights from the primitives' normalised field contributions (at
// most four joints per vertex), and the take as one animation (rotations of every joint, translations of the joints
// that move).
//
// Based on: the Khronos glTF 2.0 specification (skins, animations, GLB container).
#pragma once

#include <array>
#include <cstdint>
#include <expected>
#include <string>
#include <vector>

#include "export_take.h"
#include "imps/diagnostic.h"
#include "imps/mesh.h"

namespace imps::app {

struct GltfExportOptions {
  float cellSize = 0.02f;  // Marching Cubes cell for the rest mesh, metres
};

// Per vertex: up to four (joint, weight) pairs, weights > 0 summing to 1, heaviest first; unused slots (0, 0).
struct SkinWeights {
  std::vector<std::array<uint16_t, 4>> joints;
  std::vector<std::array<float, 4>> weights;
};

// Weights for `mesh` (in the rest pose): per vertex, each primitive's blend term at the vertex (its contribution
// to the field, 1 on its own surface) summed per joint (primitives without a joint count for joint 0), the four
// largest kept and normalised. A vertex no primitive reaches gets the joint of the primitive with the smallest
// normalised distance. The character must have at least one joint.
SkinWeights skinWeights(const Character& character, const Mesh& mesh);

// The .glb bytes, or one error without a location when the character has no joints (or more than a skin holds) or
// the rest mesh is empty.
std::expected<std::vector<uint8_t>, Diagnostics> encodeSkinnedGlb(const Character& character, const Take& take,
                                                                  const GltfExportOptions& options);
// encodeSkinnedGlb written atomically to `path`: fails with its error, or the save's "cannot save 'path': ...".
std::expected<void, Diagnostics> writeSkinnedGlb(const Character& character, const Take& take,
                                                 const GltfExportOptions& options, const std::string& path);

}  // namespace imps::app
