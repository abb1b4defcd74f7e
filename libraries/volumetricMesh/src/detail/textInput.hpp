// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace asyncfem::detail {

/// Where a line came from: index into FlatText::files and the 1-based line number.
struct Location {
  int file = 0;
  std::size_t line = 0;
};

/// The text of an input file with every `*INCLUDE` spliced in (when enabled), plus the
/// bookkeeping that maps each byte back to its file and line for error messages.
struct FlatText {
  struct Segment {
    std::size_t start = 0;      ///< offset in text where this segment begins
    int file = 0;               ///< index into files
    std::size_t firstLine = 1;  ///< line number (in that file) of the segment's first line
  };
  std::string text;
  std::vector<std::string> files;  ///< file names as shown in messages
  std::vector<Segment> segments;
};

/// Reads a whole file; throws asyncfem::Error naming the path if it cannot be read.
std::string readWholeFile(const std::filesystem::path& path);

/// Loads path; with expandIncludes, lines `*INCLUDE other` (case-insensitive, outside
/// '#' comments) are replaced by the text of `other`, resolved relative to the including
/// file. Cycles, nesting deeper than 32 and more than 4096 includes are ParseErrors.
FlatText loadFlatText(const std::filesystem::path& path, bool expandIncludes);

/// Line-by-line reader over a FlatText that skips blank lines (and '#' comments when
/// asked), trims whitespace, accepts LF, CRLF and CR line ends, and builds ParseErrors
/// "FILE:LINE: message" for the line it is on.
class LineCursor {
 public:
  LineCursor(const FlatText& flat, bool hashComments);

  /// Moves to the next non-blank line; false at the end of the input.
  bool next();
  /// Makes the next call to next() return the current line again.
  void pushBack() { pushedBack_ = true; }
  std::string_view line() const { return line_; }
  Location location() const { return location_; }
  const std::string& fileName() const { return flat_.files[static_cast<std::size_t>(location_.file)]; }
  /// Name of the top-level file (for messages about the whole file).
  const std::string& mainFileName() const { return flat_.files.front(); }
  const std::string& fileName(int file) const { return flat_.files[static_cast<std::size_t>(file)]; }
  /// Bytes not yet consumed: an upper bound for how many more records can follow.
  std::size_t bytesRemaining() const { return flat_.text.size() - pos_; }

  /// Throws ParseError at the current line.
  [[noreturn]] void fail(const std::string& message) const;
  /// Throws ParseError at a stored location.
  [[noreturn]] void failAt(Location where, const std::string& message) const;
  /// Throws ParseError at the end of the input (line 0 of the main file: whole file).
  [[noreturn]] void failAtEnd(const std::string& message) const;

  /// Fails unless count items of at least minBytesPerItem bytes each can still fit in
  /// the rest of the input, so a corrupt header cannot make us allocate absurdly.
  void checkCountFits(long long count, std::size_t minBytesPerItem, const std::string& what) const;

 private:
  const FlatText& flat_;
  bool hashComments_;
  std::size_t pos_ = 0;
  std::size_t segment_ = 0;
  std::size_t nextLineNumber_ = 1;
  bool pushedBack_ = false;
  bool started_ = false;
  std::string_view line_;
  Location location_;
};

/// Splits a line into tokens separated by whitespace (and commas when commas is true).
std::vector<std::string_view> splitTokens(std::string_view line, bool commas);

/// Strict number parsing: the whole token must be a number (std::from_chars; a leading
/// '+' is allowed). Return false instead of throwing so callers can name what they read.
bool parseInteger(std::string_view token, long long& value);
bool parseDouble(std::string_view token, double& value);

/// Helpers that throw a ParseError at the cursor's line naming `what` and the token.
long long integerAt(const LineCursor& cursor, std::string_view token, const std::string& what);
double doubleAt(const LineCursor& cursor, std::string_view token, const std::string& what);
/// A finite double (coordinates, material constants).
double finiteDoubleAt(const LineCursor& cursor, std::string_view token, const std::string& what);

bool equalsIgnoreCase(std::string_view a, std::string_view b);
bool startsWithIgnoreCase(std::string_view text, std::string_view prefix);
std::string_view trim(std::string_view text);
/// Shortest text that reads back to the same double.
std::string formatDouble(double value);

}  // namespace asyncfem::detail
