// SPDX-License-Identifier: MIT
// A fresh directory for one test, and whole-file reads and writes for checking what the code under test wrote.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace imps {

// Creates an empty directory named after the running test (and the process, so parallel ctest runs never share
// one) under the system's temporary directory; removes it with everything in it when destroyed, owner
// permissions restored first so a test that made it read-only cannot leave it behind. Not copyable.
class ScratchDir {
 public:
  explicit ScratchDir(std::string_view prefix);
  ~ScratchDir();
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// The whole contents of `path` as bytes ("" when it cannot be opened).
std::string fileBytes(const std::filesystem::path& path);
// Writes `bytes` to `path`, replacing it.
void writeBytes(const std::filesystem::path& path, std::string_view bytes);

}  // namespace imps
