// SPDX-License-Identifier: BSD-3-Clause
#include "detail/textInput.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <cctype>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstring>
#include <fstream>
#include <system_error>

namespace asyncfem::detail {

namespace {

constexpr int kMaxIncludeDepth = 32;
constexpr int kMaxIncludes = 4096;

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }

/// End of the line starting at pos (exclusive) and the start of the next line; a line
/// ends at LF, CRLF or a lone CR.
std::size_t lineEnd(const std::string& text, std::size_t pos, std::size_t& nextStart) {
  std::size_t end = pos;
  while (end < text.size() && text[end] != '\n' && text[end] != '\r') ++end;
  nextStart = end;
  if (nextStart < text.size()) {
    nextStart += (text[nextStart] == '\r' && nextStart + 1 < text.size() && text[nextStart + 1] == '\n') ? 2 : 1;
  }
  return end;
}

std::string_view stripComment(std::string_view line) {
  const std::size_t hash = line.find('#');
  return hash == std::string_view::npos ? line : line.substr(0, hash);
}

class IncludeLoader {
 public:
  IncludeLoader(FlatText& flat, bool expand) : flat_(flat), expand_(expand) {}

  /// Appends the file at path (shown as displayName) to the flat text.
  /// includerFile/includerLine say where it was included from (file -1: top level).
  void load(const std::filesystem::path& path, const std::string& displayName, int includerFile,
            std::size_t includerLine) {
    const std::string text = readIncluded(path, includerFile, includerLine);
    std::error_code ec;
    std::filesystem::path canonical = std::filesystem::weakly_canonical(path, ec);
    if (ec) canonical = path.lexically_normal();

    const int fileIndex = static_cast<int>(flat_.files.size());
    flat_.files.push_back(displayName);
    stack_.push_back(canonical);
    appendExpanded(path, text, fileIndex);
    stack_.pop_back();
  }

 private:
  /// The text of the file at path; an included file that cannot be read is a ParseError
  /// at the *INCLUDE line.
  std::string readIncluded(const std::filesystem::path& path, int includerFile, std::size_t includerLine) const {
    if (includerFile < 0) return readWholeFile(path);
    try {
      return readWholeFile(path);
    } catch (const ParseError&) {
      throw;
    } catch (const Error& error) {
      throw ParseError(flat_.files[static_cast<std::size_t>(includerFile)], includerLine,
                       std::string("*INCLUDE: ") + error.what());
    }
  }

  /// Appends text (file fileIndex, read from path) to the flat text, replacing every
  /// *INCLUDE line by the included file when expanding.
  void appendExpanded(const std::filesystem::path& path, const std::string& text, int fileIndex) {
    std::size_t chunkStart = 0;
    std::size_t chunkFirstLine = 1;
    std::size_t lineNumber = 1;
    std::size_t pos = 0;
    while (expand_ && pos < text.size()) {
      std::size_t next = 0;
      const std::size_t end = lineEnd(text, pos, next);
      const std::string_view content = trim(stripComment(std::string_view(text).substr(pos, end - pos)));
      if (startsWithIgnoreCase(content, "*INCLUDE") && (content.size() == 8 || isSpace(content[8]))) {
        appendChunk(text, chunkStart, pos, fileIndex, chunkFirstLine);
        include(path, content.substr(8), fileIndex, lineNumber);
        chunkStart = next;
        chunkFirstLine = lineNumber + 1;
      }
      pos = next;
      ++lineNumber;
    }
    appendChunk(text, chunkStart, text.size(), fileIndex, chunkFirstLine);
  }

  void appendChunk(const std::string& text, std::size_t begin, std::size_t end, int file, std::size_t firstLine) {
    if (begin >= end) return;
    flat_.segments.push_back({flat_.text.size(), file, firstLine});
    flat_.text.append(text, begin, end - begin);
    // Every chunk ends a line, so the next chunk starts on a fresh one.
    if (flat_.text.back() != '\n' && flat_.text.back() != '\r') flat_.text.push_back('\n');
  }

  void include(const std::filesystem::path& includer, std::string_view argument, int includerFile,
               std::size_t includerLine) {
    const std::string& includerName = flat_.files[static_cast<std::size_t>(includerFile)];
    std::string_view name = trim(argument);
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"') name = name.substr(1, name.size() - 2);
    if (name.empty()) throw ParseError(includerName, includerLine, "*INCLUDE needs a file name");
    if (static_cast<int>(stack_.size()) > kMaxIncludeDepth) {
      throw ParseError(includerName, includerLine,
                       "*INCLUDE nested deeper than " + std::to_string(kMaxIncludeDepth) + " files");
    }
    if (++includeCount_ > kMaxIncludes) {
      throw ParseError(includerName, includerLine, "more than " + std::to_string(kMaxIncludes) + " *INCLUDEs");
    }
    const std::filesystem::path target = includer.parent_path() / std::filesystem::path(std::string(name));
    std::error_code ec;
    std::filesystem::path canonical = std::filesystem::weakly_canonical(target, ec);
    if (ec) canonical = target.lexically_normal();
    if (std::find(stack_.begin(), stack_.end(), canonical) != stack_.end()) {
      std::string chain;
      for (const auto& p : stack_) chain += p.filename().string() + " -> ";
      throw ParseError(includerName, includerLine, "*INCLUDE cycle: " + chain + canonical.filename().string());
    }
    load(target, target.string(), includerFile, includerLine);
  }

  FlatText& flat_;
  bool expand_;
  std::vector<std::filesystem::path> stack_;
  int includeCount_ = 0;
};

}  // namespace

std::string readWholeFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw Error("cannot read '" + path.string() + "': no such file");
  if (std::filesystem::is_directory(path, ec)) throw Error("cannot read '" + path.string() + "': it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open '" + path.string() + "': " + std::strerror(errno));
  std::string text;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  if (size > 0) {
    text.resize(static_cast<std::size_t>(size));
    in.read(text.data(), size);
  }
  if (!in && !in.eof()) throw Error("cannot read '" + path.string() + "': read failed");
  text.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return text;
}

FlatText loadFlatText(const std::filesystem::path& path, bool expandIncludes) {
  FlatText flat;
  IncludeLoader loader(flat, expandIncludes);
  loader.load(path, path.string(), -1, 0);
  return flat;
}

LineCursor::LineCursor(const FlatText& flat, bool hashComments) : flat_(flat), hashComments_(hashComments) {
  if (!flat_.segments.empty()) nextLineNumber_ = flat_.segments.front().firstLine;
}

bool LineCursor::next() {
  if (pushedBack_) {
    pushedBack_ = false;
    return started_;
  }
  const std::string& text = flat_.text;
  while (pos_ < text.size()) {
    while (segment_ + 1 < flat_.segments.size() && pos_ >= flat_.segments[segment_ + 1].start) {
      ++segment_;
      nextLineNumber_ = flat_.segments[segment_].firstLine;
    }
    std::size_t after = 0;
    const std::size_t end = lineEnd(text, pos_, after);
    std::string_view content = std::string_view(text).substr(pos_, end - pos_);
    location_ = {flat_.segments.empty() ? 0 : flat_.segments[segment_].file, nextLineNumber_};
    ++nextLineNumber_;
    pos_ = after;
    if (hashComments_) content = stripComment(content);
    content = trim(content);
    if (!content.empty()) {
      line_ = content;
      started_ = true;
      return true;
    }
  }
  started_ = false;
  line_ = {};
  return false;
}

void LineCursor::fail(const std::string& message) const {
  if (!started_) failAtEnd(message);
  failAt(location_, message);
}

void LineCursor::failAt(Location where, const std::string& message) const {
  throw ParseError(fileName(where.file), where.line, message);
}

void LineCursor::failAtEnd(const std::string& message) const {
  throw ParseError(flat_.files.front(), 0, message + " (at end of file)");
}

void LineCursor::checkCountFits(long long count, std::size_t minBytesPerItem, const std::string& what) const {
  if (count < 0) fail("negative " + what + " count " + std::to_string(count));
  if (count > INT_MAX)
    fail(what + " count " + std::to_string(count) + " exceeds the supported maximum " + std::to_string(INT_MAX));
  const std::size_t fits = bytesRemaining() / minBytesPerItem;
  if (static_cast<unsigned long long>(count) > fits) {
    fail("header says " + std::to_string(count) + " " + what + ", but the rest of the file (" +
         std::to_string(bytesRemaining()) + " bytes) can hold at most " + std::to_string(fits));
  }
}

std::vector<std::string_view> splitTokens(std::string_view line, bool commas) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  auto separator = [&](char c) { return isSpace(c) || (commas && c == ','); };
  while (i < line.size()) {
    while (i < line.size() && separator(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !separator(line[i])) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

bool parseInteger(std::string_view token, long long& value) {
  if (token.size() > 1 && token.front() == '+' && token[1] != '-') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  return ec == std::errc() && ptr == end && !token.empty();
}

bool parseDouble(std::string_view token, double& value) {
  if (token.size() > 1 && token.front() == '+' && token[1] != '-') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value, std::chars_format::general);
  return ec == std::errc() && ptr == end && !token.empty();
}

long long integerAt(const LineCursor& cursor, std::string_view token, const std::string& what) {
  long long value = 0;
  if (!parseInteger(token, value)) cursor.fail(what + ": expected an integer, got '" + std::string(token) + "'");
  return value;
}

double doubleAt(const LineCursor& cursor, std::string_view token, const std::string& what) {
  double value = 0;
  if (!parseDouble(token, value)) cursor.fail(what + ": expected a number, got '" + std::string(token) + "'");
  return value;
}

double finiteDoubleAt(const LineCursor& cursor, std::string_view token, const std::string& what) {
  const double value = doubleAt(cursor, token, what);
  if (!std::isfinite(value)) cursor.fail(what + ": value '" + std::string(token) + "' is not finite");
  return value;
}

bool equalsIgnoreCase(std::string_view a, std::string_view b) {
  return a.size() == b.size() && startsWithIgnoreCase(a, b);
}

bool startsWithIgnoreCase(std::string_view text, std::string_view prefix) {
  if (text.size() < prefix.size()) return false;
  for (std::size_t i = 0; i < prefix.size(); ++i) {
    if (std::toupper(static_cast<unsigned char>(text[i])) != std::toupper(static_cast<unsigned char>(prefix[i]))) {
      return false;
    }
  }
  return true;
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && isSpace(text.front())) text.remove_prefix(1);
  while (!text.empty() && isSpace(text.back())) text.remove_suffix(1);
  return text;
}

std::string formatDouble(double value) {
  char buffer[64];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return ec == std::errc() ? std::string(buffer, ptr) : std::to_string(value);
}

}  // namespace asyncfem::detail
