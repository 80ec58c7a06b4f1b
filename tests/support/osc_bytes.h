// SPDX-License-Identifier: MIT
// Hand-built OSC 1.0 bytes for tests that need packets no OSC library would produce (malformed ones, odd types).
#pragma once

#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

namespace imps {

// Appends OSC atoms big-endian, strings NUL-terminated and padded to 4 bytes.
struct OscBytes {
  std::vector<uint8_t> bytes;
  OscBytes& str(std::string_view s) {
    bytes.insert(bytes.end(), s.begin(), s.end());
    do bytes.push_back(0);
    while (bytes.size() % 4 != 0);
    return *this;
  }
  OscBytes& u32(uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) bytes.push_back(uint8_t(v >> shift));
    return *this;
  }
  OscBytes& i64(int64_t v) { return u32(uint32_t(uint64_t(v) >> 32)).u32(uint32_t(uint64_t(v))); }
  OscBytes& f32(float f) {
    uint32_t v;
    std::memcpy(&v, &f, 4);
    return u32(v);
  }
  OscBytes& f64(double d) {
    uint64_t v;
    std::memcpy(&v, &d, 8);
    return i64(int64_t(v));
  }
  // A bundle element: its size, then its bytes.
  OscBytes& element(const OscBytes& e) {
    u32(uint32_t(e.bytes.size()));
    bytes.insert(bytes.end(), e.bytes.begin(), e.bytes.end());
    return *this;
  }
  static OscBytes bundle() { return OscBytes().str("#bundle").u32(0).u32(1); }
};

}  // namespace imps
