// SPDX-License-Identifier: MIT
#include "imps/io_error.h"

#include <gtest/gtest.h>

#include <cerrno>
#include <cstring>

namespace imps {
namespace {

TEST(IoError, NamesThePathThenWhatFailed) {
  EXPECT_EQ((IoError{"out/take.session", "cannot create: Permission denied", EACCES}).str(),
            "out/take.session: cannot create: Permission denied");
  EXPECT_EQ((IoError{"", "no device answered", 0}).str(), "no device answered");
}

TEST(IoError, FromErrnoKeepsTheCodeAndTheSystemsWords) {
  const IoError e = IoError::fromErrno("/full/disk.glb", "write", ENOSPC);
  EXPECT_EQ(e.code, ENOSPC);
  EXPECT_EQ(e.path, "/full/disk.glb");
  EXPECT_EQ(e.message, std::string("write: ") + std::strerror(ENOSPC));
  EXPECT_EQ(e.str(), "/full/disk.glb: write: " + std::string(std::strerror(ENOSPC)));
}

TEST(IoError, IoResultCarriesAValueOrTheError) {
  const IoResult<int> ok = 3;
  const IoResult<void> bad = std::unexpected(IoError{"x", "gone", ENOENT});
  ASSERT_TRUE(ok.has_value());
  EXPECT_EQ(*ok, 3);
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error().code, ENOENT);
}

}  // namespace
}  // namespace imps
