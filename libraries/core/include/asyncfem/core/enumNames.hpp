// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace asyncfem {

/// One row of an enum's name table: a value and the name it is written and parsed as.
/// A table is a constexpr array `EnumName<E> table[] = {{E::a, "a"}, ...}` in the order
/// its names are listed in messages.
template <class Enum>
struct EnumName {
  Enum value;
  std::string_view name;
};

/// The name of value in table, or nullopt when the table has no row for it.
template <class Enum, std::size_t N>
constexpr std::optional<std::string_view> findEnumName(const EnumName<Enum> (&table)[N], Enum value) {
  for (const EnumName<Enum>& row : table) {
    if (row.value == value) return row.name;
  }
  return std::nullopt;
}

/// The value of the first row of table named name (exact comparison), or nullopt.
template <class Enum, std::size_t N>
constexpr std::optional<Enum> findEnumValue(const EnumName<Enum> (&table)[N], std::string_view name) {
  for (const EnumName<Enum>& row : table) {
    if (row.name == name) return row.value;
  }
  return std::nullopt;
}

/// The names of table in order, joined by separator and, before the last one, by
/// lastSeparator: ("a", "b", "c") with ", " and " or " gives "a, b or c".
template <class Enum, std::size_t N>
std::string joinEnumNames(const EnumName<Enum> (&table)[N], std::string_view separator,
                          std::string_view lastSeparator) {
  std::string joined;
  for (std::size_t i = 0; i < N; ++i) {
    if (i > 0) joined += i + 1 == N ? lastSeparator : separator;
    joined += table[i].name;
  }
  return joined;
}

}  // namespace asyncfem
