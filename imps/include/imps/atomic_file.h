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

}  // namespace imps
