// SPDX-License-Identifier: BSD-3-Clause
#include "detail/vegaOptionFile.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace asyncfem::detail {

namespace {

std::string trim(std::string_view text) {
  const auto isSpace = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  while (!text.empty() && isSpace(text.front())) text.remove_prefix(1);
  while (!text.empty() && isSpace(text.back())) text.remove_suffix(1);
  return std::string(text);
}

}  // namespace

std::vector<Option> splitOptions(const std::string& text, const std::string& source) {
  std::vector<Option> options;
  std::istringstream in(text);
  std::string raw;
  std::size_t lineNumber = 0;
  bool awaitingValue = false;
  while (std::getline(in, raw)) {
    ++lineNumber;
    const std::string line = trim(raw);
    if (line.empty() || line.front() == '#') continue;
    if (line.front() == '*') {
      if (awaitingValue) {
        throw ParseError(source, options.back().line, "*" + options.back().key + ": no value before the next option");
      }
      const std::string key = trim(std::string_view(line).substr(1));
      if (key.empty()) throw ParseError(source, lineNumber, "'*' without an option name");
      for (const Option& earlier : options) {
        if (earlier.key == key) {
          throw ParseError(source, lineNumber,
                           "*" + key + ": given twice (first on line " + std::to_string(earlier.line) + ")");
        }
      }
      options.push_back({key, "", lineNumber, false});
      awaitingValue = true;
      continue;
    }
    if (!awaitingValue) {
      throw ParseError(source, lineNumber, "\"" + line + "\" is not an option (option names start with '*')");
    }
    options.back().value = line;
    awaitingValue = false;
  }
  if (awaitingValue) throw ParseError(source, options.back().line, "*" + options.back().key + ": no value");
  return options;
}

ConfigOptions::ConfigOptions(std::vector<Option> options, std::string source, std::filesystem::path base)
    : options_(std::move(options)), source_(std::move(source)), base_(std::move(base)) {}

Option* ConfigOptions::find(std::string_view key) {
  for (Option& option : options_) {
    if (option.key == key) return &option;
  }
  return nullptr;
}

void ConfigOptions::fail(const Option& option, const std::string& message) const {
  throw ParseError(source_, option.line, "*" + option.key + ": " + message);
}

void ConfigOptions::note(std::string_view key, const std::string& outcome) {
  if (Option* option = find(key)) {
    option->done = true;
    outcomes_[option->key] = outcome;
  }
}

std::string ConfigOptions::outcome(const std::string& key) const {
  const auto it = outcomes_.find(key);
  return it == outcomes_.end() ? std::string() : it->second;
}

std::optional<std::string> ConfigOptions::text(std::string_view key) {
  Option* option = find(key);
  if (option == nullptr || option->value == "__none") return std::nullopt;
  return option->value;
}

std::optional<double> ConfigOptions::number(std::string_view key) {
  Option* option = find(key);
  if (option == nullptr) return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(option->value.c_str(), &end);
  if (end == option->value.c_str() || *end != '\0' || errno == ERANGE || !std::isfinite(value)) {
    fail(*option, "expected a finite number, got \"" + option->value + "\"");
  }
  return value;
}

std::optional<long> ConfigOptions::integer(std::string_view key) {
  Option* option = find(key);
  if (option == nullptr) return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const long value = std::strtol(option->value.c_str(), &end, 10);
  if (end == option->value.c_str() || *end != '\0' || errno == ERANGE) {
    fail(*option, "expected an integer, got \"" + option->value + "\"");
  }
  return value;
}

std::optional<bool> ConfigOptions::boolean(std::string_view key) {
  Option* option = find(key);
  if (option == nullptr) return std::nullopt;
  std::string value = option->value;
  std::transform(value.begin(), value.end(), value.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (value == "1" || value == "true") return true;
  if (value == "0" || value == "false") return false;
  fail(*option, "expected a boolean (1, 0, true or false), got \"" + option->value + "\"");
}

std::optional<std::pair<std::string, std::filesystem::path>> ConfigOptions::file(std::string_view key) {
  const std::optional<std::string> written = text(key);
  if (!written) return std::nullopt;
  const std::filesystem::path path(*written);
  const std::filesystem::path resolved = path.is_absolute() || base_.empty() ? path : (base_ / path).lexically_normal();
  std::error_code ignored;
  if (!std::filesystem::is_regular_file(resolved, ignored)) {
    fail(*find(key), "no such file: " + resolved.string());
  }
  return std::make_pair(*written, resolved);
}

}  // namespace asyncfem::detail
