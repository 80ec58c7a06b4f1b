// SPDX-License-Identifier: MIT
// Bounded whole-file reads (imps/base/include/imps/file_read.h): the size limit, IMPS_MAX_INPUT_MIB, endless inputs
// and the system's errors.
#include "imps/file_read.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include "scratch_dir.h"

namespace imps {
namespace {

namespace fs = std::filesystem;

constexpr size_t kMiB = size_t{1} << 20;

// Sets (or with nullopt unsets) IMPS_MAX_INPUT_MIB for one scope, restoring what was there.
class ScopedLimit {
 public:
  explicit ScopedLimit(std::optional<std::string> value) {
    if (const char* old = std::getenv("IMPS_MAX_INPUT_MIB")) old_ = old;
    if (value) ::setenv("IMPS_MAX_INPUT_MIB", value->c_str(), 1);
    else ::unsetenv("IMPS_MAX_INPUT_MIB");
  }
  ~ScopedLimit() {
    if (old_) ::setenv("IMPS_MAX_INPUT_MIB", old_->c_str(), 1);
    else ::unsetenv("IMPS_MAX_INPUT_MIB");
  }

 private:
  std::optional<std::string> old_;
};

class FileRead : public ::testing::Test {
 protected:
  fs::path fileOf(const std::string& name, const std::string& bytes) const {
    writeBytes(dir_ / name, bytes);
    return dir_ / name;
  }
  ScratchDir dir_{"imps_file_read_test"};
  ScopedLimit noLimit_{std::nullopt};
};

// Bytes that differ from chunk to chunk, so a dropped or repeated 64 KiB chunk changes the result.
std::string pattern(size_t n) {
  std::string s(n, '\0');
  for (size_t i = 0; i < n; ++i) s[i] = char((i * 7 + i / 65536) & 0xff);
  return s;
}

TEST_F(FileRead, ReadsTheWholeFileAcrossChunks) {
  for (size_t n : {size_t(0), size_t(1), size_t(65535), size_t(65536), size_t(65537), size_t(3 * 65536 + 5)}) {
    const std::string bytes = pattern(n);
    const auto text = readFileText(fileOf("f", bytes), kMiB);
    ASSERT_TRUE(text) << n << ": " << text.error().str();
    EXPECT_EQ(*text, bytes) << n;
  }
}

TEST_F(FileRead, AFileOfExactlyTheLimitIsReadAndOneByteMoreIsRefused) {
  for (size_t limit : {size_t(10), size_t(65536), size_t(2 * 65536 + 3)}) {
    EXPECT_TRUE(readFileText(fileOf("at", pattern(limit)), limit)) << limit;
    const auto over = readFileText(fileOf("over", pattern(limit + 1)), limit);
    ASSERT_FALSE(over) << limit;
    EXPECT_EQ(over.error().message,
              "larger than the " + byteSizeText(limit) + " limit (IMPS_MAX_INPUT_MIB=N raises it)");
  }
}

TEST_F(FileRead, AnEndlessInputIsRefusedAtTheLimit) {
  const auto zero = readFileText("/dev/zero", kMiB);
  ASSERT_FALSE(zero);
  EXPECT_EQ(zero.error().path, "/dev/zero");
  EXPECT_EQ(zero.error().message, "larger than the 1 MiB limit (IMPS_MAX_INPUT_MIB=N raises it)");
}

TEST_F(FileRead, TheEnvironmentVariableReplacesTheReadersDefault) {
  const fs::path twoMiB = fileOf("two", pattern(2 * kMiB));
  EXPECT_FALSE(readFileText(twoMiB, 100));
  {
    const ScopedLimit limit("2");
    EXPECT_EQ(inputLimitBytes(100).value_or(0), size_t(2 * kMiB));
    const auto text = readFileText(twoMiB, 100);
    ASSERT_TRUE(text) << text.error().str();
    EXPECT_EQ(text->size(), 2 * kMiB);
  }
  {
    const ScopedLimit limit("1");  // lowers a default too
    const auto text = readFileText(twoMiB, 64 * kMiB);
    ASSERT_FALSE(text);
    EXPECT_EQ(text.error().message, "larger than the 1 MiB limit (IMPS_MAX_INPUT_MIB=N raises it)");
  }
}

TEST_F(FileRead, WithoutTheVariableTheLimitIsTheDefault) {
  EXPECT_EQ(inputLimitBytes(12345).value_or(0), size_t(12345));
}

TEST_F(FileRead, TheLargestValidValueIs16TiB) {
  const ScopedLimit limit("16777216");
  EXPECT_EQ(inputLimitBytes(1).value_or(0), size_t(size_t{1} << 44));
}

TEST_F(FileRead, AnInvalidValueIsAnErrorNamingTheVariable) {
  const fs::path small = fileOf("small", "abc");
  for (const char* value :
       {"", "0", "-1", "+5", " 5", "5 ", "1x", "abc", "1.5", "16777217", "99999999999999999999999"}) {
    const ScopedLimit limit{std::string(value)};
    const auto bytes = inputLimitBytes(kMiB);
    ASSERT_FALSE(bytes) << "'" << value << "'";
    ASSERT_EQ(bytes.error().errorCount(), 1);
    EXPECT_EQ(bytes.error().all().front().message,
              "IMPS_MAX_INPUT_MIB='" + std::string(value) + "' is not a whole number of MiB from 1 to 16777216");
    // The reader refuses too rather than falling back to its default.
    const auto text = readFileText(small, kMiB);
    ASSERT_FALSE(text) << "'" << value << "'";
    EXPECT_EQ(text.error().message, bytes.error().all().front().message);
  }
}

TEST_F(FileRead, SystemErrorsAreReportedInTheSystemsWords) {
  const auto missing = readFileText(dir_ / "missing.wrl", kMiB);
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().message, "No such file or directory");
  EXPECT_EQ(missing.error().code, ENOENT);
  EXPECT_EQ(missing.error().str(), (dir_ / "missing.wrl").string() + ": No such file or directory");
  const auto directory = readFileText(dir_.path(), kMiB);
  ASSERT_FALSE(directory);
  EXPECT_EQ(directory.error().message, "Is a directory");
  EXPECT_EQ(directory.error().code, EISDIR);
}

TEST(ByteSizeText, NamesTheLargestWholeUnit) {
  EXPECT_EQ(byteSizeText(0), "0 bytes");
  EXPECT_EQ(byteSizeText(1023), "1023 bytes");
  EXPECT_EQ(byteSizeText(kMiB - 1), "1048575 bytes");
  EXPECT_EQ(byteSizeText(kMiB), "1 MiB");
  EXPECT_EQ(byteSizeText(16 * kMiB), "16 MiB");
  EXPECT_EQ(byteSizeText(kMiB + kMiB / 2), "1.5 MiB");
  EXPECT_EQ(byteSizeText(size_t{1} << 30), "1 GiB");
  EXPECT_EQ(byteSizeText((size_t{3} << 30) / 2), "1.5 GiB");
}

}  // namespace
}  // namespace imps
