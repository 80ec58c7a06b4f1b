// Whole-file reads with a size limit (see file_read.h).
#include "imps/file_read.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

namespace imps {

std::string byteSizeText(size_t bytes) {
  char buf[64];
  if (bytes >= (size_t{1} << 30)) std::snprintf(buf, sizeof buf, "%g GiB", static_cast<double>(bytes) / (1 << 30));
  else if (bytes >= (size_t{1} << 20)) std::snprintf(buf, sizeof buf, "%g MiB", static_cast<double>(bytes) / (1 << 20));
  else std::snprintf(buf, sizeof buf, "%zu bytes", bytes);
  return buf;
}

std::expected<std::string, std::string> readFileText(const std::filesystem::path& path, size_t maxBytes) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) return std::unexpected(std::strerror(errno));
  std::string text;
  char buffer[1 << 16];
  for (;;) {
    const size_t n = std::fread(buffer, 1, sizeof buffer, file.get());
    if (n > maxBytes - text.size()) return std::unexpected("larger than the " + byteSizeText(maxBytes) + " limit");
    text.append(buffer, n);
    if (n < sizeof buffer) {
      if (std::ferror(file.get())) return std::unexpected(std::strerror(errno));
      return text;
    }
  }
}

}  // namespace imps
