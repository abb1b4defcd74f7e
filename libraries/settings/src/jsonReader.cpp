// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/settings/jsonReader.hpp>
#include <cmath>
#include <sstream>

namespace asyncfem {

JsonObjectReader::JsonObjectReader(const nlohmann::json& value, std::string path, std::string sourceName)
    : value_(value), path_(std::move(path)), sourceName_(std::move(sourceName)) {
  if (!value_.is_object()) {
    failAt(sourceName_, path_.empty() ? std::string("(top level)") : path_,
           "expected an object, got " + describe(value_));
  }
}

std::string JsonObjectReader::keyPath(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

std::string JsonObjectReader::elementPath(const std::string& key, std::size_t index) const {
  return keyPath(key) + "[" + std::to_string(index) + "]";
}

void JsonObjectReader::failAt(const std::string& sourceName, const std::string& path, const std::string& message) {
  throw ValidationError(sourceName + ": " + path + ": " + message);
}

void JsonObjectReader::fail(const std::string& key, const std::string& message) const {
  failAt(sourceName_, keyPath(key), message);
}

std::string JsonObjectReader::describe(const nlohmann::json& value) {
  switch (value.type()) {
    case nlohmann::json::value_t::null:
      return "null";
    case nlohmann::json::value_t::boolean:
      return "a boolean";
    case nlohmann::json::value_t::string:
      return "a string";
    case nlohmann::json::value_t::array:
      return "an array";
    case nlohmann::json::value_t::object:
      return "an object";
    case nlohmann::json::value_t::number_integer:
    case nlohmann::json::value_t::number_unsigned:
      return "an integer";
    case nlohmann::json::value_t::number_float:
      return "a number";
    default:
      return "an unsupported value";
  }
}

const nlohmann::json* JsonObjectReader::find(const std::string& key) {
  if (std::find(known_.begin(), known_.end(), key) == known_.end()) {
    known_.push_back(key);
  }
  const auto it = value_.find(key);
  return it == value_.end() ? nullptr : &*it;
}

bool JsonObjectReader::has(const std::string& key) { return find(key) != nullptr; }

const nlohmann::json& JsonObjectReader::required(const std::string& key) {
  const nlohmann::json* value = find(key);
  if (value == nullptr) {
    fail(key, "required key missing");
  }
  return *value;
}

double JsonObjectReader::toNumber(const nlohmann::json& value, const std::string& path, const std::string& sourceName) {
  if (!value.is_number()) {
    failAt(sourceName, path, "expected a number, got " + describe(value));
  }
  const double number = value.get<double>();
  if (!std::isfinite(number)) {
    failAt(sourceName, path, "expected a finite number");
  }
  return number;
}

int JsonObjectReader::toInteger(const nlohmann::json& value, const std::string& path, const std::string& sourceName,
                                int minimum, int maximum) {
  const auto range = [&] {
    return "expected an integer in [" + std::to_string(minimum) + ", " + std::to_string(maximum) + "]";
  };
  if (value.is_number_float()) {
    const double number = value.get<double>();
    // 2.0 is as good an integer as 2 in JSON written by other tools.
    if (std::isfinite(number) && number == std::floor(number) && number >= minimum && number <= maximum) {
      return static_cast<int>(number);
    }
    failAt(sourceName, path, range() + ", got " + value.dump());
  }
  if (value.is_number_unsigned()) {
    const auto number = value.get<std::uint64_t>();
    if (number > static_cast<std::uint64_t>(maximum) || (minimum > 0 && number < static_cast<std::uint64_t>(minimum))) {
      failAt(sourceName, path, range() + ", got " + value.dump());
    }
    return static_cast<int>(number);
  }
  if (value.is_number_integer()) {
    const auto number = value.get<std::int64_t>();
    if (number < minimum || number > maximum) {
      failAt(sourceName, path, range() + ", got " + value.dump());
    }
    return static_cast<int>(number);
  }
  failAt(sourceName, path, range() + ", got " + describe(value));
}

std::string JsonObjectReader::toString(const nlohmann::json& value, const std::string& path,
                                       const std::string& sourceName) {
  if (!value.is_string()) {
    failAt(sourceName, path, "expected a string, got " + describe(value));
  }
  return value.get<std::string>();
}

Eigen::Vector3d JsonObjectReader::toVector3(const nlohmann::json& value, const std::string& path,
                                            const std::string& sourceName) {
  if (!value.is_array() || value.size() != 3 ||
      !std::all_of(value.begin(), value.end(), [](const nlohmann::json& x) { return x.is_number(); })) {
    failAt(sourceName, path, "expected [x, y, z] (three numbers), got " + value.dump());
  }
  Eigen::Vector3d result;
  for (int i = 0; i < 3; ++i) {
    result[i] = toNumber(value[static_cast<std::size_t>(i)], path + "[" + std::to_string(i) + "]", sourceName);
  }
  return result;
}

double JsonObjectReader::number(const std::string& key, double defaultValue) {
  return optionalNumber(key).value_or(defaultValue);
}

std::optional<double> JsonObjectReader::optionalNumber(const std::string& key) {
  const nlohmann::json* value = find(key);
  if (value == nullptr) {
    return std::nullopt;
  }
  return toNumber(*value, keyPath(key), sourceName_);
}

double JsonObjectReader::requiredNumber(const std::string& key) {
  return toNumber(required(key), keyPath(key), sourceName_);
}

int JsonObjectReader::integer(const std::string& key, int defaultValue, int minimum, int maximum) {
  const nlohmann::json* value = find(key);
  return value == nullptr ? defaultValue : toInteger(*value, keyPath(key), sourceName_, minimum, maximum);
}

bool JsonObjectReader::boolean(const std::string& key, bool defaultValue) {
  const nlohmann::json* value = find(key);
  if (value == nullptr) {
    return defaultValue;
  }
  if (!value->is_boolean()) {
    fail(key, "expected true or false, got " + describe(*value));
  }
  return value->get<bool>();
}

std::string JsonObjectReader::string(const std::string& key, const std::string& defaultValue) {
  return optionalString(key).value_or(defaultValue);
}

std::optional<std::string> JsonObjectReader::optionalString(const std::string& key) {
  const nlohmann::json* value = find(key);
  if (value == nullptr) {
    return std::nullopt;
  }
  return toString(*value, keyPath(key), sourceName_);
}

std::string JsonObjectReader::choice(const std::string& key, const std::string& defaultValue,
                                     const std::vector<std::string>& choices) {
  const std::string value = string(key, defaultValue);
  if (std::find(choices.begin(), choices.end(), value) == choices.end()) {
    std::string list;
    for (const std::string& c : choices) {
      list += (list.empty() ? "\"" : ", \"") + c + "\"";
    }
    fail(key, "unknown value \"" + value + "\" (expected one of " + list + ")");
  }
  return value;
}

Eigen::Vector3d JsonObjectReader::vector3(const std::string& key, const Eigen::Vector3d& defaultValue) {
  return optionalVector3(key).value_or(defaultValue);
}

std::optional<Eigen::Vector3d> JsonObjectReader::optionalVector3(const std::string& key) {
  const nlohmann::json* value = find(key);
  if (value == nullptr) {
    return std::nullopt;
  }
  return toVector3(*value, keyPath(key), sourceName_);
}

void JsonObjectReader::finish() const {
  for (const auto& item : value_.items()) {
    if (std::find(known_.begin(), known_.end(), item.key()) == known_.end()) {
      std::string list;
      for (const std::string& k : known_) {
        list += (list.empty() ? "" : ", ") + k;
      }
      failAt(sourceName_, keyPath(item.key()), "unknown key (known here: " + list + ")");
    }
  }
}

}  // namespace asyncfem
