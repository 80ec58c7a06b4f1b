// SPDX-License-Identifier: MIT
// UTF-8 well-formedness (see utf8.h).
#include "imps/utf8.h"

namespace imps {

size_t firstInvalidUtf8(std::string_view text) {
  size_t i = 0;
  const size_t n = text.size();
  while (i < n) {
    const auto b0 = static_cast<unsigned char>(text[i]);
    if (b0 < 0x80) {
      ++i;
      continue;
    }
    size_t length = 0;
    unsigned min = 0;
    unsigned cp = 0;
    if ((b0 & 0xE0) == 0xC0) {
      length = 2, min = 0x80, cp = b0 & 0x1Fu;
    } else if ((b0 & 0xF0) == 0xE0) {
      length = 3, min = 0x800, cp = b0 & 0x0Fu;
    } else if ((b0 & 0xF8) == 0xF0) {
      length = 4, min = 0x10000, cp = b0 & 0x07u;
    } else {
      return i;
    }
    if (n - i < length) return i;
    for (size_t k = 1; k < length; ++k) {
      const auto b = static_cast<unsigned char>(text[i + k]);
      if ((b & 0xC0) != 0x80) return i;
      cp = (cp << 6) | (b & 0x3Fu);
    }
    if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return i;
    i += length;
  }
  return n;
}

namespace {

// How many bytes from an ill-formed position one U+FFFD stands for: a lead byte with the continuation bytes that
// follow it (a sequence cut short is one replacement, as most decoders do), else the single byte.
size_t illFormedLength(std::string_view text) {
  const auto b0 = static_cast<unsigned char>(text[0]);
  const size_t length = b0 >= 0xC2 && b0 <= 0xDF ? 2 : b0 >= 0xE0 && b0 <= 0xEF ? 3 : b0 >= 0xF0 && b0 <= 0xF4 ? 4 : 1;
  size_t n = 1;
  while (n < length && n < text.size() && (static_cast<unsigned char>(text[n]) & 0xC0) == 0x80) ++n;
  return n;
}

}  // namespace

std::string toValidUtf8(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (;;) {
    const size_t bad = firstInvalidUtf8(text);
    out.append(text.substr(0, bad));
    if (bad == text.size()) return out;
    out += "\xEF\xBF\xBD";  // U+FFFD
    text.remove_prefix(bad + illFormedLength(text.substr(bad)));
  }
}

}  // namespace imps
