// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/sceneIO/scene.hpp>
#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace asyncfem {

/// What became of one key of a Vega simulator config (docs/file-formats.md, "Vega
/// simulator .config files").
struct VegaConfigKey {
  std::string key;       ///< the option name without its '*'
  std::string value;     ///< the value line as written (trimmed)
  std::size_t line = 0;  ///< 1-based line of the option name
  std::string outcome;   ///< what it maps to ("integrator.name = \"trapezoidal\""), or why it is ignored
};

/// A Vega FEM simulator config (the file Vega's interactive simulator reads) translated
/// into a scene, with the render meshes the scene format has no place for.
struct VegaConfig {
  /// The equivalent scene JSON (docs/scene-format.md); relative paths as written in the
  /// config, resolved against the config's folder like a scene file's.
  nlohmann::json sceneJson;
  /// sceneJson parsed (parseScene); its sourceName is the config file.
  Scene scene;
  /// renderingMeshFilename: Vega's primary render mesh, which shares the volumetric mesh's
  /// vertices (frameRenderer draws the tet mesh's boundary in its place).
  std::optional<std::filesystem::path> renderingMesh;
  /// secondaryRenderingMeshFilename and secondaryRenderingMeshInterpolationFilename: a
  /// render mesh embedded in the volumetric mesh by the weights of a Vega .interp file
  /// (both or neither).
  std::optional<std::filesystem::path> secondaryRenderingMesh;
  std::optional<std::filesystem::path> secondaryInterpolation;
  /// Every key of the file in order, with what it became.
  std::vector<VegaConfigKey> keys;
};

/// Whether path names a Vega simulator config (extension ".config", any case).
bool isVegaConfigPath(const std::filesystem::path& path);

/// Parses the text of a Vega simulator config: `*optionName` lines each followed by the
/// value on the next line that is not blank and not a `#` comment; booleans `0`/`1` or
/// `true`/`false`; filename values `__none` mean "not given". Every key Vega's simulator
/// defines maps to a scene setting, is ignored because it only steers the interactive
/// program (camera, window, mouse forces, threads), is accepted at a value that changes
/// nothing, or is refused; the table is in docs/file-formats.md. Relative paths resolve
/// against baseDirectory. The config has no end time: the scene gets frames.rate =
/// 1 / timestep (one Vega graphics frame), substepsPerTimeStep steps per frame and the
/// default frame count (a utility's --frames changes it).
/// Throws asyncfem::ParseError "SOURCE:LINE: *key: ..." for an unknown key, a key given
/// twice, a missing or malformed value, a refused key or value and a file that does not
/// exist; "SOURCE: ..." (line 0) for a required key that is missing.
VegaConfig parseVegaConfig(const std::string& text, const std::filesystem::path& baseDirectory,
                           const std::string& sourceName);

/// Reads and parses a Vega simulator config (parseVegaConfig); relative paths resolve
/// against its folder. Throws asyncfem::Error if the file cannot be read.
VegaConfig readVegaConfig(const std::filesystem::path& path);

/// The JSON a scene file stands for: a scene file's JSON (comments allowed), or for a
/// Vega config (isVegaConfigPath) its equivalent scene JSON. Errors as loadScene.
nlohmann::json sceneFileJson(const std::filesystem::path& path);

}  // namespace asyncfem
