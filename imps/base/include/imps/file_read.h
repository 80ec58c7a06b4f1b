// SPDX-License-Identifier: MIT
// Reading a whole input file with a size limit, so a huge or endless input (/dev/zero, a pipe that never closes)
// is refused with a message instead of growing memory until the process dies.
#pragma once

#include <cstddef>
#include <expected>
#include <filesystem>
#include <string>

#include "imps/diagnostic.h"
#include "imps/io_error.h"

namespace imps {

// The whole contents of `path`, or why it cannot be read: an IoError whose path is `path` and whose message is the
// reason alone (readers put it in their own diagnostic): the system's error text ("No such file or directory",
// "Is a directory", with its errno as code), or "larger than the N MiB limit (IMPS_MAX_INPUT_MIB=N raises it)" once
// more than the limit was read (without reading further; code 0). The limit is `maxBytes`, the reader's default,
// unless the environment variable IMPS_MAX_INPUT_MIB gives one in MiB (a positive whole number; anything else is an
// error naming the variable, code 0). Reads in 64 KiB chunks.
IoResult<std::string> readFileText(const std::filesystem::path& path, size_t maxBytes);

// The limit readFileText applies for a reader whose default is `maxBytes`, or why IMPS_MAX_INPUT_MIB is unusable
// (one error without a location: the environment is not a file).
std::expected<size_t, Diagnostics> inputLimitBytes(size_t maxBytes);

// "16 MiB", "1.5 GiB": a byte limit for messages.
std::string byteSizeText(size_t bytes);

}  // namespace imps
