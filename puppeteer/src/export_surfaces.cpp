// SPDX-License-Identifier: MIT
// Baked surface sequences: a mesh per frame of a take, numbered files.
#include "export_surfaces.h"

#include <filesystem>
#include <optional>
#include <variant>

#include "imps/marching_cubes.h"
#include "imps/mesh_io.h"
#include "imps/tesselator.h"

namespace imps::app {

std::string sequenceFileName(const std::string& pattern, size_t frame) {
  const size_t first = pattern.find('#');
  if (first == std::string::npos) return pattern;
  size_t last = first;
  while (last < pattern.size() && pattern[last] == '#') ++last;
  std::string number = std::to_string(frame);
  if (number.size() < last - first) number.insert(0, last - first - number.size(), '0');
  return pattern.substr(0, first) + number + pattern.substr(last);
}

std::expected<void, Diagnostics> writeSurfaceSequence(const Scene& scene, const Character& character, const Take& take,
                                                      const SurfaceSequenceOptions& options,
                                                      const std::string& pattern) {
  SkeletonCache skeleton(character);
  std::optional<Tesselator> tesselator;
  if (options.particles) {
    TesselatorOptions t = TesselatorOptions::forScene(scene, skeleton.field());
    tesselator.emplace(t);
  }
  // The pattern's folder is made when missing ("skin/take_####.ply").
  const std::filesystem::path folder = std::filesystem::path(pattern).parent_path();
  std::error_code ec;
  if (!folder.empty()) std::filesystem::create_directories(folder, ec);
  if (ec) return std::unexpected(singleError({}, folder.string() + ": cannot create the folder: " + ec.message()));
  MarchingCubesOptions mc;
  mc.cellSize = options.cellSize;
  Mesh mesh;
  for (size_t f = 0; f < take.frames(); ++f) {
    for (size_t j = 0; j < take.locals[f].size(); ++j) {
      skeleton.setRotation(static_cast<int>(j), take.locals[f][j].rotation);
      skeleton.setTranslation(static_cast<int>(j), take.locals[f][j].translation);
    }
    skeleton.update();
    if (tesselator) {
      if (f == 0) tesselator->settle(skeleton, mesh);
      else tesselator->frame(skeleton, mesh);
    } else {
      mesh = polygonize(skeleton.field(), mc);
    }
    if (auto written = writeMesh(mesh, sequenceFileName(pattern, f)); !written) return written;
    if (options.progress) options.progress(f + 1);
  }
  return {};
}

}  // namespace imps::app
