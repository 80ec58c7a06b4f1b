// SPDX-License-Identifier: MIT
// Reading a 3D Studio MAX-style VRML 97 export of about 2 MB (a 40-bone chain with 400-key position and orientation
// interpolators per bone, and a 20,000-vertex skin mesh). Goal (issue 12): well under a second. Measured in a
// Release build: 45 ms CPU for 1.97 MB (98 ms wall on a loaded 2-core machine).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "imps/vrml_file.h"

namespace {

constexpr int kBones = 40;
constexpr int kKeys = 400;
constexpr int kMeshVertices = 20000;

// The bones nest as a chain, each with its interpolators in its children list (MAX's layout and commas).
std::string maxStyleExport() {
  std::string text = "#VRML V2.0 utf8\n\n# Produced by 3D Studio MAX VRML97 exporter (generated for the benchmark)\n";
  char buf[160];
  std::string routes;
  for (int b = 0; b < kBones; ++b) {
    std::snprintf(buf, sizeof buf, "DEF Bip01-Bone%02d Transform {\n  translation 0 0.1 0\n  children [\n", b);
    text += buf;
    std::snprintf(buf, sizeof buf, "    DEF Bip01-Bone%02d-TIMER TimeSensor { loop TRUE cycleInterval 13.3 },\n", b);
    text += buf;
    for (const char* kind : {"POS", "ROT"}) {
      const bool pos = kind[0] == 'P';
      std::snprintf(buf, sizeof buf, "    DEF Bip01-Bone%02d-%s-INTERP %sInterpolator {\n      key [", b, kind,
                    pos ? "Position" : "Orientation");
      text += buf;
      for (int k = 0; k < kKeys; ++k) {
        std::snprintf(buf, sizeof buf, "%.4f, ", static_cast<double>(k) / (kKeys - 1));
        text += buf;
      }
      text += "]\n      keyValue [";
      for (int k = 0; k < kKeys; ++k) {
        if (pos) std::snprintf(buf, sizeof buf, "%.4f %.4f %.4f, ", 0.01 * k, 0.1, -0.002 * k);
        else std::snprintf(buf, sizeof buf, "0.5774 0.5774 -0.5774 %.4f, ", 0.004 * k);
        text += buf;
      }
      text += "] },\n";
      std::snprintf(buf, sizeof buf,
                    "ROUTE Bip01-Bone%02d-TIMER.fraction_changed TO Bip01-Bone%02d-%s-INTERP.set_fraction\n"
                    "ROUTE Bip01-Bone%02d-%s-INTERP.value_changed TO Bip01-Bone%02d.set_%s\n",
                    b, b, kind, b, kind, b, pos ? "translation" : "rotation");
      routes += buf;
    }
  }
  text += "    Shape { geometry DEF Skin-FACES IndexedFaceSet {\n      coord DEF Skin-COORD Coordinate { point [\n";
  for (int v = 0; v < kMeshVertices; ++v) {
    std::snprintf(buf, sizeof buf, "        %.4f %.4f %.4f,\n", 0.001 * v, 0.5 + 0.0001 * v, -0.0003 * v);
    text += buf;
  }
  text += "      ] }\n      coordIndex [\n";
  for (int v = 0; v + 2 < kMeshVertices; v += 3) {
    std::snprintf(buf, sizeof buf, "        %d, %d, %d, -1,\n", v, v + 1, v + 2);
    text += buf;
  }
  text += "      ] } }\n";
  for (int b = 0; b < kBones; ++b) text += "  ]\n}\n";
  return text + routes;
}

void readMaxExport(benchmark::State& state) {
  const std::string text = maxStyleExport();
  for (auto _ : state) {
    auto file = imps::readVrml(text, "max.wrl");
    if (!file) {
      std::fprintf(stderr, "%s", file.error().str().c_str());
      std::abort();
    }
    benchmark::DoNotOptimize(file->roots.size());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * text.size()));
  state.counters["file_MB"] = static_cast<double>(text.size()) / 1e6;
}
BENCHMARK(readMaxExport)->Unit(benchmark::kMillisecond);

}  // namespace
