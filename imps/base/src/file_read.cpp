// SPDX-License-Identifier: MIT
// Whole-file reads with a size limit (see file_read.h).
#include "imps/file_read.h"

#include <cerrno>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
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

std::expected<size_t, Diagnostics> inputLimitBytes(size_t maxBytes) {
  const char* env = std::getenv("IMPS_MAX_INPUT_MIB");
  if (env == nullptr) return maxBytes;
  constexpr uint64_t kMostMiB = uint64_t{1} << 24;  // 16 TiB: beyond any file this machine class reads
  char* end = nullptr;
  errno = 0;
  const unsigned long long mib = std::strtoull(env, &end, 10);
  if (*env < '0' || *env > '9' || *end != '\0' || errno != 0 || mib == 0 || mib > kMostMiB)
    return std::unexpected(singleError({}, "IMPS_MAX_INPUT_MIB='" + std::string(env) +
                                               "' is not a whole number of MiB from 1 to " + std::to_string(kMostMiB)));
  return size_t(mib) << 20;
}

IoResult<std::string> readFileText(const std::filesystem::path& path, size_t maxBytes) {
  const auto limit = inputLimitBytes(maxBytes);
  if (!limit) return std::unexpected(IoError{path.string(), limit.error().all().front().message, 0});
  maxBytes = *limit;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  const auto systemError = [&](int err) { return std::unexpected(IoError{path.string(), std::strerror(err), err}); };
  if (!file) return systemError(errno);
  std::string text;
  char buffer[1 << 16];
  for (;;) {
    const size_t n = std::fread(buffer, 1, sizeof buffer, file.get());
    if (n > maxBytes - text.size())
      return std::unexpected(IoError{
          path.string(), "larger than the " + byteSizeText(maxBytes) + " limit (IMPS_MAX_INPUT_MIB=N raises it)", 0});
    text.append(buffer, n);
    if (n < sizeof buffer) {
      if (std::ferror(file.get())) return systemError(errno);
      return text;
    }
  }
}

}  // namespace imps
