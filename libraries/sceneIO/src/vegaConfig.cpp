// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/vegaConfig.hpp>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string_view>

#include "detail/vegaOptionFile.hpp"

namespace asyncfem {

namespace {

using detail::ConfigOptions;
using detail::Option;
using detail::splitOptions;
using nlohmann::json;

// Keys that only steer Vega's interactive program: the window, camera, lights, what is
// drawn, the mouse's drag force, the pause and frame-rate switches, thread counts (the
// result does not depend on them) and Vega's own text output.
constexpr std::string_view interactiveKeys[] = {"windowWidth",
                                                "windowHeight",
                                                "cameraRadius",
                                                "focusPositionX",
                                                "focusPositionY",
                                                "focusPositionZ",
                                                "cameraLongitude",
                                                "cameraLattitude",
                                                "renderWireframe",
                                                "renderAxes",
                                                "renderSecondaryDeformableObject",
                                                "extraSceneGeometry",
                                                "enableTextures",
                                                "backgroundColor",
                                                "lightingConfigFilename",
                                                "groundPlane",
                                                "useRealTimeNormals",
                                                "singleStepMode",
                                                "pauseSimulation",
                                                "lockAt30Hz",
                                                "syncTimestepWithGraphics",
                                                "deformableObjectCompliance",
                                                "forceNeighborhoodSize",
                                                "numInternalForceThreads",
                                                "numSolverThreads",
                                                "outputFilename"};

// The keys that map to the scene, are checked, or are refused with a reason.
constexpr std::string_view physicalKeys[] = {"volumetricMeshFilename",
                                             "fixedVerticesFilename",
                                             "customMassSpringSystem",
                                             "massSpringSystemObjConfigFilename",
                                             "massSpringSystemTetMeshConfigFilename",
                                             "massSpringSystemCubicMeshConfigFilename",
                                             "solver",
                                             "implicitSolverMethod",
                                             "maxIterations",
                                             "epsilon",
                                             "newmarkBeta",
                                             "newmarkGamma",
                                             "timestep",
                                             "substepsPerTimeStep",
                                             "dampingMassCoef",
                                             "dampingStiffnessCoef",
                                             "dampingLaplacianCoef",
                                             "deformableObjectMethod",
                                             "corotationalLinearFEM_warp",
                                             "invertibleMaterial",
                                             "inversionThreshold",
                                             "enableCompressionResistance",
                                             "compressionResistance",
                                             "addGravity",
                                             "g",
                                             "renderingMeshFilename",
                                             "secondaryRenderingMeshFilename",
                                             "secondaryRenderingMeshInterpolationFilename",
                                             "frequencyScaling",
                                             "plasticThreshold",
                                             "initialPositionFilename",
                                             "initialVelocityFilename",
                                             "forceLoadsFilename",
                                             "centralDifferencesTangentialDampingUpdateMode"};

bool isKnownKey(std::string_view key) {
  return std::find(std::begin(physicalKeys), std::end(physicalKeys), key) != std::end(physicalKeys) ||
         std::find(std::begin(interactiveKeys), std::end(interactiveKeys), key) != std::end(interactiveKeys);
}

// Why each interactive key is ignored, for the key table the reader returns.
std::string interactiveReason(std::string_view key) {
  if (key == "deformableObjectCompliance" || key == "forceNeighborhoodSize") {
    return "ignored: interactive only (scales and spreads the mouse's drag force)";
  }
  if (key == "syncTimestepWithGraphics") {
    return "ignored: interactive only (ties the timestep to the screen's frame rate; the run uses timestep)";
  }
  if (key == "numInternalForceThreads" || key == "numSolverThreads") {
    return "ignored: thread count (the result does not depend on it)";
  }
  if (key == "outputFilename") return "ignored: offlineSimulator writes an .afsim file (--output)";
  return "ignored: interactive only (window, camera, lighting or display)";
}

std::string quoted(const std::string& text) { return "\"" + text + "\""; }

std::string formatFullPrecision(double value) {
  std::ostringstream out;
  out.precision(12);
  out << value;
  return out.str();
}

// A required number: ParseError at line 0 when the key is missing.
double requiredNumber(ConfigOptions& options, std::string_view key) {
  const std::optional<double> value = options.number(key);
  if (!value) {
    throw ParseError(options.source(), 0, "required option *" + std::string(key) + " is missing (Vega requires it)");
  }
  return *value;
}

// Keys that must keep the value at which they change nothing here; fail naming why otherwise.
void requireNoEffect(ConfigOptions& options, std::string_view key, double neutral, const std::string& why) {
  const std::optional<double> value = options.number(key);
  if (!value) return;
  if (*value != neutral) options.fail(*options.find(key), why);
  options.note(key, "accepted: " + formatFullPrecision(neutral) + " changes nothing");
}

void refuseFile(ConfigOptions& options, std::string_view key, const std::string& why) {
  if (options.text(key)) options.fail(*options.find(key), why);
  options.note(key, "accepted: __none");
}

void mapMesh(ConfigOptions& options, json& scene) {
  const auto mesh = options.file("volumetricMeshFilename");
  for (const char* key : {"customMassSpringSystem", "massSpringSystemObjConfigFilename",
                          "massSpringSystemTetMeshConfigFilename", "massSpringSystemCubicMeshConfigFilename"}) {
    refuseFile(options, key, "mass-spring systems are not supported (the toolkit simulates finite element meshes)");
  }
  if (!mesh) {
    if (const Option* option = options.find("volumetricMeshFilename")) options.fail(*option, "expected a mesh file");
    throw ParseError(options.source(), 0, "required option *volumetricMeshFilename is missing");
  }
  scene["mesh"] = {{"file", mesh->first}};
  options.note("volumetricMeshFilename", "mesh.file = " + quoted(mesh->first));
  if (const auto fixed = options.file("fixedVerticesFilename")) {
    scene["fixed"] = {{"bou", fixed->first}};
    options.note("fixedVerticesFilename", "fixed.bou = " + quoted(fixed->first) + " (1-based ids, as Vega)");
  } else {
    options.note("fixedVerticesFilename", "accepted: __none (nothing fixed)");
  }
}

// solver (and the obsolete implicitSolverMethod) to the integrator's name and options.
void mapSolver(ConfigOptions& options, json& scene) {
  std::string solver = "implicitNewmark";
  const Option* solverOption = options.find("solver");
  if (const auto obsolete = options.text("implicitSolverMethod"); obsolete && *obsolete != "none") {
    if (solverOption == nullptr) {
      solver = *obsolete;
      solverOption = options.find("implicitSolverMethod");
    }
  }
  if (const auto given = options.text("solver")) solver = *given;
  static const std::map<std::string, std::string> names = {{"implicitNewmark", "trapezoidal"},
                                                           {"implicitBackwardEuler", "backward-euler"},
                                                           {"centralDifferences", "central-differences"},
                                                           {"symplecticEuler", "symplectic-euler"}};
  if (solver == "Euler") {
    options.fail(*solverOption,
                 "explicit (forward) Euler is not available (it gains energy at every step); use "
                 "symplecticEuler, centralDifferences or an implicit solver");
  }
  const auto name = names.find(solver);
  if (name == names.end()) {
    options.fail(*solverOption, "unknown solver \"" + solver +
                                    "\" (known: implicitNewmark, implicitBackwardEuler, centralDifferences, "
                                    "symplecticEuler, Euler)");
  }
  json& integrator = scene["integrator"];
  integrator["name"] = name->second;
  const std::string mapped = "integrator.name = " + quoted(name->second);
  options.note("solver", mapped);
  options.note("implicitSolverMethod", solverOption == options.find("implicitSolverMethod")
                                           ? mapped + " (obsolete spelling of *solver)"
                                           : "ignored: obsolete spelling of *solver (none, or *solver given)");

  const bool implicit = solver == "implicitNewmark" || solver == "implicitBackwardEuler";
  const long maxIterations = options.integer("maxIterations").value_or(1);
  if (const Option* option = options.find("maxIterations"); option && (maxIterations < 1 || maxIterations > 1000)) {
    options.fail(*option, "expected an integer in [1, 1000]");
  }
  json integratorOptions = json::object();
  if (implicit) {
    integratorOptions["maxIterations"] = maxIterations;
    options.note("maxIterations", "integrator.options.maxIterations = " + std::to_string(maxIterations));
  } else {
    options.note("maxIterations", "ignored: explicit solvers take no Newton iterations (as in Vega)");
  }
  if (const auto epsilon = options.number("epsilon")) {
    if (!(*epsilon > 0.0)) options.fail(*options.find("epsilon"), "expected a number > 0");
    if (implicit && maxIterations > 1) {
      integratorOptions["tolerance"] = *epsilon;
      options.note("epsilon", "integrator.options.tolerance = " + formatFullPrecision(*epsilon));
    } else {
      options.note("epsilon", "ignored: no Newton iteration to stop (maxIterations 1 or an explicit solver)");
    }
  }
  if (solver == "implicitBackwardEuler" && maxIterations > 1) {
    // Vega's backward Euler evaluates the stiffness-proportional damping at every iterate.
    integratorOptions["rayleighStiffnessAtIterate"] = true;
  }
  if (!integratorOptions.empty()) integrator["options"] = integratorOptions;

  if (solver == "implicitNewmark") {
    requireNoEffect(options, "newmarkBeta", 0.25,
                    "the toolkit's Newmark method is the trapezoidal rule (beta 0.25, gamma 0.5) only");
    requireNoEffect(options, "newmarkGamma", 0.5,
                    "the toolkit's Newmark method is the trapezoidal rule (beta 0.25, gamma 0.5) only");
  } else {
    (void)options.number("newmarkBeta");
    (void)options.number("newmarkGamma");
    options.note("newmarkBeta", "ignored: only implicitNewmark reads it (as in Vega)");
    options.note("newmarkGamma", "ignored: only implicitNewmark reads it (as in Vega)");
  }
}

// timestep and substepsPerTimeStep: one Vega graphics frame of `timestep` seconds holds
// `substepsPerTimeStep` integrator steps of timestep / substepsPerTimeStep.
void mapTiming(ConfigOptions& options, json& scene) {
  const double timestep = requiredNumber(options, "timestep");
  if (!(timestep > 0.0)) options.fail(*options.find("timestep"), "expected a number > 0");
  const long substeps = options.integer("substepsPerTimeStep").value_or(1);
  if (substeps < 1 || substeps > 1000000) {
    options.fail(*options.find("substepsPerTimeStep"), "expected an integer in [1, 1000000]");
  }
  scene["frames"] = {{"rate", 1.0 / timestep}};
  scene["integrator"]["stepsPerFrame"] = substeps;
  options.note("timestep", "frames.rate = 1 / " + formatFullPrecision(timestep) + " (one Vega frame per scene frame)");
  options.note("substepsPerTimeStep", "integrator.stepsPerFrame = " + std::to_string(substeps) +
                                          " (integrator timestep = timestep / substepsPerTimeStep)");
}

void mapDamping(ConfigOptions& options, json& scene) {
  const double alpha = requiredNumber(options, "dampingMassCoef");
  const double beta = requiredNumber(options, "dampingStiffnessCoef");
  if (alpha < 0.0) options.fail(*options.find("dampingMassCoef"), "expected a number >= 0");
  if (beta < 0.0) options.fail(*options.find("dampingStiffnessCoef"), "expected a number >= 0");
  scene["damping"] = {{"alpha", alpha}, {"beta", beta}};
  options.note("dampingMassCoef", "damping.alpha = " + formatFullPrecision(alpha));
  options.note("dampingStiffnessCoef", "damping.beta = " + formatFullPrecision(beta));
  requireNoEffect(options, "dampingLaplacianCoef", 0.0, "Laplacian damping is not supported; set it to 0");
}

// InvertibleFEM: the material, the inversion threshold and the compression resistance.
void mapInvertible(ConfigOptions& options, json& model) {
  const std::string material = options.text("invertibleMaterial").value_or("StVK");
  if (material == "StVK") {
    model = {{"type", "stvk"}, {"stvkFormulation", "principal-stretches"}};
  } else if (material == "neoHookean") {
    model = {{"type", "neo-hookean"}};
  } else if (material == "MooneyRivlin") {
    model = {{"type", "mooney-rivlin"}};
  } else {
    options.fail(*options.find("invertibleMaterial"),
                 "unknown invertible material \"" + material + "\" (known: StVK, neoHookean, MooneyRivlin)");
  }
  options.note("invertibleMaterial", "forceModel.type = " + quoted(model["type"].get<std::string>()));
  if (const auto threshold = options.number("inversionThreshold")) {
    if (*threshold > 0.0 && *threshold < 1.0) {
      model["inversionThreshold"] = *threshold;
      model["inversionHandling"] = "vega-clamp";
      options.note("inversionThreshold", "forceModel.inversionThreshold = " + formatFullPrecision(*threshold) +
                                             ", inversionHandling vega-clamp");
    } else if (*threshold <= -1e300) {
      options.note("inversionThreshold", "accepted: Vega's default (no inversion handling)");
    } else {
      options.fail(*options.find("inversionThreshold"), "expected a principal stretch in (0, 1)");
    }
  }
  const bool resist = options.boolean("enableCompressionResistance").value_or(false);
  const double resistance = options.number("compressionResistance").value_or(500.0);
  if (resist) {
    if (resistance < 0.0) options.fail(*options.find("compressionResistance"), "expected a number >= 0");
    model["compressionResistance"] = resistance;
    options.note("enableCompressionResistance", "forceModel.compressionResistance (with *compressionResistance)");
    options.note("compressionResistance", "forceModel.compressionResistance = " + formatFullPrecision(resistance));
  } else {
    options.note("enableCompressionResistance", "accepted: off");
    options.note("compressionResistance", "ignored: *enableCompressionResistance is off");
  }
}

void mapForceModel(ConfigOptions& options, json& scene) {
  const std::string method = options.text("deformableObjectMethod").value_or("StVK");
  json model;
  if (method == "StVK") {
    model = {{"type", "stvk"}};
  } else if (method == "LinearFEM") {
    model = {{"type", "linear"}};
  } else if (method == "CLFEM") {
    const long warp = options.integer("corotationalLinearFEM_warp").value_or(1);
    if (warp == 0) {
      model = {{"type", "linear"}};
    } else if (warp == 1 || warp == 2) {
      model = {{"type", "corotational"}, {"tangent", warp == 1 ? "simple" : "exact"}};
    } else {
      options.fail(*options.find("corotationalLinearFEM_warp"), "expected 0, 1 or 2");
    }
    options.note("corotationalLinearFEM_warp",
                 warp == 0 ? "forceModel.type = \"linear\" (no warping)"
                           : std::string("forceModel.tangent = ") + (warp == 1 ? "\"simple\"" : "\"exact\""));
  } else if (method == "InvertibleFEM") {
    mapInvertible(options, model);
  } else if (method == "MassSpring") {
    options.fail(*options.find("deformableObjectMethod"),
                 "mass-spring systems are not supported (the toolkit simulates finite element meshes)");
  } else {
    const Option* option = options.find("deformableObjectMethod");
    options.fail(*option, "unknown deformable model \"" + method +
                              "\" (known: StVK, CLFEM, LinearFEM, InvertibleFEM; MassSpring is not supported)");
  }
  scene["forceModel"] = model;
  options.note("deformableObjectMethod", "forceModel.type = " + quoted(model["type"].get<std::string>()));
  if (method != "CLFEM") {
    (void)options.integer("corotationalLinearFEM_warp");
    options.note("corotationalLinearFEM_warp", "ignored: only CLFEM reads it (as in Vega)");
  }
  if (method != "InvertibleFEM") {
    (void)options.number("inversionThreshold");
    (void)options.boolean("enableCompressionResistance");
    (void)options.number("compressionResistance");
    for (const char* key :
         {"invertibleMaterial", "inversionThreshold", "enableCompressionResistance", "compressionResistance"}) {
      options.note(key, "ignored: only InvertibleFEM reads it (as in Vega)");
    }
  }
}

void mapGravity(ConfigOptions& options, json& scene) {
  const bool add = options.boolean("addGravity").value_or(false);
  const double g = options.number("g").value_or(9.81);
  if (add) {
    scene["gravity"] = {0.0, -g, 0.0};
    options.note("addGravity", "gravity = [0, -g, 0] (Vega pulls along -y)");
    options.note("g", "gravity = [0, " + formatFullPrecision(-g) + ", 0]");
  } else {
    options.note("addGravity", "accepted: no gravity");
    options.note("g", "ignored: *addGravity is off");
  }
}

void mapRendering(ConfigOptions& options, VegaConfig& config) {
  if (const auto mesh = options.file("renderingMeshFilename")) {
    config.renderingMesh = mesh->second;
    options.note("renderingMeshFilename",
                 "render mesh on the volumetric mesh's vertices (frameRenderer draws the tet mesh's boundary)");
  } else {
    options.note("renderingMeshFilename", "accepted: __none");
  }
  const auto secondary = options.file("secondaryRenderingMeshFilename");
  const auto interpolation = options.file("secondaryRenderingMeshInterpolationFilename");
  if (secondary.has_value() != interpolation.has_value()) {
    const char* given = secondary ? "secondaryRenderingMeshFilename" : "secondaryRenderingMeshInterpolationFilename";
    const char* missing = secondary ? "secondaryRenderingMeshInterpolationFilename" : "secondaryRenderingMeshFilename";
    options.fail(*options.find(given), std::string("needs *") + missing + " too");
  }
  if (secondary) {
    config.secondaryRenderingMesh = secondary->second;
    config.secondaryInterpolation = interpolation->second;
    options.note("secondaryRenderingMeshFilename", "render mesh drawn by frameRenderer");
    options.note("secondaryRenderingMeshInterpolationFilename", "its .interp weights (frameRenderer)");
  } else {
    options.note("secondaryRenderingMeshFilename", "accepted: __none");
    options.note("secondaryRenderingMeshInterpolationFilename", "accepted: __none");
  }
}

// Keys whose every value but the neutral one changes physics the toolkit does not model.
void checkUnsupported(ConfigOptions& options, const json& scene) {
  requireNoEffect(options, "frequencyScaling", 1.0,
                  "scales the internal forces by frequencyScaling^2; scale Young's modulus in the mesh file instead");
  if (const auto threshold = options.number("plasticThreshold")) {
    if (*threshold < 1e20) options.fail(*options.find("plasticThreshold"), "plastic deformation is not supported");
    options.note("plasticThreshold", "accepted: no plasticity");
  }
  for (const char* key : {"initialPositionFilename", "initialVelocityFilename"}) {
    refuseFile(options, key, "an initial state is not supported (runs start at rest)");
  }
  refuseFile(options, "forceLoadsFilename",
             "force load files are not supported; give loads as forces in a scene JSON (docs/scene-format.md)");
  if (options.integer("centralDifferencesTangentialDampingUpdateMode")) {
    const double beta = scene["damping"]["beta"].get<double>();
    if (scene["integrator"]["name"] == "central-differences" && beta > 0.0) {
      options.fail(*options.find("centralDifferencesTangentialDampingUpdateMode"),
                   "is not supported; with stiffness damping central differences damp with the rest stiffness");
    }
    options.note("centralDifferencesTangentialDampingUpdateMode",
                 "ignored: no stiffness damping under central differences");
  }
}

}  // namespace

bool isVegaConfigPath(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".config";
}

VegaConfig parseVegaConfig(const std::string& text, const std::filesystem::path& baseDirectory,
                           const std::string& sourceName) {
  ConfigOptions options(splitOptions(text, sourceName), sourceName, baseDirectory);
  // Unknown keys first: a misspelt required key is reported as what it is.
  for (const Option& option : options.all()) {
    if (!isKnownKey(option.key)) {
      const std::string hint = option.key == "renderingMeshInterpolationFilename"
                                   ? " (did you mean *secondaryRenderingMeshInterpolationFilename?)"
                                   : " (docs/file-formats.md lists the keys of Vega's simulator)";
      options.fail(option, "unknown option" + hint);
    }
  }
  for (const std::string_view key : interactiveKeys) options.note(key, interactiveReason(key));
  VegaConfig config;
  json scene = json::object();
  scene["description"] = "Vega FEM simulator config " + sourceName;
  mapMesh(options, scene);
  mapSolver(options, scene);
  mapTiming(options, scene);
  mapDamping(options, scene);
  mapForceModel(options, scene);
  mapGravity(options, scene);
  mapRendering(options, config);
  checkUnsupported(options, scene);
  for (const Option& option : options.all()) {
    if (!option.done) options.fail(option, "has no mapping (a gap in this reader)");
    config.keys.push_back({option.key, option.value, option.line, options.outcome(option.key)});
  }
  config.sceneJson = scene;
  config.scene = parseScene(scene, baseDirectory, sourceName);
  return config;
}

VegaConfig readVegaConfig(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open the Vega config file");
  std::ostringstream text;
  text << in.rdbuf();
  return parseVegaConfig(text.str(), path.parent_path(), path.string());
}

nlohmann::json sceneFileJson(const std::filesystem::path& path) {
  if (isVegaConfigPath(path)) return readVegaConfig(path).sceneJson;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open the scene file");
  std::ostringstream text;
  text << in.rdbuf();
  try {
    return nlohmann::json::parse(text.str(), nullptr, true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::parse_error& error) {
    throw ParseError(path.string(), 0, std::string("invalid JSON: ") + error.what());
  }
}

}  // namespace asyncfem
