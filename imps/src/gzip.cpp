// SPDX-License-Identifier: MIT
// gzip decompression with zlib (see gzip.h).
#include "imps/gzip.h"

#include <zlib.h>

#include <algorithm>
#include <climits>

#include "imps/file_read.h"

namespace imps {

bool isGzip(std::string_view bytes) {
  return bytes.size() >= 2 && static_cast<unsigned char>(bytes[0]) == 0x1F &&
         static_cast<unsigned char>(bytes[1]) == 0x8B;
}

std::expected<std::string, Diagnostics> gunzip(std::string_view bytes, size_t maxBytes) {
  const auto fail = [](std::string reason) { return std::unexpected(singleError({}, std::move(reason))); };
  z_stream stream{};
  if (inflateInit2(&stream, 16 + MAX_WBITS) != Z_OK) return fail("cannot start zlib");
  std::string out;
  char buffer[1 << 16];
  size_t consumed = 0;
  int status = Z_OK;
  while (true) {
    // zlib counts in uInt: feed at most 1 GiB at a time.
    if (stream.avail_in == 0 && consumed < bytes.size()) {
      const size_t chunk = std::min<size_t>(bytes.size() - consumed, size_t{1} << 30);
      stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data() + consumed));
      stream.avail_in = static_cast<uInt>(chunk);
      consumed += chunk;
    }
    stream.next_out = reinterpret_cast<Bytef*>(buffer);
    stream.avail_out = sizeof buffer;
    status = inflate(&stream, Z_NO_FLUSH);
    const size_t produced = sizeof buffer - stream.avail_out;
    if (produced > maxBytes - out.size()) {
      inflateEnd(&stream);
      return fail("larger than the " + byteSizeText(maxBytes) + " limit when decompressed");
    }
    out.append(buffer, produced);
    if (status == Z_STREAM_END) {
      // Another gzip member may follow (cat a.gz b.gz); trailing zero padding is ignored.
      const bool more = stream.avail_in > 0 || consumed < bytes.size();
      if (!more) break;
      const std::string_view rest = bytes.substr(bytes.size() - stream.avail_in - (bytes.size() - consumed));
      if (!isGzip(rest)) break;
      if (inflateReset(&stream) != Z_OK) break;
      continue;
    }
    if (status == Z_BUF_ERROR && stream.avail_in == 0 && consumed >= bytes.size()) {
      inflateEnd(&stream);
      return fail("truncated gzip data");
    }
    if (status != Z_OK && status != Z_BUF_ERROR) {
      const std::string reason = stream.msg != nullptr ? stream.msg : "error " + std::to_string(status);
      inflateEnd(&stream);
      return fail("corrupt gzip data (" + reason + ")");
    }
  }
  inflateEnd(&stream);
  return out;
}

}  // namespace imps
