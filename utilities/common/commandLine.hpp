// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What every utility does the same way with its command line: readable range checks
// ("--dt: must be > 0 (got -1)", not CLI11's "not in range 2.2e-308 to 1.79769...e+308"),
// and one exit convention (docs/scene-format.md, "Running a scene"): "PROGRAM: message" on stderr, status 2 for
// a usage error, 1 for any other error, 0 after --help.

#include <CLI/CLI.hpp>
#include <exception>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace asyncfem::cli {

/// Exit status of a command-line (usage) error.
inline constexpr int usageError = 2;
/// Exit status of any other error.
inline constexpr int runError = 1;

/// A command-line value that cannot work (an output extension no writer knows, ...),
/// found after parsing: run() prints it like a parse error and returns usageError.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace detail {
inline std::string number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

/// A check of a numeric option by test(value), failing with "must be <requirement> (got X)".
template <typename Test>
CLI::Validator numberCheck(const std::string& requirement, Test test) {
  return CLI::Validator(
      [requirement, test](std::string& text) -> std::string {
        double value = 0.0;
        std::istringstream in(text);
        if (!(in >> value) || !in.eof() || !test(value)) return "must be " + requirement + " (got " + text + ")";
        return {};
      },
      requirement);
}
}  // namespace detail

/// value > 0
inline CLI::Validator positive() {
  return detail::numberCheck("> 0", [](double value) { return value > 0.0; });
}

/// value >= minimum
inline CLI::Validator atLeast(double minimum) {
  return detail::numberCheck(">= " + detail::number(minimum), [minimum](double value) { return value >= minimum; });
}

/// minimum <= value <= maximum
inline CLI::Validator inRange(double minimum, double maximum) {
  return detail::numberCheck("in [" + detail::number(minimum) + ", " + detail::number(maximum) + "]",
                             [minimum, maximum](double value) { return value >= minimum && value <= maximum; });
}

/// True when a and b name the same file: the same path once symbolic links, "." and ".."
/// are resolved, or (both existing) the same file through a hard link.
inline bool sameFile(const std::filesystem::path& a, const std::filesystem::path& b) {
  std::error_code error;
  if (std::filesystem::exists(a, error) && std::filesystem::exists(b, error) &&
      std::filesystem::equivalent(a, b, error))
    return true;
  // weakly_canonical resolves links only in the leading part that exists: normalize
  // "dir/missing/../x" to "dir/x" first, so that the link x is resolved too.
  const auto resolved = [&error](const std::filesystem::path& path) {
    return std::filesystem::weakly_canonical(std::filesystem::absolute(path, error).lexically_normal(), error);
  };
  const std::filesystem::path canonicalA = resolved(a);
  if (error) return false;
  const std::filesystem::path canonicalB = resolved(b);
  return !error && canonicalA == canonicalB;
}

/// A file a run reads, with what it is for messages ("the scene").
struct NamedPath {
  std::string what;
  std::filesystem::path path;
};

/// Throws std::runtime_error "<output.what> <output> is <input.what> <input>:
/// writing it would destroy the input; <advice>" when an output is one of the inputs.
inline void refuseOutputOverInputs(const NamedPath& output, const std::vector<NamedPath>& inputs,
                                   const std::string& advice) {
  for (const NamedPath& input : inputs) {
    if (sameFile(output.path, input.path)) {
      throw std::runtime_error(output.what + " " + output.path.string() + " is " + input.what + " " +
                               input.path.string() + ": writing it would destroy the input; " + advice);
    }
  }
}

/// Parses the command line. Returns the exit status when the program should stop now: 0
/// after printing --help, usageError after printing "PROGRAM: message (see --help)".
inline std::optional<int> parse(CLI::App& app, int argc, char** argv, const std::string& program) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& help) {
    return app.exit(help);
  } catch (const CLI::CallForAllHelp& help) {
    return app.exit(help);
  } catch (const CLI::ParseError& error) {
    std::cerr << program << ": " << error.what() << " (see --help)\n";
    return usageError;
  }
  return std::nullopt;
}

/// Runs a utility's body: an exception becomes "PROGRAM: message" on stderr and runError
/// (a UsageError: usageError).
template <typename Body>
int run(const std::string& program, Body body) {
  try {
    return body();
  } catch (const UsageError& error) {
    std::cerr << program << ": " << error.what() << " (see --help)\n";
    return usageError;
  } catch (const std::exception& error) {
    std::cerr << program << ": " << error.what() << "\n";
    return runError;
  }
}

}  // namespace asyncfem::cli
