// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

/// The option-file layer of Vega's simulator configs: `*key` lines, their value lines and
/// typed access that throws ParseError naming the file, the line and the key. What the keys
/// mean is vegaConfig.cpp's business.
namespace asyncfem::detail {

/// One `*key` and its value line.
struct Option {
  std::string key;
  std::string value;     ///< trimmed
  std::size_t line = 0;  ///< 1-based line of the key
  bool done = false;     ///< given an outcome (ConfigOptions::note)
};

/// The options in file order: each `*key` takes the next line that is neither blank nor a
/// `#` comment as its value (commented alternatives may sit between them). Throws
/// ParseError for a key given twice, a key without a value and a value without a key.
std::vector<Option> splitOptions(const std::string& text, const std::string& source);

/// The options of one config, typed access to their values, and what each became.
class ConfigOptions {
 public:
  ConfigOptions(std::vector<Option> options, std::string source, std::filesystem::path base);

  /// The option named key, or null.
  Option* find(std::string_view key);
  /// Throws ParseError "SOURCE:LINE: *key: message".
  [[noreturn]] void fail(const Option& option, const std::string& message) const;
  const std::string& source() const { return source_; }
  const std::vector<Option>& all() const { return options_; }

  /// Records what the option key (if given) became, and marks it done.
  void note(std::string_view key, const std::string& outcome);
  /// What note() recorded for key (empty if nothing).
  std::string outcome(const std::string& key) const;

  /// The value, or nothing when the key is absent or the value is `__none`.
  std::optional<std::string> text(std::string_view key);
  /// A finite number (strtod syntax: 1000, 25E5, -0.5).
  std::optional<double> number(std::string_view key);
  /// A whole decimal number.
  std::optional<long> integer(std::string_view key);
  /// `1`, `0`, `true` or `false`, in any case.
  std::optional<bool> boolean(std::string_view key);
  /// A file value: as written (for the scene JSON) and resolved against the config's
  /// folder; the file must exist.
  std::optional<std::pair<std::string, std::filesystem::path>> file(std::string_view key);

 private:
  std::vector<Option> options_;
  std::string source_;
  std::filesystem::path base_;
  std::map<std::string, std::string> outcomes_;
};

}  // namespace asyncfem::detail
