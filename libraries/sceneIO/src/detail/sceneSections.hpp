// SPDX-License-Identifier: BSD-3-Clause
// Sections of the scene parser that live in their own files. Private to the library.
#pragma once

#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/settings/jsonReader.hpp>

namespace asyncfem::detail {

/// Reads the "forceModel" section into scene.forceModel and scene.hyperelastic (errors name
/// the key under forceModel).
void parseForceModel(JsonObjectReader& top, Scene& scene);

/// A mesh section ({"file"} or {"generator", ...}) at key path `path` into mesh.
void parseMeshSection(const nlohmann::json& value, const std::string& path, const Scene& scene, Scene::Mesh& mesh);
/// A fixed section ({"sets", "boxes", "bou"}) at key path `path`, added to fixed.
void parseFixedSection(const nlohmann::json& value, const std::string& path, const Scene& scene, Scene::Fixed& fixed);
/// The non-empty path at key, resolved against the scene's folder.
std::filesystem::path resolveScenePath(const Scene& scene, JsonObjectReader& reader, const std::string& key);

/// The "objects" array (several bodies) into scene.objects; adds each object's fixed
/// vertex set "<name>/fixed" to scene.fixed.sets (sceneObjectKeys.cpp).
void parseObjects(const nlohmann::json& objects, Scene& scene);
/// contact.obstacles and contact.surfaces (sceneObjectKeys.cpp).
void parseContactSurfaces(JsonObjectReader& contact, Scene& scene);

}  // namespace asyncfem::detail
