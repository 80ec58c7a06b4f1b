// SPDX-License-Identifier: MIT
// Atomic file replacement: temporary file, write, fsync, rename, fsync the directory.
#include "imps/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

namespace imps {
namespace {

std::unexpected<IoError> failWith(const std::string& path, const char* step, int code) {
  return std::unexpected(IoError{path, "cannot save '" + path + "': " + step + ": " + std::strerror(code), code});
}

// Step 4 of a save: replace the target in one step, then make the rename itself durable (best effort: the data is
// safe once renamed).
IoResult<void> renameOver(const std::string& temp, const std::string& path) {
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    const int code = errno;
    ::unlink(temp.c_str());
    return failWith(path, "renaming the temporary file over it", code);
  }
  const size_t slash = path.find_last_of('/');
  const std::string directory = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  if (const int dir = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); dir >= 0) {
    ::fsync(dir);
    ::close(dir);
  }
  return {};
}

}  // namespace

std::string temporarySibling(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  return path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter.fetch_add(1));
}

IoResult<void> commitTemporaryFile(const std::string& temp, const std::string& path) {
  struct stat existing {};
  if (::stat(path.c_str(), &existing) == 0 && ::chmod(temp.c_str(), existing.st_mode & 07777) != 0) {
    const int code = errno;
    ::unlink(temp.c_str());
    return failWith(path, "setting permissions", code);
  }
  return renameOver(temp, path);
}

IoResult<void> writeFileAtomically(const std::string& path, std::span<const uint8_t> bytes) {
  auto fail = [&](const char* step, int code) { return failWith(path, step, code); };
  // 1. A unique sibling: same directory so the rename stays within one file system; O_EXCL so concurrent savers
  // never share one; mode 0666 so the umask applies as it would to a plain fopen().
  std::string temp;
  int fd = -1;
  for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
    temp = temporarySibling(path);
    fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0 && errno != EEXIST) break;
  }
  if (fd < 0) return fail("creating a temporary file", errno);
  auto abandon = [&](const char* step) {
    const int code = errno;
    ::close(fd);
    ::unlink(temp.c_str());
    return fail(step, code);
  };

  // 2. An existing target keeps its permissions.
  struct stat existing {};
  if (::stat(path.c_str(), &existing) == 0 && ::fchmod(fd, existing.st_mode & 07777) != 0)
    return abandon("setting permissions");

  // 3. Everything written and on the disk before the rename makes it visible.
  size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return abandon("writing");
    written += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0) return abandon("flushing to disk");
  if (::close(fd) != 0) {
    const int code = errno;
    ::unlink(temp.c_str());
    return fail("closing", code);
  }

  // 4. Replace the target in one step, durably.
  return renameOver(temp, path);
}

IoResult<void> writeFileAtomically(const std::string& path, std::string_view text) {
  return writeFileAtomically(path,
                             std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
}

}  // namespace imps
