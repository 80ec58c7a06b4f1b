// SPDX-License-Identifier: MIT
// A small JSON reader that remembers where every value and key is (file:line:column), for the calibration
// files' diagnostics. Private to calibration/; writing goes through nlohmann-json.
#pragma once

#include <cstddef>
#include <expected>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "imps/diagnostic.h"

namespace imps::calibration::detail {

// The largest rig map, calibration or check-pose file read (a real one is a few kilobytes): a bigger or endless
// input (/dev/zero) is refused before it fills memory.
inline constexpr size_t kMaxFileBytes = size_t{16} << 20;

// The text of a calibration-side JSON file (`what`: "rig map", "joint map", "check pose"), read up to kMaxFileBytes
// (IMPS_MAX_INPUT_MIB raises it), or one diagnostic at `path`: "cannot read WHAT: no such file", "…: not a readable
// file" or "…: larger than the 16 MiB limit (…); a WHAT is a few kilobytes".
std::expected<std::string, Diagnostics> readJsonFileText(const std::filesystem::path& path, std::string_view what);

struct JsonValue {
  enum class Kind { Null, Bool, Number, String, Array, Object };
  struct Member;

  Kind kind = Kind::Null;
  SourceLoc loc;  // where the value starts
  bool boolean = false;
  double number = 0;
  bool integral = false;  // the number was written without fraction or exponent
  std::string string;
  std::vector<JsonValue> items;  // Array
  std::vector<Member> members;   // Object, in file order (duplicate keys are a parse error)

  // The member named `key`, or nullptr.
  const JsonValue* find(std::string_view key) const;
};

struct JsonValue::Member {
  std::string key;
  SourceLoc keyLoc;
  JsonValue value;
};

// "null", "a boolean", "a number", "a string", "an array", "an object".
const char* describe(JsonValue::Kind kind);

// Parses one JSON document (RFC 8259; no comments, no trailing commas). On a syntax error adds one diagnostic
// `file:line:column: error: …` and returns false. Columns count bytes from 1.
bool parseJson(std::string_view text, std::string_view fileName, JsonValue& out, Diagnostics& diags);

}  // namespace imps::calibration::detail
