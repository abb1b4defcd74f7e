// SPDX-License-Identifier: BSD-3-Clause
// The scene keys of several bodies (objects) and of surface contact (contact.obstacles,
// contact.surfaces); docs/scene-format.md.
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/settings/jsonReader.hpp>
#include <cmath>
#include <numbers>
#include <set>

#include "detail/sceneSections.hpp"

namespace asyncfem::detail {

namespace {

using nlohmann::json;

// {"axis": [x, y, z], "angle": degrees}.
Eigen::Quaterniond parseRotation(const json& value, const std::string& path, const std::string& source) {
  JsonObjectReader reader(value, path, source);
  const Eigen::Vector3d axis = JsonObjectReader::toVector3(reader.required("axis"), reader.keyPath("axis"), source);
  const double degrees = reader.requiredNumber("angle");
  reader.finish();
  if (!(axis.norm() > 0.0)) reader.fail("axis", "expected a non-zero vector");
  return Eigen::Quaterniond(Eigen::AngleAxisd(degrees * std::numbers::pi / 180.0, axis.normalized()));
}

// "translation", "rotation", "scale" of an object or obstacle.
Scene::Placement parsePlacement(JsonObjectReader& reader, const std::string& source) {
  Scene::Placement placement;
  placement.translation = reader.vector3("translation", Eigen::Vector3d::Zero());
  if (const json* rotation = reader.find("rotation")) {
    placement.rotation = parseRotation(*rotation, reader.keyPath("rotation"), source);
  }
  placement.scale = reader.number("scale", 1.0);
  if (!(placement.scale > 0.0)) reader.fail("scale", "expected a scale factor > 0");
  return placement;
}

// An object's or obstacle's name: non-empty, no '/', not "allElements", unique among names.
std::string parseName(JsonObjectReader& reader, std::set<std::string>& taken) {
  const std::string name = reader.string("name", "");
  if (name.empty()) reader.fail("name", "expected a non-empty name");
  if (name.find('/') != std::string::npos || name == "allElements") {
    reader.fail("name", "\"" + name + "\" cannot name an object (no '/', not allElements)");
  }
  if (!taken.insert(name).second) reader.fail("name", "\"" + name + "\" names two objects or obstacles");
  return name;
}

Scene::Object parseObject(const json& value, const std::string& path, Scene& scene, std::set<std::string>& names) {
  const std::string& source = scene.sourceName;
  JsonObjectReader reader(value, path, source);
  Scene::Object object;
  object.name = parseName(reader, names);
  parseMeshSection(reader.required("mesh"), reader.keyPath("mesh"), scene, object.mesh);
  if (const json* fixed = reader.find("fixed")) {
    parseFixedSection(*fixed, reader.keyPath("fixed"), scene, object.fixed);
    scene.fixed.sets.push_back(object.name + "/fixed");
  }
  object.placement = parsePlacement(reader, source);
  object.velocity = reader.vector3("velocity", Eigen::Vector3d::Zero());
  reader.finish();
  return object;
}

// path: [{"time", "translation", "rotation"}, ...], at least two keys, times increasing.
std::vector<RigidKey> parsePath(const json& value, const std::string& path, const std::string& source) {
  if (!value.is_array()) JsonObjectReader::failAt(source, path, "expected an array of {time, translation, rotation}");
  if (value.size() < 2) {
    JsonObjectReader::failAt(source, path,
                             "a moving obstacle's path needs at least two keys (got " + std::to_string(value.size()) +
                                 "); leave path out for a static obstacle");
  }
  std::vector<RigidKey> keys;
  for (std::size_t k = 0; k < value.size(); ++k) {
    JsonObjectReader reader(value[k], path + "[" + std::to_string(k) + "]", source);
    RigidKey key;
    key.time = reader.requiredNumber("time");
    key.translation = reader.vector3("translation", Eigen::Vector3d::Zero());
    if (const json* rotation = reader.find("rotation")) {
      key.rotation = parseRotation(*rotation, reader.keyPath("rotation"), source);
    }
    reader.finish();
    if (!keys.empty() && !(key.time > keys.back().time)) {
      reader.fail("time", "key times must increase (the key before is at " + std::to_string(keys.back().time) + ")");
    }
    keys.push_back(key);
  }
  return keys;
}

Scene::Contact::Obstacle parseObstacle(const json& value, const std::string& path, Scene& scene,
                                       std::set<std::string>& names) {
  const std::string& source = scene.sourceName;
  JsonObjectReader reader(value, path, source);
  Scene::Contact::Obstacle obstacle;
  obstacle.name = parseName(reader, names);
  obstacle.file = resolveScenePath(scene, reader, "file");
  obstacle.closed = reader.boolean("closed", true);
  obstacle.placement = parsePlacement(reader, source);
  if (const json* keys = reader.find("path")) obstacle.path = parsePath(*keys, reader.keyPath("path"), source);
  reader.finish();
  return obstacle;
}

Scene::Contact::Surfaces parseSurfaces(const json& value, const std::string& path, const std::string& source) {
  JsonObjectReader reader(value, path, source);
  Scene::Contact::Surfaces surfaces;
  surfaces.thickness = reader.optionalNumber("thickness");
  if (surfaces.thickness && !(*surfaces.thickness > 0.0)) reader.fail("thickness", "expected a length > 0");
  surfaces.betweenBodies = reader.boolean("betweenBodies", true);
  surfaces.self = reader.boolean("self", false);
  surfaces.edges = reader.boolean("edges", true);
  surfaces.broadPhase = reader.choice("broadPhase", "spatialHash", {"spatialHash", "dynamicTree"}) == "dynamicTree"
                            ? BroadPhaseMethod::DynamicTree
                            : BroadPhaseMethod::SpatialHash;
  reader.finish();
  return surfaces;
}

}  // namespace

void parseObjects(const json& objects, Scene& scene) {
  if (!objects.is_array() || objects.empty()) {
    JsonObjectReader::failAt(scene.sourceName, "objects", "expected a non-empty array of {name, mesh, ...}");
  }
  std::set<std::string> names;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    scene.objects.push_back(parseObject(objects[i], "objects[" + std::to_string(i) + "]", scene, names));
  }
}

void parseContactSurfaces(JsonObjectReader& contact, Scene& scene) {
  Scene::Contact& out = scene.contact;
  std::set<std::string> names;
  for (const Scene::Object& object : scene.objects) names.insert(object.name);
  if (const json* obstacles = contact.find("obstacles")) {
    if (!obstacles->is_array()) contact.fail("obstacles", "expected an array of {name, file, ...}");
    for (std::size_t i = 0; i < obstacles->size(); ++i) {
      out.obstacles.push_back(parseObstacle((*obstacles)[i], contact.elementPath("obstacles", i), scene, names));
    }
  }
  if (const json* surfaces = contact.find("surfaces")) {
    out.surfaces = parseSurfaces(*surfaces, contact.keyPath("surfaces"), scene.sourceName);
  } else if (!out.obstacles.empty()) {
    out.surfaces = Scene::Contact::Surfaces{};
  }
}

}  // namespace asyncfem::detail
