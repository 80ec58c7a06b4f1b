// SPDX-License-Identifier: MIT
// gzip decompression (imps/include/imps/gzip.h): round trips through zlib's own compressor, concatenated members,
// the output limit, and truncated or corrupt input.
#include "imps/gzip.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <string>

#include "imps/file_read.h"

namespace imps {
namespace {

// `text` as one gzip member, compressed by zlib (not by the code under test).
std::string gzipOf(const std::string& text, int level = Z_DEFAULT_COMPRESSION) {
  z_stream stream{};
  EXPECT_EQ(deflateInit2(&stream, level, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY), Z_OK);
  std::string out(deflateBound(&stream, uLong(text.size())), '\0');
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(text.data()));
  stream.avail_in = uInt(text.size());
  stream.next_out = reinterpret_cast<Bytef*>(out.data());
  stream.avail_out = uInt(out.size());
  EXPECT_EQ(deflate(&stream, Z_FINISH), Z_STREAM_END);
  out.resize(stream.total_out);
  deflateEnd(&stream);
  return out;
}

// Why gunzip failed: its one error, which has no location (the caller adds the file); "" when it did not fail.
std::string reason(const std::expected<std::string, Diagnostics>& out) {
  if (out) return "";
  EXPECT_EQ(out.error().errorCount(), 1);
  EXPECT_TRUE(out.error().all().front().loc.file.empty());
  return out.error().all().front().message;
}

// Varied text that compresses but not to nothing, so several output buffers are needed.
std::string sample(size_t n) {
  std::string s;
  for (size_t i = 0; s.size() < n; ++i) s += "Transform { translation " + std::to_string(i * 37 % 1001) + " 0 1 }\n";
  s.resize(n);
  return s;
}

TEST(IsGzip, LooksAtTheMagicNumberOnly) {
  EXPECT_TRUE(isGzip(gzipOf("x")));
  EXPECT_TRUE(isGzip("\x1F\x8B"));
  EXPECT_FALSE(isGzip("#VRML V2.0 utf8"));
  EXPECT_FALSE(isGzip("\x1F"));
  EXPECT_FALSE(isGzip(""));
}

TEST(Gunzip, RoundTripsWhatZlibCompressed) {
  for (size_t n : {size_t(0), size_t(1), size_t(1000), size_t(65536), size_t(300000)})
    for (int level : {0, 1, 9}) {
      const std::string text = sample(n);
      const auto out = gunzip(gzipOf(text, level), size_t(1) << 20);
      ASSERT_TRUE(out) << n << " " << level << ": " << reason(out);
      EXPECT_EQ(*out, text) << n << " " << level;
    }
}

TEST(Gunzip, JoinsConcatenatedMembersAsGunzipDoes) {
  const std::string a = sample(70000), b = "second member\n", c = sample(10);
  const auto out = gunzip(gzipOf(a) + gzipOf(b) + gzipOf(c), size_t(1) << 20);
  ASSERT_TRUE(out) << reason(out);
  EXPECT_EQ(*out, a + b + c);
}

TEST(Gunzip, IgnoresTrailingZeroPadding) {
  const auto out = gunzip(gzipOf("padded") + std::string(512, '\0'), 1000);
  ASSERT_TRUE(out) << reason(out);
  EXPECT_EQ(*out, "padded");
}

TEST(Gunzip, StopsAtTheLimitWithoutExceedingIt) {
  const std::string text = sample(200000);
  const std::string zipped = gzipOf(text);
  EXPECT_TRUE(gunzip(zipped, text.size()));  // exactly the limit is allowed
  const auto over = gunzip(zipped, text.size() - 1);
  ASSERT_FALSE(over);
  EXPECT_EQ(reason(over), "larger than the " + byteSizeText(text.size() - 1) + " limit when decompressed");
  // A bomb: 64 MiB of zeros compress to about 64 KiB; a 1 MiB limit refuses it.
  const auto bomb = gunzip(gzipOf(std::string(size_t(64) << 20, '\0'), 9), size_t(1) << 20);
  ASSERT_FALSE(bomb);
  EXPECT_EQ(reason(bomb), "larger than the 1 MiB limit when decompressed");
}

TEST(Gunzip, TheLimitCountsAllMembersTogether) {
  const std::string a = sample(600), b = sample(600);
  EXPECT_TRUE(gunzip(gzipOf(a) + gzipOf(b), 1200));
  EXPECT_FALSE(gunzip(gzipOf(a) + gzipOf(b), 1199));
}

TEST(Gunzip, TruncatedInputIsReportedAsTruncated) {
  const std::string zipped = gzipOf(sample(50000));
  for (size_t keep : {size_t(2), size_t(10), zipped.size() / 2, zipped.size() - 4, zipped.size() - 1}) {
    const auto out = gunzip(zipped.substr(0, keep), size_t(1) << 20);
    ASSERT_FALSE(out) << keep;
    EXPECT_EQ(reason(out), "truncated gzip data") << keep;
  }
}

TEST(Gunzip, CorruptInputIsReportedAsCorrupt) {
  std::string badMethod = gzipOf("hello");
  badMethod[2] = 7;  // compression method other than deflate
  std::string badCrc = gzipOf(sample(5000));
  badCrc[badCrc.size() - 6] ^= 0x55;  // the CRC-32 of the member's data
  std::string badData = gzipOf(sample(5000), 9);
  badData[10] = char(0xff);  // the first deflate block header (after the 10-byte member header): reserved type 3
  for (const std::string* bad : {&badMethod, &badCrc, &badData}) {
    const auto out = gunzip(*bad, size_t(1) << 20);
    ASSERT_FALSE(out);
    EXPECT_EQ(reason(out).rfind("corrupt gzip data (", 0), 0u) << reason(out);
  }
  const auto notGzip = gunzip("#VRML V2.0 utf8\n", 1000);
  ASSERT_FALSE(notGzip);
  EXPECT_EQ(reason(notGzip).rfind("corrupt gzip data (", 0), 0u) << reason(notGzip);
}

}  // namespace
}  // namespace imps
