// SPDX-License-Identifier: MIT
// Saves that never lose data: every file the project writes goes through here.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace imps {

// Replaces `path` with `bytes` atomically: a temporary file beside it (same file system, unique name, created
// exclusively), written completely, fsync'ed, given the target's permissions if it exists (else 0666 less the
// umask), renamed over the target, and the directory fsync'ed. Readers see the old file or the new one, never a
// mix; after a crash the target is whole. On failure returns false, leaves `path` untouched, removes the temporary
// file and sets *error (if non-null) to "cannot save 'PATH': STEP: REASON".
bool writeFileAtomically(const std::string& path, std::span<const uint8_t> bytes, std::string* error);
bool writeFileAtomically(const std::string& path, std::string_view text, std::string* error);

// For a file written in pieces by its own writer (a session): a fresh sibling name for the temporary file,
// "PATH.tmp-PID-N" (N counts per process), to be created with O_EXCL, written and fsync'ed by the caller; then
// commitTemporaryFile gives it the target's permissions if the target exists, renames it over `path` and fsyncs
// the directory. On failure `temp` is removed, `path` is untouched and *error says why, as above.
std::string temporarySibling(const std::string& path);
bool commitTemporaryFile(const std::string& temp, const std::string& path, std::string* error);

}  // namespace imps
