// Reading a whole session or BVH file with a size limit, so an endless input (/dev/zero, a pipe) or a huge one is
// refused with a message instead of filling memory. Private to sim/ (imps/file_read.h is the same for the modules
// that link imps; sim does not).
#pragma once

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <expected>
#include <filesystem>
#include <memory>
#include <string>

namespace imps::sim::detail {

// The whole file, or the reason it cannot be read: the system's error text, or "larger than the N MiB limit" once
// more than `maxBytes` bytes were read (without reading further).
inline std::expected<std::string, std::string> readFileText(const std::filesystem::path& path, size_t maxBytes) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) return std::unexpected(std::strerror(errno));
  std::string text;
  char buffer[1 << 16];
  for (;;) {
    const size_t n = std::fread(buffer, 1, sizeof buffer, file.get());
    if (n > maxBytes - text.size())
      return std::unexpected("larger than the " + std::to_string(maxBytes >> 20) + " MiB limit");
    text.append(buffer, n);
    if (n < sizeof buffer) {
      if (std::ferror(file.get())) return std::unexpected(std::strerror(errno));
      return text;
    }
  }
}

}  // namespace imps::sim::detail
