// SPDX-License-Identifier: MIT
// The project's two ways to fail. Bad *content* — a file, a wire frame or an argument that does not say what it must —
// is a `Diagnostics` (diagnostic.h): `std::expected<T, Diagnostics>`, printed as `file:line:column: error: …`.
// A failure of the world outside the program — a file, directory, device or socket that cannot be opened, read,
// written, synced or renamed — is an `IoError`: `IoResult<T>` = `std::expected<T, IoError>`. Library code returns
// one of the two and never prints; only `puppeteer/` turns them into messages and exit codes (docs/cli.md: bad input
// exits 1, I/O exits 3). A function that can fail both ways (a reader whose file may be missing or corrupt, a writer
// whose mesh or clip may be invalid) returns Diagnostics with the I/O failure as one of them, unless its callers must
// tell the two apart for the exit code (docs/ARCHITECTURE.md, "How failures travel").
#pragma once

#include <expected>
#include <string>
#include <string_view>

namespace imps {

struct IoError {
  std::string path;     // the file, directory, device or address concerned; "" when none applies
  std::string message;  // what failed and why, e.g. "No such file or directory"; an atomic save's is the whole
                        // sentence "cannot save 'PATH': STEP: REASON" (atomic_file.h)
  int code = 0;         // the errno the OS gave, or 0

  // "PATH: MESSAGE", or MESSAGE alone when there is no path.
  std::string str() const;
  // An error for a failed system call: MESSAGE is "WHAT: strerror(err)" and code is err.
  static IoError fromErrno(std::string path, std::string_view what, int err);
};

template <class T>
using IoResult = std::expected<T, IoError>;

}  // namespace imps
