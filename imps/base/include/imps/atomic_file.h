// SPDX-License-Identifier: MIT
// Saves that never lose data: every file the project writes goes through here.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "imps/io_error.h"

namespace imps {

// Replaces `path` with `bytes` atomically: a temporary file beside it (same file system, unique name, created
// exclusively), written completely, fsync'ed, given the target's permissions if it exists (else 0666 less the
// umask), renamed over the target, and the directory fsync'ed. Readers see the old file or the new one, never a
// mix; after a crash the target is whole. On failure leaves `path` untouched, removes the temporary file and returns
// an IoError with path PATH, the errno as code, and as message the whole sentence the commands print,
// "cannot save 'PATH': STEP: REASON" (it names the file already: print message, not str()).
IoResult<void> writeFileAtomically(const std::string& path, std::span<const uint8_t> bytes);
IoResult<void> writeFileAtomically(const std::string& path, std::string_view text);

// For a file written in pieces by its own writer (a session): a fresh sibling name for the temporary file,
// "PATH.tmp-PID-N" (N counts per process), to be created with O_EXCL, written and fsync'ed by the caller; then
// commitTemporaryFile gives it the target's permissions if the target exists, renames it over `path` and fsyncs
// the directory. On failure `temp` is removed, `path` is untouched and the IoError says why, as above.
std::string temporarySibling(const std::string& path);
IoResult<void> commitTemporaryFile(const std::string& temp, const std::string& path);

}  // namespace imps
