// SPDX-License-Identifier: MIT
// Reading IMPS scene files (the VRML 2 dialect of thesis appendix A; docs/scene-format.md) into an imps::Scene.
#pragma once

#include <expected>
#include <string>
#include <string_view>

#include "imps/diagnostic.h"
#include "imps/scene.h"

namespace imps {

// Reads a whole scene file from `text`; `fileName` is used only in diagnostics (and kept in Scene::fileName).
//
// On success returns the scene: every node and field of the file, USE copies expanded (a USE copy has an empty
// `name`, `useOf` set to the DEF name and `loc` at the USE). On failure returns every diagnostic, errors and
// warnings in file order, each printed by Diagnostic::str() as `file:line:column: error: message`; reading goes on
// after an error where that is safe, so one run reports up to 50 errors. Any error makes the result an error:
// nothing is ever silently defaulted.
//
// Warnings (the scene is still usable: a DEF name defined twice, a LineSeg whose one end sphere contains the
// other) are returned through `warnings` when it is not null: they are appended to it, on success and on failure
// alike. Without the out-parameter, warnings of a successful read are dropped.
//
// Never throws for bad input (only std::bad_alloc), never crashes or hangs: the input may be any bytes.
// Thread-safe: calls share no state.
std::expected<Scene, Diagnostics> readScene(std::string_view text, const std::string& fileName);
std::expected<Scene, Diagnostics> readScene(std::string_view text, const std::string& fileName,
                                            Diagnostics* warnings);

// Reads the file at `path` with readScene. A file that cannot be opened or read (missing, a directory, larger than
// 256 MiB) gives one diagnostic `path: error: cannot read scene file: reason`.
std::expected<Scene, Diagnostics> readSceneFile(const std::string& path);
std::expected<Scene, Diagnostics> readSceneFile(const std::string& path, Diagnostics* warnings);

}  // namespace imps
