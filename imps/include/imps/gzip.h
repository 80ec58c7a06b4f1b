// SPDX-License-Identifier: MIT
// gzip decompression (RFC 1952) for inputs that were served compressed, such as VRML .wrl and .wrz files.
#pragma once

#include <cstddef>
#include <expected>
#include <string>
#include <string_view>

#include "imps/diagnostic.h"

namespace imps {

// Does `bytes` start with the gzip magic number (1F 8B)?
bool isGzip(std::string_view bytes);

// The decompressed contents of the gzip stream `bytes` (concatenated members are joined, as gunzip does), or why it
// cannot be decompressed: one error without a location (the caller knows the file and adds it) saying
// "corrupt gzip data (...)", "truncated gzip data", or "larger than the N MiB limit" once the output would exceed
// `maxBytes` (decompression stops there, so a gzip bomb costs at most `maxBytes`). Thread-safe.
std::expected<std::string, Diagnostics> gunzip(std::string_view bytes, size_t maxBytes);

}  // namespace imps
