// SPDX-License-Identifier: MIT
// UTF-8 checks for text that came from a file or a device: find the first ill-formed byte, or make the text
// well-formed before it reaches a format that requires UTF-8 (JSON, glTF).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace imps {

// The offset of the first byte of `text` that is not part of well-formed UTF-8 (overlong forms, surrogates and
// code points above U+10FFFF are ill-formed), or text.size() when it is all valid.
size_t firstInvalidUtf8(std::string_view text);

// `text` with each ill-formed sequence (a lead byte and the continuation bytes after it, or a stray byte) replaced by
// U+FFFD, the replacement character; well-formed text is returned unchanged. For strings from devices and files on
// their way into JSON, which must be UTF-8.
std::string toValidUtf8(std::string_view text);

}  // namespace imps
