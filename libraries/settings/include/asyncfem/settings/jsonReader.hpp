// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace asyncfem {

/// Reads the keys of one JSON object with type and range checks, remembering which keys
/// were asked for so that finish() can reject the others. Every error is an
/// asyncfem::ValidationError reading "<sourceName>: <full key path>: <message>", e.g.
/// "scene.json: forces[1].window: expected [start, end] with start <= end".
///
/// Used by the scene parser and by integrator factories reading `integrator.options`.
class JsonObjectReader {
 public:
  /// value must be a JSON object (else an error naming path). path: the object's own key
  /// path ("" for the document root, "integrator.options", "forces[2]").
  JsonObjectReader(const nlohmann::json& value, std::string path, std::string sourceName);

  /// Path of a key of this object ("forces[2].window").
  std::string keyPath(const std::string& key) const;
  /// Path of element index of an array value of this object ("fixed.sets[0]").
  std::string elementPath(const std::string& key, std::size_t index) const;
  const std::string& path() const { return path_; }
  const std::string& sourceName() const { return sourceName_; }

  /// Marks key as known and returns its value, or nullptr when absent.
  const nlohmann::json* find(const std::string& key);
  /// Marks key as known; true when present.
  bool has(const std::string& key);
  /// The value of a key that must be present.
  const nlohmann::json& required(const std::string& key);

  /// A finite number (JSON integers are accepted).
  double number(const std::string& key, double defaultValue);
  std::optional<double> optionalNumber(const std::string& key);
  double requiredNumber(const std::string& key);
  /// An integer in [minimum, maximum].
  int integer(const std::string& key, int defaultValue, int minimum, int maximum);
  bool boolean(const std::string& key, bool defaultValue);
  std::string string(const std::string& key, const std::string& defaultValue);
  std::optional<std::string> optionalString(const std::string& key);
  /// A string that must be one of choices (the error lists them).
  std::string choice(const std::string& key, const std::string& defaultValue, const std::vector<std::string>& choices);
  /// [x, y, z], three finite numbers.
  Eigen::Vector3d vector3(const std::string& key, const Eigen::Vector3d& defaultValue);
  std::optional<Eigen::Vector3d> optionalVector3(const std::string& key);

  /// Throws for the first key present in the object that no call above asked for,
  /// listing the keys this object knows.
  void finish() const;

  /// Throws "<sourceName>: <keyPath(key)>: <message>".
  [[noreturn]] void fail(const std::string& key, const std::string& message) const;

  /// Conversions of a value at an arbitrary path (elements of arrays).
  static double toNumber(const nlohmann::json& value, const std::string& path, const std::string& sourceName);
  static int toInteger(const nlohmann::json& value, const std::string& path, const std::string& sourceName, int minimum,
                       int maximum);
  static std::string toString(const nlohmann::json& value, const std::string& path, const std::string& sourceName);
  static Eigen::Vector3d toVector3(const nlohmann::json& value, const std::string& path, const std::string& sourceName);
  /// Throws "<sourceName>: <path>: <message>".
  [[noreturn]] static void failAt(const std::string& sourceName, const std::string& path, const std::string& message);
  /// "a number", "a string", ... for messages.
  static std::string describe(const nlohmann::json& value);

 private:
  const nlohmann::json& value_;
  std::string path_;
  std::string sourceName_;
  std::vector<std::string> known_;
};

}  // namespace asyncfem
