// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace asyncfem {

/// Base of every exception AsyncFEM throws. The message is complete and meant for
/// the user: it names the file and line, the element or vertex, or the scene key.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Malformed input file. what() reads "FILE:LINE: MESSAGE" (LINE is 1-based; 0 when
/// the problem concerns the whole file, e.g. a missing section).
class ParseError : public Error {
 public:
  ParseError(std::string file, std::size_t line, const std::string& message)
      : Error(format(file, line, message)), file_(std::move(file)), line_(line) {}

  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }

 private:
  static std::string format(const std::string& file, std::size_t line, const std::string& message) {
    return line > 0 ? file + ":" + std::to_string(line) + ": " + message : file + ": " + message;
  }
  std::string file_;
  std::size_t line_;
};

/// Input that parses but is not valid (degenerate element, unknown set name, bad
/// region partition, bad scene value, ...).
class ValidationError : public Error {
 public:
  using Error::Error;
};

/// A computation failed numerically: non-finite state, failed factorization,
/// energy blow-up. The message names the step/frame and what went wrong.
class NumericalError : public Error {
 public:
  using Error::Error;
};

}  // namespace asyncfem
