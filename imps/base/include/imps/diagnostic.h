// SPDX-License-Identifier: MIT
// Diagnostics for bad input: where it is (file:line:column) and what was expected.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace imps {

// A position in an input file. Lines and columns count from 1; 0 means "unknown".
struct SourceLoc {
  std::string file;
  int line = 0;
  int column = 0;
};

enum class Severity { Error, Warning, Note };

// One message about an input, printed as `file:line:column: error: message`.
struct Diagnostic {
  Severity severity = Severity::Error;
  SourceLoc loc;
  std::string message;

  std::string str() const;
};

// Diagnostics collected while reading or validating one input. Errors make the input invalid; warnings do not.
class Diagnostics {
 public:
  void error(SourceLoc loc, std::string message);
  void warning(SourceLoc loc, std::string message);
  void note(SourceLoc loc, std::string message);

  bool hasErrors() const { return errorCount_ > 0; }
  int errorCount() const { return errorCount_; }
  const std::vector<Diagnostic>& all() const { return items_; }
  // The first kMaxPrinted diagnostics, one per line, in the order reported, then "... and N more (E errors in all;
  // ...)" when there were more: a file with 100,000 bad entries gives a readable report, not megabytes of errors.
  std::string str() const;
  static constexpr size_t kMaxPrinted = 100;
  void append(const Diagnostics& other);
  // The first error as Diagnostic::str() (no newline), "" when there is none: a result that failed for one reason,
  // printed inside a longer line ("puppeteer convert: error: " + firstError()).
  std::string firstError() const;

 private:
  std::vector<Diagnostic> items_;
  int errorCount_ = 0;
};

// Diagnostics holding one error: the result of a function that fails for a single reason.
Diagnostics singleError(SourceLoc loc, std::string message);

// The closest candidate to `word` by edit distance, or "" when none is close enough to be a likely typo.
// Used for "did you mean 'radius'?" suggestions.
std::string closestMatch(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace imps
