// SPDX-License-Identifier: MIT
// BVH reading (lenient about what real exporters write, precise about what is wrong) and canonical writing.
#include "sim/bvh.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <vector>

#include "imps/atomic_file.h"
#include "imps/diagnostic.h"
#include "imps/file_read.h"

namespace imps::sim {

namespace {

constexpr size_t kMaxBvhFileBytes = size_t{256} << 20;  // readBvh refuses larger (or endless) inputs

constexpr std::array<std::string_view, 6> kChannelNames = {"Xposition", "Yposition", "Zposition",
                                                           "Xrotation", "Yrotation", "Zrotation"};

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    char x = a[i], y = b[i];
    if (x >= 'A' && x <= 'Z') x = static_cast<char>(x - 'A' + 'a');
    if (y >= 'A' && y <= 'Z') y = static_cast<char>(y - 'A' + 'a');
    if (x != y) return false;
  }
  return true;
}

bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\f' || c == '\v'; }
bool isNewline(char c) { return c == '\n' || c == '\r'; }

struct Token {
  std::string_view text;  // empty at end of input
  int line = 0;
  int column = 0;
};

// Splits the text into whitespace-separated tokens ('{' and '}' are tokens of their own), tracking line and
// column (1-based, in bytes). "\r\n", "\n" and a lone "\r" each end a line.
class Lexer {
 public:
  explicit Lexer(std::string_view text) : text_(text) {
    if (text_.starts_with("\xEF\xBB\xBF")) pos_ = 3;  // UTF-8 byte order mark
  }

  // Skips blanks on the current line only; true if the line (or the input) ends there.
  bool atLineEnd() {
    while (pos_ < text_.size() && isBlank(text_[pos_])) advance();
    return pos_ >= text_.size() || isNewline(text_[pos_]);
  }
  bool atEnd() {
    skipSpace();
    return pos_ >= text_.size();
  }
  // Moves past the end of the current line.
  void skipLineEnd() {
    while (pos_ < text_.size() && !isNewline(text_[pos_])) advance();
    if (pos_ < text_.size()) advance();
  }
  // Position of the next non-blank character (or the line end) on the current line.
  Token here() {
    atLineEnd();
    return {{}, line_, column_};
  }
  Token next() {
    skipSpace();
    Token t{{}, line_, column_};
    const size_t start = pos_;
    if (pos_ < text_.size() && (text_[pos_] == '{' || text_[pos_] == '}')) {
      advance();
    } else {
      while (pos_ < text_.size() && !isBlank(text_[pos_]) && !isNewline(text_[pos_]) && text_[pos_] != '{' &&
             text_[pos_] != '}')
        advance();
    }
    t.text = text_.substr(start, pos_ - start);
    return t;
  }
  Token peek() {
    Lexer copy = *this;
    return copy.next();
  }
  // True if the next character on this line is '{' (after blanks).
  bool braceNextOnLine() { return !atLineEnd() && text_[pos_] == '{'; }

 private:
  void skipSpace() {
    while (pos_ < text_.size() && (isBlank(text_[pos_]) || isNewline(text_[pos_]))) advance();
  }
  void advance() {
    const char c = text_[pos_++];
    if (c == '\n' || (c == '\r' && (pos_ >= text_.size() || text_[pos_] != '\n'))) {
      ++line_;
      column_ = 1;
    } else if (c != '\r') {
      ++column_;
    }
  }

  std::string_view text_;
  size_t pos_ = 0;
  int line_ = 1;
  int column_ = 1;
};

template <typename T>
std::optional<T> parseNumber(std::string_view s) {
  if (s.starts_with('+')) s.remove_prefix(1);
  if (s.empty()) return std::nullopt;
  T v{};
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  if constexpr (std::is_floating_point_v<T>) {
    if (!std::isfinite(v)) return std::nullopt;
  }
  return v;
}

std::string quoted(std::string_view s) {
  if (s.empty()) return "end of file";
  return "'" + std::string(s) + "'";
}

class Parser {
 public:
  Parser(std::string_view text, std::string_view name, Diagnostics* warnings)
      : lex_(text), name_(name), warnings_(warnings) {}

  std::expected<BvhClip, Diagnostics> parse() {
    Token t = lex_.next();
    if (!iequals(t.text, "HIERARCHY"))
      return fail(t, "expected 'HIERARCHY' at the start of the file, found " + quoted(t.text));
    for (;;) {
      t = lex_.next();
      if (iequals(t.text, "ROOT")) {
        if (auto r = parseJoint(t, -1); !r) return std::unexpected(r.error());
      } else if (iequals(t.text, "MOTION") && !clip_.joints.empty()) {
        break;
      } else {
        return fail(t, clip_.joints.empty() ? "expected 'ROOT', found " + quoted(t.text)
                                            : "expected 'ROOT' or 'MOTION', found " + quoted(t.text));
      }
    }
    if (auto r = parseMotion(); !r) return std::unexpected(r.error());
    return std::move(clip_);
  }

 private:
  // The reader stops at the first error: a failure holds exactly that one.
  std::unexpected<Diagnostics> fail(const Token& at, std::string what) const {
    Diagnostics errors;
    errors.error(location(at), std::move(what));
    return std::unexpected(std::move(errors));
  }
  SourceLoc location(const Token& at) const { return {name_, at.line, at.column}; }
  void warn(const Token& at, std::string what) {
    if (warnings_) warnings_->warning(location(at), std::move(what));
  }

  // Reads `count` numbers after keyword `what`.
  std::expected<void, Diagnostics> numbers(double* out, int count, std::string_view what) {
    for (int i = 0; i < count; ++i) {
      Token t = lex_.next();
      auto v = parseNumber<double>(t.text);
      if (!v)
        return fail(t, "expected " + std::to_string(count) + " numbers after '" + std::string(what) + "', found " +
                           quoted(t.text));
      out[i] = *v;
    }
    return {};
  }

  std::expected<void, Diagnostics> parseJoint(const Token& keyword, int parent) {
    // The name is the rest of the line up to a '{' (names with spaces are joined with one space).
    std::string name;
    while (!lex_.atLineEnd() && !lex_.braceNextOnLine()) {
      const Token part = lex_.next();
      if (part.text == "}") return fail(part, "expected '{' after joint name '" + name + "', found '}'");
      if (!name.empty()) name += ' ';
      name += part.text;
    }
    if (name.empty()) return fail(lex_.here(), "expected a joint name after " + quoted(keyword.text));
    Token brace = lex_.next();
    if (brace.text != "{")
      return fail(brace, "expected '{' after joint name '" + name + "', found " + quoted(brace.text));

    if (depth_ >= kMaxDepth) return fail(brace, "joints nested more than " + std::to_string(kMaxDepth) + " deep");
    const int index = static_cast<int>(clip_.joints.size());
    clip_.joints.push_back({});
    clip_.joints.back().name = name;
    clip_.joints.back().parent = parent;
    bool hasOffset = false, hasChannels = false;
    for (;;) {
      Token t = lex_.next();
      BvhJoint& joint = clip_.joints[static_cast<size_t>(index)];
      if (iequals(t.text, "OFFSET")) {
        if (hasOffset) return fail(t, "joint '" + name + "' has a second OFFSET");
        hasOffset = true;
        if (auto r = numbers(joint.offset.data(), 3, "OFFSET"); !r) return r;
      } else if (iequals(t.text, "CHANNELS")) {
        if (hasChannels) return fail(t, "joint '" + name + "' has a second CHANNELS");
        hasChannels = true;
        Token c = lex_.next();
        auto n = parseNumber<int>(c.text);
        if (!n || *n < 0 || *n > 6)
          return fail(c, "expected a channel count 0..6 after 'CHANNELS', found " + quoted(c.text));
        for (int i = 0; i < *n; ++i) {
          Token ch = lex_.next();
          std::optional<BvhChannel> found;
          for (size_t k = 0; k < kChannelNames.size(); ++k)
            if (iequals(ch.text, kChannelNames[k])) found = static_cast<BvhChannel>(k);
          if (!found)
            return fail(ch, "expected a channel name (Xposition ... Zrotation) for joint '" + name + "', found " +
                                quoted(ch.text));
          for (BvhChannel prev : joint.channels)
            if (prev == *found) return fail(ch, "channel " + quoted(ch.text) + " repeated in joint '" + name + "'");
          joint.channels.push_back(*found);
        }
      } else if (iequals(t.text, "JOINT")) {
        ++depth_;
        auto r = parseJoint(t, index);
        --depth_;
        if (!r) return r;
      } else if (iequals(t.text, "End")) {
        Token site = lex_.next();
        if (!iequals(site.text, "Site")) return fail(site, "expected 'Site' after 'End', found " + quoted(site.text));
        if (joint.hasEndSite) return fail(t, "joint '" + name + "' has a second End Site");
        Token open = lex_.next();
        if (open.text != "{") return fail(open, "expected '{' after 'End Site', found " + quoted(open.text));
        Token off = lex_.next();
        if (!iequals(off.text, "OFFSET")) return fail(off, "expected 'OFFSET' in End Site, found " + quoted(off.text));
        double v[3];
        if (auto r = numbers(v, 3, "OFFSET"); !r) return r;
        Token close = lex_.next();
        if (close.text != "}") return fail(close, "expected '}' to close End Site, found " + quoted(close.text));
        BvhJoint& j = clip_.joints[static_cast<size_t>(index)];
        j.hasEndSite = true;
        j.endSiteOffset = {v[0], v[1], v[2]};
      } else if (t.text == "}") {
        if (!hasOffset) return fail(t, "joint '" + name + "' has no OFFSET");
        return {};
      } else if (t.text.empty()) {
        return fail(t, "unexpected end of file: expected '}' to close joint '" + name + "'");
      } else {
        return fail(t, "expected 'OFFSET', 'CHANNELS', 'JOINT', 'End Site' or '}' in joint '" + name + "', found " +
                           quoted(t.text));
      }
    }
  }

  // Consumes a label such as "Frames:" or "Frame Time:" given as words; the colon may be glued or separate, and
  // the value may be glued to the colon ("Frames:2"). Returns the value token.
  std::expected<Token, Diagnostics> labelledValue(std::initializer_list<std::string_view> words,
                                                  std::string_view shown) {
    size_t i = 0;
    for (std::string_view w : words) {
      Token t = lex_.next();
      const bool last = ++i == words.size();
      const size_t colon = last ? t.text.find(':') : std::string_view::npos;
      if (!iequals(t.text.substr(0, colon), w))
        return fail(t, "expected '" + std::string(shown) + "', found " + quoted(t.text));
      if (!last) continue;
      if (colon == std::string_view::npos) {
        Token c = lex_.next();
        if (!c.text.starts_with(':'))
          return fail(c, "expected ':' after '" + std::string(w) + "', found " + quoted(c.text));
        if (c.text.size() > 1) return Token{c.text.substr(1), c.line, c.column + 1};
      } else if (colon + 1 < t.text.size()) {
        return Token{t.text.substr(colon + 1), t.line, t.column + static_cast<int>(colon) + 1};
      }
    }
    return lex_.next();
  }

  std::expected<void, Diagnostics> parseMotion() {
    const Token framesAt = lex_.peek();
    auto frames = labelledValue({"Frames"}, "Frames:");
    if (!frames) return std::unexpected(frames.error());
    const Token n = *frames;
    auto declared = parseNumber<long long>(n.text);
    if (!declared || *declared < 0) return fail(n, "expected a frame count after 'Frames:', found " + quoted(n.text));
    auto time = labelledValue({"Frame", "Time"}, "Frame Time:");
    if (!time) return std::unexpected(time.error());
    const Token ft = *time;
    auto frameTime = parseNumber<double>(ft.text);
    if (!frameTime || *frameTime < 0)
      return fail(ft, "expected a frame time in seconds after 'Frame Time:', found " + quoted(ft.text));
    if (*frameTime > kMaxFrameTime)
      return fail(ft, "frame time " + std::string(ft.text) + " s is longer than the " +
                          std::to_string(int(kMaxFrameTime)) +
                          " s this program accepts (a BVH frame time is a fraction of a second, e.g. 0.0083333)");
    clip_.frameTime = *frameTime;
    if (!lex_.atLineEnd()) {
      Token extra = lex_.next();
      return fail(extra, "unexpected " + quoted(extra.text) + " after the frame time");
    }
    lex_.skipLineEnd();

    // One frame per non-blank line.
    const size_t channels = clip_.channelCount();
    std::vector<float> row;
    while (!lex_.atEnd()) {
      row.clear();
      Token first = lex_.here();
      Token t;
      while (!lex_.atLineEnd()) {
        t = lex_.next();
        auto v = parseNumber<float>(t.text);
        if (!v)
          return fail(t, "expected a number in frame " + std::to_string(clip_.frames.size() + 1) + ", found " +
                             quoted(t.text));
        if (row.size() == channels)
          return fail(t, "frame " + std::to_string(clip_.frames.size() + 1) + " has more than the " +
                             std::to_string(channels) + " values the hierarchy's channels need");
        row.push_back(*v);
      }
      Token lineEnd = lex_.here();
      lex_.skipLineEnd();
      if (row.size() < channels) {
        if (lex_.atEnd()) {
          warn(first, "last frame has " + std::to_string(row.size()) + " of " + std::to_string(channels) +
                          " values (file cut short?); dropped");
          break;
        }
        return fail(lineEnd, "frame " + std::to_string(clip_.frames.size() + 1) + " has " + std::to_string(row.size()) +
                                 " values, expected " + std::to_string(channels));
      }
      if (clip_.frames.size() == kMaxFrames)
        return fail(first, "more than " + std::to_string(kMaxFrames) + " frames (" +
                               std::to_string(kMaxFrames / 120 / 3600) + " hours at 120 fps), the most this program "
                               "reads: split the clip");
      clip_.frames.push_back(row);
    }
    if (static_cast<unsigned long long>(*declared) != clip_.frames.size())
      warn(framesAt, "'Frames:' says " + std::to_string(*declared) + " but " + std::to_string(clip_.frames.size()) +
                         " frames of data follow; using the data");
    return {};
  }

  static constexpr int kMaxDepth = 256;   // deeper nesting is not a skeleton; also bounds the recursion
  // Bounds that keep every timestamp of a converted clip (frame index * frame time, in ns) inside int64 and its
  // memory in proportion: 2^20 frames of at most an hour each.
  static constexpr size_t kMaxFrames = size_t{1} << 20;
  static constexpr double kMaxFrameTime = 3600;
  Lexer lex_;
  int depth_ = 0;
  std::string name_;
  Diagnostics* warnings_;
  BvhClip clip_;
};

void appendNumber(std::string& out, double v) {
  char buf[64];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, end);
}
void appendNumber(std::string& out, float v) {
  char buf[64];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, end);
}

void appendOffset(std::string& out, const std::array<double, 3>& o) {
  out += "OFFSET";
  for (double v : o) {
    out += ' ';
    appendNumber(out, v);
  }
  out += '\n';
}

}  // namespace

std::string_view bvhChannelName(BvhChannel channel) { return kChannelNames[static_cast<size_t>(channel)]; }

size_t BvhClip::channelCount() const {
  size_t n = 0;
  for (const auto& j : joints) n += j.channels.size();
  return n;
}

size_t BvhClip::firstChannel(size_t joint) const {
  size_t n = 0;
  for (size_t j = 0; j < joint && j < joints.size(); ++j) n += joints[j].channels.size();
  return n;
}

std::expected<BvhClip, Diagnostics> readBvhText(std::string_view text, std::string_view name, Diagnostics* warnings) {
  return Parser(text, name, warnings).parse();
}

std::expected<BvhClip, Diagnostics> readBvh(const std::filesystem::path& path, Diagnostics* warnings) {
  auto text = readFileText(path, kMaxBvhFileBytes);
  if (!text) {
    Diagnostics errors;
    const char* what = text.error().message.starts_with("larger") ? "cannot read BVH file: " : "cannot open BVH file: ";
    errors.error({path.string()}, what + text.error().message);
    return std::unexpected(std::move(errors));
  }
  return readBvhText(*text, path.string(), warnings);
}

std::expected<std::string, Diagnostics> writeBvh(const BvhClip& clip) {
  const auto unwritable = [](std::string why) { return std::unexpected(singleError({}, std::move(why))); };
  std::string out = "HIERARCHY\n";
  std::vector<size_t> open;  // joints whose '}' is not written yet
  auto indent = [&](size_t depth) { out.append(depth, '\t'); };
  auto closeJoint = [&]() {
    const BvhJoint& j = clip.joints[open.back()];
    open.pop_back();
    const size_t d = open.size();
    if (j.hasEndSite) {
      indent(d + 1), out += "End Site\n";
      indent(d + 1), out += "{\n";
      indent(d + 2), appendOffset(out, j.endSiteOffset);
      indent(d + 1), out += "}\n";
    }
    indent(d), out += "}\n";
  };
  for (size_t i = 0; i < clip.joints.size(); ++i) {
    const BvhJoint& j = clip.joints[i];
    if (j.parent < -1 || j.parent >= static_cast<int>(i))
      return unwritable("cannot write BVH: joint '" + j.name + "' has a bad parent index");
    while (!open.empty() && static_cast<int>(open.back()) != j.parent) closeJoint();
    if (j.parent >= 0 && open.empty())
      return unwritable("cannot write BVH: joints are not in depth-first order at '" + j.name + "'");
    if (j.name.empty() || j.name.find_first_of("{}\r\n") != std::string::npos)
      return unwritable("cannot write BVH: joint name '" + j.name + "' cannot be written");
    const size_t d = open.size();
    indent(d), out += (j.parent < 0 ? "ROOT " : "JOINT "), out += j.name, out += '\n';
    indent(d), out += "{\n";
    indent(d + 1), appendOffset(out, j.offset);
    indent(d + 1), out += "CHANNELS " + std::to_string(j.channels.size());
    for (BvhChannel c : j.channels) out += ' ', out += bvhChannelName(c);
    out += '\n';
    open.push_back(i);
  }
  while (!open.empty()) closeJoint();

  const size_t channels = clip.channelCount();
  out += "MOTION\nFrames: " + std::to_string(clip.frames.size()) + "\nFrame Time: ";
  appendNumber(out, clip.frameTime);
  out += '\n';
  for (size_t f = 0; f < clip.frames.size(); ++f) {
    const std::vector<float>& frame = clip.frames[f];
    if (frame.size() != channels)
      return unwritable("cannot write BVH: frame " + std::to_string(f) + " has " + std::to_string(frame.size()) +
                        " values for " + std::to_string(channels) + " channels");
    for (size_t i = 0; i < frame.size(); ++i) {
      if (i) out += ' ';
      appendNumber(out, frame[i]);
    }
    out += '\n';
  }
  return out;
}

std::expected<void, Diagnostics> saveBvh(const std::filesystem::path& path, const BvhClip& clip) {
  auto text = writeBvh(clip);
  if (!text) return std::unexpected(singleError({path.string()}, text.error().all().front().message));
  if (auto saved = writeFileAtomically(path.string(), *text); !saved)
    return std::unexpected(singleError({path.string()}, saved.error().message));
  return {};
}

}  // namespace imps::sim
