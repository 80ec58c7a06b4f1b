// SPDX-License-Identifier: MIT
// The text of a device failure.
#include "drivers/byte_transport.h"

namespace imps::drivers {

std::string errorText(const IoError& error) {
  return error.path.empty() ? error.message : error.path + ": error: " + error.message;
}

}  // namespace imps::drivers
