// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <cstddef>
#include <limits>
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

/// Input that parses but whose timestep cannot be used: not positive, or above the
/// stable timestep of an explicit method. Lets scene readers put the error at the
/// timestep's key by its type, not by reading the message.
class TimestepError : public ValidationError {
 public:
  using ValidationError::ValidationError;
};

/// Where a numerical failure happened, as far as the code that detected it knows: every
/// field is optional (time NaN, indices -1 when unknown). Catchers fill in what they add
/// (the run monitor adds frame and step; a multirate integrator the region).
struct NumericalErrorLocation {
  double time = std::numeric_limits<double>::quiet_NaN();  ///< simulation time of the failing step's end
  long long frame = -1;                                    ///< 0-based frame
  long long step = -1;                                     ///< 1-based step count of the run
  int dof = -1;                                            ///< 0-based DOF (3 per vertex)
  int vertex = -1;                                         ///< 0-based vertex
  int region = -1;  ///< multirate integrators: fast region index (-1: L, or unknown / single-rate)
  std::string regionName;

  bool hasTime() const { return time == time; }
};

/// A computation failed numerically: non-finite state, failed factorization,
/// energy blow-up. The message names the step/frame and what went wrong; location()
/// carries the same facts as fields, for programs that react to them.
class NumericalError : public Error {
 public:
  explicit NumericalError(const std::string& message, NumericalErrorLocation location = {})
      : Error(message), location_(std::move(location)) {}
  const NumericalErrorLocation& location() const { return location_; }

 private:
  NumericalErrorLocation location_;
};

}  // namespace asyncfem
