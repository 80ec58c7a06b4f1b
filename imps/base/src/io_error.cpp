// SPDX-License-Identifier: MIT
#include "imps/io_error.h"

#include <cstring>

namespace imps {

std::string IoError::str() const { return path.empty() ? message : path + ": " + message; }

IoError IoError::fromErrno(std::string path, std::string_view what, int err) {
  return IoError{std::move(path), std::string(what) + ": " + std::strerror(err), err};
}

}  // namespace imps
