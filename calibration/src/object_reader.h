// SPDX-License-Identifier: MIT
// Reading one JSON object's members with diagnostics: unknown keys (with "did you mean"), missing fields, wrong
// types, and angles given in radians (`key`) or degrees (`key_deg`). Private to calibration/.
#pragma once

#include <cstdio>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "imps/diagnostic.h"
#include "json_document.h"

namespace imps::calibration::detail {

inline constexpr double kDegree = std::numbers::pi / 180.0;

// An integral JSON number as text, whatever its size ("3", "100000000000000000000").
inline std::string integerText(double v) {
  char buf[400];
  std::snprintf(buf, sizeof buf, "%.0f", v);
  return buf;
}

inline std::string quoted(const std::vector<std::string>& words) {
  std::string s;
  for (size_t i = 0; i < words.size(); ++i) {
    if (i) s += i + 1 == words.size() ? " or " : ", ";
    s += "'" + words[i] + "'";
  }
  return s;
}

// Reads the members of one JSON object, reporting unknown keys (with a suggestion) and wrong types.
class ObjectReader {
 public:
  ObjectReader(const JsonValue& object, std::string what, std::vector<std::string> known, Diagnostics& diags)
      : object_(object), what_(std::move(what)), diags_(diags) {
    for (const JsonValue::Member& m : object.members) {
      bool ok = false;
      for (const std::string& k : known) ok = ok || k == m.key;
      if (ok) continue;
      std::string message = "unknown field '" + m.key + "' in " + what_;
      const std::string guess = closestMatch(m.key, known);
      if (!guess.empty()) message += "; did you mean '" + guess + "'?";
      else message += " (expected " + quoted(known) + ")";
      diags_.error(m.keyLoc, message);
    }
  }

  const JsonValue* get(std::string_view key) const { return object_.find(key); }

  void missing(const std::string& key) const {
    diags_.error(object_.loc, "missing field '" + key + "' in " + what_);
  }

  const JsonValue* typed(std::string_view key, JsonValue::Kind kind, const char* expected) const {
    const JsonValue* v = object_.find(key);
    if (!v) return nullptr;
    if (v->kind != kind) {
      diags_.error(v->loc, "'" + std::string(key) + "' must be " + expected + ", not " + describe(v->kind));
      return nullptr;
    }
    return v;
  }

  std::optional<double> number(std::string_view key) const {
    const JsonValue* v = typed(key, JsonValue::Kind::Number, "a number");
    if (!v) return std::nullopt;
    return v->number;
  }

  // An angle given in radians as `key` or in degrees as `key_deg`; the location of whichever was given.
  std::optional<double> angle(const std::string& key, SourceLoc* loc = nullptr) const {
    const JsonValue* rad = get(key);
    const JsonValue* deg = get(key + "_deg");
    if (rad && deg) {
      diags_.error(deg->loc, "give either '" + key + "' (radians) or '" + key + "_deg' (degrees), not both");
      return std::nullopt;
    }
    if (rad) {
      if (loc) *loc = rad->loc;
      return number(key);
    }
    if (deg) {
      if (loc) *loc = deg->loc;
      if (auto d = number(key + "_deg")) return *d * kDegree;
    }
    return std::nullopt;
  }

  const SourceLoc& loc() const { return object_.loc; }
  const SourceLoc& locOf(std::string_view key) const {
    const JsonValue* v = object_.find(key);
    return v ? v->loc : object_.loc;
  }

 private:
  const JsonValue& object_;
  std::string what_;
  Diagnostics& diags_;
};

}  // namespace imps::calibration::detail
