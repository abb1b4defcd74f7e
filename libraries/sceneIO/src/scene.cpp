// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/vegaConfig.hpp>
#include <asyncfem/settings/jsonReader.hpp>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "detail/frameTiming.hpp"
#include "detail/sceneSections.hpp"

namespace asyncfem {

namespace {

using nlohmann::json;

constexpr int maxInt = std::numeric_limits<int>::max();

std::filesystem::path resolvePath(const std::filesystem::path& base, const std::string& text) {
  const std::filesystem::path path(text);
  return path.is_absolute() || base.empty() ? path.lexically_normal() : (base / path).lexically_normal();
}

std::string pathString(JsonObjectReader& reader, const std::string& key) {
  const std::string text = reader.string(key, "");
  if (text.empty()) {
    reader.fail(key, "expected a non-empty path");
  }
  return text;
}

// A material object { "name", "density", "youngsModulus", "poissonRatio" } over defaults.
Material parseMaterial(const json& value, const std::string& path, const std::string& source, Material material) {
  JsonObjectReader reader(value, path, source);
  material.name = reader.string("name", material.name);
  if (material.name.empty()) {
    reader.fail("name", "expected a non-empty name");
  }
  material.density = reader.number("density", material.density);
  material.youngsModulus = reader.number("youngsModulus", material.youngsModulus);
  material.poissonRatio = reader.number("poissonRatio", material.poissonRatio);
  reader.finish();
  if (material.density <= 0.0) {
    reader.fail("density", "expected a density > 0");
  }
  if (material.youngsModulus <= 0.0) {
    reader.fail("youngsModulus", "expected a Young's modulus > 0");
  }
  if (material.poissonRatio <= -1.0 || material.poissonRatio >= 0.5) {
    reader.fail("poissonRatio", "expected a Poisson ratio in (-1, 0.5)");
  }
  return material;
}

void requirePositive(JsonObjectReader& reader, const std::string& key, double value) {
  if (!(value > 0.0)) {
    reader.fail(key, "expected a number > 0");
  }
}

void parseBeam(JsonObjectReader& reader, const std::string& source, BeamSpec& beam) {
  beam.length = reader.number("length", beam.length);
  requirePositive(reader, "length", beam.length);
  beam.height = reader.number("height", beam.height);
  requirePositive(reader, "height", beam.height);
  beam.depth = reader.number("depth", beam.depth);
  requirePositive(reader, "depth", beam.depth);
  beam.cellsAlongLength = reader.integer("cellsAlongLength", beam.cellsAlongLength, 1, 100000);
  beam.tipFraction = reader.number("tipFraction", beam.tipFraction);
  if (beam.tipFraction < 0.0 || beam.tipFraction >= 1.0) {
    reader.fail("tipFraction", "expected a fraction in [0, 1)");
  }
  if (const json* body = reader.find("body")) {
    beam.body = parseMaterial(*body, reader.keyPath("body"), source, beam.body);
  }
  if (const json* tip = reader.find("tip")) {
    beam.tip = parseMaterial(*tip, reader.keyPath("tip"), source, beam.tip);
  }
}

// mesh.regions[i]: { "name", "min", "max", "material" }.
BoxRegion parseBoxRegion(const json& value, const std::string& path, const std::string& source) {
  JsonObjectReader region(value, path, source);
  BoxRegion result;
  result.name = region.string("name", "");
  if (result.name.empty()) {
    region.fail("name", "expected a non-empty name");
  }
  result.min = JsonObjectReader::toVector3(region.required("min"), region.keyPath("min"), source);
  result.max = JsonObjectReader::toVector3(region.required("max"), region.keyPath("max"), source);
  if ((result.min.array() > result.max.array()).any()) {
    JsonObjectReader::failAt(source, path, "expected min <= max");
  }
  result.material = parseMaterial(region.required("material"), region.keyPath("material"), source,
                                  Material{result.name, 1000.0, 1e6, 0.45});
  region.finish();
  return result;
}

void parseBox(JsonObjectReader& reader, const std::string& source, BoxMeshSpec& box) {
  box.origin = reader.vector3("origin", box.origin);
  box.size = reader.vector3("size", box.size);
  if ((box.size.array() <= 0.0).any()) {
    reader.fail("size", "expected three sizes > 0");
  }
  if (const json* cells = reader.find("cells")) {
    const std::string path = reader.keyPath("cells");
    if (!cells->is_array() || cells->size() != 3) {
      JsonObjectReader::failAt(source, path, "expected [nx, ny, nz] (three integers >= 1)");
    }
    for (int i = 0; i < 3; ++i) {
      box.cells[i] = JsonObjectReader::toInteger((*cells)[static_cast<std::size_t>(i)],
                                                 path + "[" + std::to_string(i) + "]", source, 1, 10000);
    }
  }
  if (const json* material = reader.find("material")) {
    box.material = parseMaterial(*material, reader.keyPath("material"), source, box.material);
  }
  if (const json* regions = reader.find("regions")) {
    if (!regions->is_array()) {
      reader.fail("regions", "expected an array of {name, min, max, material}");
    }
    for (std::size_t i = 0; i < regions->size(); ++i) {
      box.regions.push_back(parseBoxRegion((*regions)[i], reader.elementPath("regions", i), source));
    }
  }
}

void parseMesh(JsonObjectReader& top, Scene& scene) {
  if (const json* objects = top.find("objects")) {
    if (top.has("mesh")) top.fail("mesh", "give either \"mesh\" (one body) or \"objects\" (several), not both");
    detail::parseObjects(*objects, scene);
    return;
  }
  detail::parseMeshSection(top.required("mesh"), "mesh", scene, scene.mesh);
}

void parseMaterials(JsonObjectReader& top, Scene& scene) {
  const json* materials = top.find("materials");
  if (materials == nullptr) {
    return;
  }
  if (!materials->is_array()) {
    top.fail("materials", "expected an array of {set, density, youngsModulus, poissonRatio}");
  }
  for (std::size_t i = 0; i < materials->size(); ++i) {
    JsonObjectReader reader((*materials)[i], top.elementPath("materials", i), scene.sourceName);
    Scene::MaterialOverride override;
    override.set = JsonObjectReader::toString(reader.required("set"), reader.keyPath("set"), scene.sourceName);
    override.density = reader.optionalNumber("density");
    override.youngsModulus = reader.optionalNumber("youngsModulus");
    override.poissonRatio = reader.optionalNumber("poissonRatio");
    reader.finish();
    if (!override.density && !override.youngsModulus && !override.poissonRatio) {
      JsonObjectReader::failAt(scene.sourceName, reader.path(),
                               "gives no constant to override (density, youngsModulus, poissonRatio)");
    }
    if (override.density && *override.density <= 0.0) {
      reader.fail("density", "expected a density > 0");
    }
    if (override.youngsModulus && *override.youngsModulus <= 0.0) {
      reader.fail("youngsModulus", "expected a Young's modulus > 0");
    }
    if (override.poissonRatio && (*override.poissonRatio <= -1.0 || *override.poissonRatio >= 0.5)) {
      reader.fail("poissonRatio", "expected a Poisson ratio in (-1, 0.5)");
    }
    scene.materials.push_back(override);
  }
}

void parseFixed(JsonObjectReader& top, Scene& scene) {
  const json* fixed = top.find("fixed");
  if (fixed == nullptr) {
    return;
  }
  detail::parseFixedSection(*fixed, "fixed", scene, scene.fixed);
}

}  // namespace

namespace detail {

std::filesystem::path resolveScenePath(const Scene& scene, JsonObjectReader& reader, const std::string& key) {
  return resolvePath(scene.baseDirectory, pathString(reader, key));
}

void parseMeshSection(const json& value, const std::string& path, const Scene& scene, Scene::Mesh& mesh) {
  const std::string& source = scene.sourceName;
  JsonObjectReader reader(value, path, source);
  const bool hasFile = reader.has("file");
  const bool hasGenerator = reader.has("generator");
  if (hasFile == hasGenerator) {
    JsonObjectReader::failAt(source, path, "give either \"file\" or \"generator\"");
  }
  if (hasFile) {
    mesh.source = Scene::MeshSource::file;
    mesh.file = resolvePath(scene.baseDirectory, pathString(reader, "file"));
  } else if (reader.choice("generator", "", {"beam", "box"}) == "beam") {
    mesh.source = Scene::MeshSource::beam;
    parseBeam(reader, source, mesh.beam);
  } else {
    mesh.source = Scene::MeshSource::box;
    parseBox(reader, source, mesh.box);
  }
  reader.finish();
}

void parseFixedSection(const json& value, const std::string& path, const Scene& scene, Scene::Fixed& fixed) {
  const std::string& source = scene.sourceName;
  JsonObjectReader reader(value, path, source);
  if (const json* sets = reader.find("sets")) {
    if (!sets->is_array()) {
      reader.fail("sets", "expected an array of vertex set names");
    }
    for (std::size_t i = 0; i < sets->size(); ++i) {
      fixed.sets.push_back(JsonObjectReader::toString((*sets)[i], reader.elementPath("sets", i), source));
    }
  }
  if (const json* boxes = reader.find("boxes")) {
    if (!boxes->is_array()) {
      reader.fail("boxes", "expected an array of {min, max}");
    }
    for (std::size_t i = 0; i < boxes->size(); ++i) {
      const std::string path = reader.elementPath("boxes", i);
      JsonObjectReader boxReader((*boxes)[i], path, source);
      Scene::Box box;
      box.min = JsonObjectReader::toVector3(boxReader.required("min"), boxReader.keyPath("min"), source);
      box.max = JsonObjectReader::toVector3(boxReader.required("max"), boxReader.keyPath("max"), source);
      boxReader.finish();
      if ((box.min.array() > box.max.array()).any()) {
        JsonObjectReader::failAt(source, path, "expected min <= max in every coordinate");
      }
      fixed.boxes.push_back(box);
    }
  }
  if (reader.has("bou")) {
    fixed.bouFile = resolvePath(scene.baseDirectory, pathString(reader, "bou"));
  }
  reader.finish();
}

}  // namespace detail

namespace {

// The vertices a force acts on: "set" or "vertices" (0-based ids).
void parseForceTarget(JsonObjectReader& reader, const std::string& source, Scene::Force& force) {
  const bool hasSet = reader.has("set");
  if (hasSet == reader.has("vertices")) {
    JsonObjectReader::failAt(source, reader.path(), "give either \"set\" or \"vertices\"");
  }
  if (hasSet) {
    force.set = reader.string("set", "");
    if (force.set.empty()) {
      reader.fail("set", "expected a non-empty vertex set name");
    }
    return;
  }
  const json& vertices = *reader.find("vertices");
  if (!vertices.is_array() || vertices.empty()) {
    reader.fail("vertices", "expected a non-empty array of 0-based vertex ids");
  }
  for (std::size_t k = 0; k < vertices.size(); ++k) {
    force.vertices.push_back(
        JsonObjectReader::toInteger(vertices[k], reader.elementPath("vertices", k), source, 0, maxInt));
  }
}

// A pull's "force" and optional "window": [start, end].
void parsePull(JsonObjectReader& reader, const std::string& source, Scene::Force& force) {
  force.vector = JsonObjectReader::toVector3(reader.required("force"), reader.keyPath("force"), source);
  const json* window = reader.find("window");
  if (window == nullptr) return;
  const std::string windowPath = reader.keyPath("window");
  const char* expected = "expected [start, end] with start <= end";
  if (!window->is_array() || window->size() != 2 || !(*window)[0].is_number() || !(*window)[1].is_number()) {
    JsonObjectReader::failAt(source, windowPath, expected);
  }
  force.start = JsonObjectReader::toNumber((*window)[0], windowPath + "[0]", source);
  force.end = JsonObjectReader::toNumber((*window)[1], windowPath + "[1]", source);
  if (force.start > force.end) {
    JsonObjectReader::failAt(source, windowPath, expected);
  }
}

Scene::Force parseForce(const json& value, const std::string& path, const std::string& source) {
  JsonObjectReader reader(value, path, source);
  Scene::Force force;
  const std::string type = reader.choice("type", "", {"pull", "impulse"});
  force.type = type == "pull" ? Scene::ForceType::pull : Scene::ForceType::impulse;
  parseForceTarget(reader, source, force);
  if (force.type == Scene::ForceType::pull) {
    parsePull(reader, source, force);
  } else {
    force.vector = JsonObjectReader::toVector3(reader.required("impulse"), reader.keyPath("impulse"), source);
    force.time = reader.number("time", 0.0);
    if (force.time < 0.0) {
      reader.fail("time", "expected a time >= 0");
    }
  }
  reader.finish();
  return force;
}

void parseForces(JsonObjectReader& top, Scene& scene) {
  const json* forces = top.find("forces");
  if (forces == nullptr) {
    return;
  }
  if (!forces->is_array()) {
    top.fail("forces", "expected an array of {type, set | vertices, ...}");
  }
  for (std::size_t i = 0; i < forces->size(); ++i) {
    scene.forces.push_back(parseForce((*forces)[i], top.elementPath("forces", i), scene.sourceName));
  }
}

void parseIntegrator(JsonObjectReader& top, Scene& scene, TimingKeys& timing) {
  JsonObjectReader reader(top.required("integrator"), "integrator", scene.sourceName);
  scene.integrator.name = reader.string("name", scene.integrator.name);
  if (scene.integrator.name.empty()) {
    reader.fail("name", "expected a non-empty integrator name");
  }
  const bool hasTimestep = reader.has("timestep");
  if (hasTimestep == reader.has("stepsPerFrame")) {
    // A misspelt key ("timestpe") is the likelier mistake: name it first.
    (void)reader.find("options");
    reader.finish();
    JsonObjectReader::failAt(scene.sourceName, "integrator",
                             "give either \"timestep\" or \"stepsPerFrame\" (steps per frame of 1 / frames.rate)");
  }
  if (hasTimestep) {
    timing.timestep = reader.requiredNumber("timestep");
    requirePositive(reader, "timestep", timing.timestep);
  } else {
    // The timestep follows once frames.rate is known (parseScene).
    timing.stepsPerFrame = reader.integer("stepsPerFrame", 1, 1, detail::maxStepsPerFrame);
  }
  if (const json* options = reader.find("options")) {
    if (!options->is_object()) {
      reader.fail("options", "expected an object, got " + JsonObjectReader::describe(*options));
    }
    scene.integrator.options = *options;
  }
  reader.finish();
}

void parseOutput(JsonObjectReader& top, Scene& scene) {
  const json* output = top.find("output");
  if (output == nullptr) {
    return;
  }
  JsonObjectReader reader(*output, "output", scene.sourceName);
  if (reader.has("file")) {
    scene.output.file = resolvePath(scene.baseDirectory, pathString(reader, "file"));
  }
  if (const json* vtu = reader.find("vtu")) {
    JsonObjectReader vtuReader(*vtu, reader.keyPath("vtu"), scene.sourceName);
    scene.output.vtuFolder = resolvePath(scene.baseDirectory, pathString(vtuReader, "folder"));
    scene.output.vtuEvery = vtuReader.integer("every", 1, 1, maxInt);
    scene.output.vtuEncoding = vtuReader.choice("encoding", "binary", {"binary", "ascii"}) == "ascii"
                                   ? VtuEncoding::ascii
                                   : VtuEncoding::binary;
    vtuReader.finish();
  }
  scene.output.velocities = reader.boolean("velocities", false);
  scene.output.contactForces = reader.boolean("contactForces", false);
  scene.output.sync = reader.boolean("sync", false);
  if (reader.has("regions")) scene.output.regions = reader.boolean("regions", false);
  reader.finish();
}

void parseContactPlanes(JsonObjectReader& reader, const std::string& source, Scene::Contact& out) {
  if (const json* ground = reader.find("ground")) {
    JsonObjectReader groundReader(*ground, reader.keyPath("ground"), source);
    ContactPlane plane;
    plane.normal = groundReader.vector3("up", Eigen::Vector3d::UnitY());
    if (!(plane.normal.norm() > 0.0)) groundReader.fail("up", "expected a non-zero vector");
    plane.normal.normalize();
    plane.offset = groundReader.number("height", 0.0);
    groundReader.finish();
    out.planes.push_back(plane);
    out.ground = plane;
  }
  const json* planes = reader.find("planes");
  if (planes == nullptr) return;
  if (!planes->is_array()) reader.fail("planes", "expected an array of {\"point\": [x, y, z], \"normal\": [x, y, z]}");
  for (std::size_t i = 0; i < planes->size(); ++i) {
    JsonObjectReader planeReader((*planes)[i], reader.elementPath("planes", i), source);
    const Eigen::Vector3d point =
        JsonObjectReader::toVector3(planeReader.required("point"), planeReader.keyPath("point"), source);
    Eigen::Vector3d normal =
        JsonObjectReader::toVector3(planeReader.required("normal"), planeReader.keyPath("normal"), source);
    if (!(normal.norm() > 0.0)) planeReader.fail("normal", "expected a non-zero vector");
    planeReader.finish();
    normal.normalize();
    out.planes.push_back({normal, normal.dot(point)});
  }
}

void parseContactSpheres(JsonObjectReader& reader, const std::string& source, Scene::Contact& out) {
  const json* spheres = reader.find("spheres");
  if (spheres == nullptr) return;
  if (!spheres->is_array()) reader.fail("spheres", "expected an array of {\"center\": [x, y, z], \"radius\": r}");
  for (std::size_t i = 0; i < spheres->size(); ++i) {
    JsonObjectReader sphereReader((*spheres)[i], reader.elementPath("spheres", i), source);
    ContactSphere sphere;
    sphere.center =
        JsonObjectReader::toVector3(sphereReader.required("center"), sphereReader.keyPath("center"), source);
    sphere.radius = sphereReader.requiredNumber("radius");
    requirePositive(sphereReader, "radius", sphere.radius);
    sphereReader.finish();
    out.spheres.push_back(sphere);
  }
}

void parseContact(JsonObjectReader& top, Scene& scene) {
  const json* contact = top.find("contact");
  if (contact == nullptr) return;
  const std::string& source = scene.sourceName;
  JsonObjectReader reader(*contact, "contact", source);
  Scene::Contact& out = scene.contact;
  parseContactPlanes(reader, source, out);
  parseContactSpheres(reader, source, out);
  detail::parseContactSurfaces(reader, scene);
  PenaltyContactParameters& p = out.parameters;
  p.stiffness = reader.number("stiffness", p.stiffness);
  requirePositive(reader, "stiffness", p.stiffness);
  p.damping = reader.number("damping", p.damping);
  if (p.damping < 0.0) reader.fail("damping", "expected damping >= 0");
  p.friction = reader.number("friction", p.friction);
  if (p.friction < 0.0) reader.fail("friction", "expected a Coulomb coefficient >= 0");
  p.frictionViscosity = reader.number("frictionViscosity", p.frictionViscosity);
  requirePositive(reader, "frictionViscosity", p.frictionViscosity);
  out.implicit = reader.boolean("implicit", false);
  if (out.implicit && p.friction > 0.0) {
    reader.fail("implicit", "implicit contact is frictionless: set contact.friction to 0, or leave implicit out");
  }
  reader.finish();
  if (!out.enabled()) reader.fail("ground", "contact needs a ground, planes, spheres, obstacles or surfaces");
}

void parseDamping(JsonObjectReader& top, Scene& scene) {
  const json* damping = top.find("damping");
  if (damping == nullptr) return;
  JsonObjectReader reader(*damping, "damping", scene.sourceName);
  scene.rayleighAlpha = reader.number("alpha", 0.0);
  scene.rayleighBeta = reader.number("beta", 0.0);
  reader.finish();
  if (scene.rayleighAlpha < 0.0) {
    reader.fail("alpha", "expected alpha >= 0");
  }
  if (scene.rayleighBeta < 0.0) {
    reader.fail("beta", "expected beta >= 0");
  }
}

void parseFrames(JsonObjectReader& top, const Scene& scene, TimingKeys& timing) {
  const json* frames = top.find("frames");
  if (frames == nullptr) return;
  JsonObjectReader reader(*frames, "frames", scene.sourceName);
  timing.frameRate = reader.number("rate", timing.frameRate);
  requirePositive(reader, "rate", timing.frameRate);
  timing.frameCount = reader.integer("count", timing.frameCount, 1, maxInt);
  reader.finish();
}

}  // namespace

bool hasRunTimeRegions(const Scene& scene) {
  const json& options = scene.integrator.options;
  if (!options.is_object()) return false;
  const auto regions = options.find("regions");
  return regions != options.end() && regions->is_object() && regions->contains("adaptive");
}

bool recordsRegionRatios(const Scene& scene) { return scene.output.regions.value_or(hasRunTimeRegions(scene)); }

void throwSceneError(const Scene& scene, const std::string& keyPath, const std::string& message) {
  JsonObjectReader::failAt(scene.sourceName, keyPath, message);
}

Scene parseScene(const nlohmann::json& json, const std::filesystem::path& basePath, const std::string& sourceName) {
  Scene scene;
  scene.sourceName = sourceName;
  scene.baseDirectory = basePath;
  JsonObjectReader top(json, "", sourceName);

  scene.description = top.string("description", "");
  parseMesh(top, scene);
  parseMaterials(top, scene);
  parseFixed(top, scene);
  scene.gravity = top.vector3("gravity", Eigen::Vector3d::Zero());
  parseForces(top, scene);
  scene.mass =
      top.choice("mass", "consistent", {"consistent", "lumped"}) == "lumped" ? MassType::lumped : MassType::consistent;
  parseDamping(top, scene);
  detail::parseForceModel(top, scene);
  parseContact(top, scene);
  TimingKeys timing;
  parseIntegrator(top, scene, timing);
  parseFrames(top, scene, timing);
  parseOutput(top, scene);
  top.finish();
  detail::checkTimingKeys(timing, scene.sourceName);
  // A timestep that does not divide the frame interval is reported where the timing is
  // used (requireFrameTiming: buildSimulation, integratorContext), so that tools which only
  // need the scene's mesh (afsimTool, frameRenderer) still read such a scene.
  scene.timing = detail::divideFrameInterval(timing);
  return scene;
}

Scene loadScene(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ignored;
  if (std::filesystem::is_directory(path, ignored)) {
    throw Error(name + ": is a directory, not a scene file (scenes are JSON; see docs/scene-format.md)");
  }
  if (isVegaConfigPath(path)) return readVegaConfig(path).scene;
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* meshExtension : {".veg", ".node", ".ele", ".msh", ".vtu"}) {
    if (extension == meshExtension) {
      throw Error(name +
                  ": is a mesh file, not a scene (scenes are JSON; see docs/scene-format.md); to look at a mesh use "
                  "meshInfo");
    }
  }
  for (const char* surfaceExtension : {".obj", ".stl", ".off", ".ply", ".gltf", ".glb"}) {
    if (extension == surfaceExtension) {
      throw Error(name +
                  ": is a surface mesh, not a scene (scenes are JSON; see docs/scene-format.md); make a tetrahedral "
                  "mesh of it with tetMesher (tetMesher " +
                  name + " --output " + path.stem().string() +
                  ".veg; docs/tet-mesher.md) and name that in a scene's mesh.file");
    }
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw Error(name + ": cannot open the scene file");
  }
  std::ostringstream text;
  text << in.rdbuf();
  const std::string content = text.str();
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(content, nullptr, true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::parse_error& error) {
    const std::size_t end = std::min(error.byte, content.size());
    const auto line = static_cast<std::size_t>(
        1 + std::count(content.begin(), content.begin() + static_cast<std::ptrdiff_t>(end > 0 ? end - 1 : 0), '\n'));
    throw ParseError(name, line, std::string("invalid JSON: ") + error.what());
  }
  return parseScene(json, path.parent_path(), name);
}

}  // namespace asyncfem
