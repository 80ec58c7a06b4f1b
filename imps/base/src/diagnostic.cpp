// SPDX-License-Identifier: MIT
// Diagnostics: formatting and typo suggestions.
#include "imps/diagnostic.h"

#include <algorithm>
#include <cctype>

namespace imps {

std::string Diagnostic::str() const {
  std::string out;
  if (!loc.file.empty()) out += loc.file + ":";
  if (loc.line > 0) out += std::to_string(loc.line) + ":";
  if (loc.line > 0 && loc.column > 0) out += std::to_string(loc.column) + ":";
  if (!out.empty()) out += " ";
  switch (severity) {
    case Severity::Error: out += "error: "; break;
    case Severity::Warning: out += "warning: "; break;
    case Severity::Note: out += "note: "; break;
  }
  return out + message;
}

void Diagnostics::error(SourceLoc loc, std::string message) {
  items_.push_back({Severity::Error, std::move(loc), std::move(message)});
  ++errorCount_;
}
void Diagnostics::warning(SourceLoc loc, std::string message) {
  items_.push_back({Severity::Warning, std::move(loc), std::move(message)});
}
void Diagnostics::note(SourceLoc loc, std::string message) {
  items_.push_back({Severity::Note, std::move(loc), std::move(message)});
}

std::string Diagnostics::str() const {
  std::string out;
  const size_t shown = std::min(items_.size(), kMaxPrinted);
  for (size_t i = 0; i < shown; ++i) out += items_[i].str() + "\n";
  if (shown < items_.size())
    out += "... and " + std::to_string(items_.size() - shown) + " more (" + std::to_string(errorCount_) +
           " errors in all; only the first " + std::to_string(kMaxPrinted) + " are shown)\n";
  return out;
}

std::string Diagnostics::firstError() const {
  for (const Diagnostic& d : items_)
    if (d.severity == Severity::Error) return d.str();
  return {};
}

Diagnostics singleError(SourceLoc loc, std::string message) {
  Diagnostics d;
  d.error(std::move(loc), std::move(message));
  return d;
}

void Diagnostics::append(const Diagnostics& other) {
  for (const Diagnostic& d : other.items_) items_.push_back(d);
  errorCount_ += other.errorCount_;
}

namespace {
// Levenshtein distance, case-insensitive.
size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      const bool same = std::tolower(static_cast<unsigned char>(a[i - 1])) ==
                        std::tolower(static_cast<unsigned char>(b[j - 1]));
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (same ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}
}  // namespace

std::string closestMatch(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  size_t bestDistance = std::max<size_t>(2, word.size() / 3) + 1;  // further than this is not a typo
  for (const std::string& c : candidates) {
    const size_t d = editDistance(word, c);
    if (d < bestDistance) {
      bestDistance = d;
      best = c;
    }
  }
  return best;
}

}  // namespace imps
