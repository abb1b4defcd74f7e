// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/multirateIntegrator.hpp>
#include <asyncfem/sceneIO/sceneObjects.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <asyncfem/volumetricMesh/vertexSelection.hpp>
#include <cmath>
#include <limits>
#include <sstream>

namespace asyncfem {

IntegratorRegistry defaultIntegratorRegistry() {
  IntegratorRegistry registry;
  registerSingleRateIntegrators(registry);
  registerMultirateIntegrators(registry);
  return registry;
}

std::vector<std::string> switchIntegrator(Scene& scene, const IntegratorRegistry& registry, const std::string& name) {
  if (name == scene.integrator.name) return {};
  scene.integrator.name = name;
  return registry.dropForeignOptions(name, scene.integrator.options);
}

namespace {

TetMesh loadMesh(const Scene& scene, std::vector<std::string>* warnings) {
  if (!scene.objects.empty()) return buildObjectsMesh(scene, warnings);
  switch (scene.mesh.source) {
    case Scene::MeshSource::beam:
      return makeBeamMesh(scene.mesh.beam);
    case Scene::MeshSource::box:
      return makeBoxMesh(scene.mesh.box);
    case Scene::MeshSource::file:
      break;
  }
  std::vector<std::string> readerWarnings;
  try {
    TetMesh mesh = readMeshCollectingWarnings(scene.mesh.file, readerWarnings);
    if (warnings != nullptr) {
      for (const std::string& warning : readerWarnings)
        warnings->push_back(scene.sourceName + ": mesh.file: " + warning);
    }
    return mesh;
  } catch (const Error& error) {
    throw ValidationError(scene.sourceName + ": mesh.file: " + error.what());
  }
}

std::string joined(const std::vector<std::string>& names) {
  std::string list;
  for (const std::string& name : names) list += (list.empty() ? "" : ", ") + name;
  return list;
}

std::string knownSets(const std::map<std::string, std::vector<int>>& sets) {
  std::vector<std::string> names;
  for (const auto& [name, members] : sets) {
    names.push_back(name);
  }
  return names.empty() ? "none" : joined(names);
}

// The elements of override.set ("allElements" or an element set of the mesh).
std::vector<int> overrideElements(const Scene& scene, const TetMesh& mesh, const Scene::MaterialOverride& override,
                                  const std::string& keyPath) {
  if (override.set != "allElements") {
    const auto it = mesh.elementSets().find(override.set);
    if (it == mesh.elementSets().end()) {
      throwSceneError(
          scene, keyPath,
          "unknown element set \"" + override.set + "\" (known: allElements, " + knownSets(mesh.elementSets()) + ")");
    }
    return it->second;
  }
  std::vector<int> elements(static_cast<std::size_t>(mesh.numElements()));
  for (int e = 0; e < mesh.numElements(); ++e) elements[static_cast<std::size_t>(e)] = e;
  return elements;
}

// Gives members (the elements of override.set that use materialIndex) the overridden
// material: in place when no other element uses it, else as "<material>@<set>".
void overrideMaterial(const Scene::MaterialOverride& override, int materialIndex, const std::vector<int>& members,
                      std::vector<Material>& materials, std::vector<int>& elementMaterials) {
  Material material = materials[static_cast<std::size_t>(materialIndex)];
  material.density = override.density.value_or(material.density);
  material.youngsModulus = override.youngsModulus.value_or(material.youngsModulus);
  material.poissonRatio = override.poissonRatio.value_or(material.poissonRatio);
  const auto users =
      static_cast<std::size_t>(std::count(elementMaterials.begin(), elementMaterials.end(), materialIndex));
  if (users == members.size()) {
    materials[static_cast<std::size_t>(materialIndex)] = material;
    return;
  }
  material.name += "@" + override.set;
  const auto existing =
      std::find_if(materials.begin(), materials.end(), [&](const Material& m) { return m.name == material.name; });
  int newIndex = static_cast<int>(materials.size());
  if (existing != materials.end()) {
    newIndex = static_cast<int>(existing - materials.begin());
    *existing = material;
  } else {
    materials.push_back(material);
  }
  for (const int e : members) elementMaterials[static_cast<std::size_t>(e)] = newIndex;
}

// Material overrides: new materials for the elements of each set. A material used only
// by the set's elements is changed in place (keeping its name); otherwise the set's
// elements get a copy named "<material>@<set>".
TetMesh applyMaterialOverrides(const Scene& scene, TetMesh mesh) {
  if (scene.materials.empty()) {
    return mesh;
  }
  std::vector<Material> materials = mesh.materials();
  std::vector<int> elementMaterials = mesh.elementMaterials();
  for (std::size_t i = 0; i < scene.materials.size(); ++i) {
    const Scene::MaterialOverride& override = scene.materials[i];
    const std::string keyPath = "materials[" + std::to_string(i) + "].set";
    std::map<int, std::vector<int>> byMaterial;
    for (const int e : overrideElements(scene, mesh, override, keyPath)) {
      byMaterial[elementMaterials[static_cast<std::size_t>(e)]].push_back(e);
    }
    for (const auto& [materialIndex, members] : byMaterial) {
      overrideMaterial(override, materialIndex, members, materials, elementMaterials);
    }
  }
  TetMesh result(mesh.restPositions(), mesh.elements(), materials, elementMaterials);
  for (const auto& [name, members] : mesh.elementSets()) {
    result.setElementSet(name, members);
  }
  for (const auto& [name, members] : mesh.vertexSets()) {
    result.setVertexSet(name, members);
  }
  return result;
}

// The vertices selection picks, with errors at keyPrefix's keys ("fixed.boxes[1]: ...").
std::vector<int> selectAt(const Scene& scene, const TetMesh& mesh, const VertexSelection& selection,
                          const std::string& keyPrefix) {
  try {
    return selectVertices(mesh, selection);
  } catch (const SelectionError& error) {
    throwSceneError(scene, keyPrefix + (keyPrefix.empty() ? "" : ".") + error.keySuffix(), error.what());
  }
}

std::vector<int> collectFixedVertices(const Scene& scene, const TetMesh& mesh) {
  VertexSelection selection;
  selection.sets = scene.fixed.sets;
  selection.boxes = scene.fixed.boxes;
  selection.bouFile = scene.fixed.bouFile;
  std::vector<int> fixed = selectAt(scene, mesh, selection, "fixed");
  if (!fixed.empty() && static_cast<int>(fixed.size()) == mesh.numVertices()) {
    throwSceneError(scene, "fixed", "every vertex is fixed: nothing would move");
  }
  std::vector<int> held = unusedVertices(mesh);
  held.insert(held.end(), fixed.begin(), fixed.end());
  std::sort(held.begin(), held.end());
  if (std::unique(held.begin(), held.end()) - held.begin() == mesh.numVertices()) {
    throwSceneError(scene, "fixed", "every vertex is fixed or in no element: nothing would move");
  }
  return fixed;
}

// Relative to h: how close to a window bound a step time counts as on it. Round-off in
// k h and in the substep times t0 + r hS is ~1e-16 relative; 1e-9 is far above it and far
// below any deliberate offset from a step time.
constexpr double windowTolerance = 1e-9;

// The vertices a force acts on, with errors at "forces[i].set" or "forces[i]".
std::vector<int> forceVertices(const Scene& scene, const TetMesh& mesh, const Scene::Force& force,
                               const std::string& keyPath) {
  VertexSelection selection;
  if (force.set.empty()) {
    selection.vertices = force.vertices;
    return selectAt(scene, mesh, selection, keyPath);
  }
  selection.sets.push_back(force.set);
  try {
    return selectVertices(mesh, selection);
  } catch (const SelectionError& error) {
    throwSceneError(scene, keyPath + ".set", error.what());
  }
}

// h: the timestep the loads are stepped with (impulses last one step).
std::vector<VertexLoad> collectLoads(const Scene& scene, const TetMesh& mesh, double h) {
  std::vector<VertexLoad> loads;
  for (std::size_t i = 0; i < scene.forces.size(); ++i) {
    const Scene::Force& force = scene.forces[i];
    const std::string keyPath = "forces[" + std::to_string(i) + "]";
    VertexLoad load;
    load.vertices = forceVertices(scene, mesh, force, keyPath);
    const double count = static_cast<double>(load.vertices.size());
    if (force.type == Scene::ForceType::pull) {
      load.perVertex = force.vector / count;
      // Acts at step times start <= t < end, where a step time within 1e-9 h of a bound
      // counts as the bound (docs/scene-format.md): step times are k h up to round-off, so
      // a window ending on a step time excludes that step whatever the round-off.
      load.start = force.start - (windowTolerance * h);
      load.end = force.end - (windowTolerance * h);
    } else {
      // An impulse I is a force I / h over a window one step long. Integrators evaluate
      // f_ext at step starts, step ends or both (averaged); the window
      // (t + h/2, t + 3h/2] holds exactly one step time, far from its ends, so each of
      // them delivers exactly I, in the step after t.
      load.perVertex = force.vector / (h * count);
      load.leftOpen = true;
      load.start = force.time + (0.5 * h);
      load.end = force.time + (1.5 * h);
    }
    if (load.perVertex.isZero(0.0)) continue;
    loads.push_back(std::move(load));
  }
  return loads;
}

std::string formatNumber(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

// Penalty contact is explicit: its force is evaluated at one state per (large) step. A
// boundary vertex of lumped mass m on a penalty spring k oscillates at omega = sqrt(k / m),
// and an explicit spring alone is unstable beyond omega h = 2. The lightest vertices are
// held by their stiff (implicit) neighbours, so the median boundary vertex is the measure:
// measured with benchmarkAsync --study contact, omega h of 3.2 and 4.6 for it gained energy
// at impacts, 1.1 did not (docs/benchmarks.md). Warn from omega h > 2.
// The median lumped mass of the boundary vertices (0 when none has mass).
double medianBoundaryMass(const TetMesh& mesh, const Eigen::SparseMatrix<double>& mass) {
  const Eigen::VectorXd lumped = mass * Eigen::VectorXd::Ones(mass.cols());
  std::vector<char> onBoundary(static_cast<std::size_t>(mesh.numVertices()), 0);
  for (const std::array<int, 3>& triangle : boundaryTriangles(mesh)) {
    for (const int v : triangle) onBoundary[static_cast<std::size_t>(v)] = 1;
  }
  std::vector<double> masses;
  for (int v = 0; v < mesh.numVertices(); ++v) {
    if (onBoundary[static_cast<std::size_t>(v)] && lumped[3 * static_cast<Eigen::Index>(v)] > 0.0) {
      masses.push_back(lumped[3 * static_cast<Eigen::Index>(v)]);
    }
  }
  if (masses.empty()) return 0.0;
  std::nth_element(masses.begin(), masses.begin() + static_cast<std::ptrdiff_t>(masses.size() / 2), masses.end());
  return masses[masses.size() / 2];
}

// Explicit contact damping c on a vertex of mass m alone changes its normal velocity by the
// factor 1 - c h / m per step, and friction in its viscous regime (eta |v_t| below mu f_n)
// the tangential velocity by 1 - eta h / m: beyond 2 that factor is below -1 and the
// velocity flips every step, growing until the clamp (f_n >= 0, |f_t| <= mu f_n) holds it:
// the vertices chatter. On models/drop/drop.json (frictionViscosity 1e3, eta h / m = 347)
// the block looks at rest in its frames but its contact vertices keep 0.4 m/s, and the
// contact forces sampled at frames sum to 170 N sideways. As for the stiffness (above), the
// lightest vertices are held by their neighbours through the implicit elastic forces, so
// the median boundary vertex is the measure.
std::string contactDampingWarning(const Scene& scene, double median, double h) {
  const PenaltyContactParameters& p = scene.contact.parameters;
  const bool viscousFriction = p.friction > 0.0 && p.frictionViscosity > p.damping;
  const double c = viscousFriction ? p.frictionViscosity : p.damping;
  const std::string key = viscousFriction ? "contact.frictionViscosity" : "contact.damping";
  const double ratio = c * h / median;
  if (!(ratio > 2.0)) return "";
  return scene.sourceName + ": " + key + ": " + formatNumber(c) + " on a boundary vertex of median lumped mass " +
         formatNumber(median) + " gives " + (viscousFriction ? "eta" : "c") + " h / m = " + formatNumber(ratio) +
         " at integrator.timestep " + formatNumber(h) + "; explicit " +
         (viscousFriction ? "friction in its viscous regime" : "contact damping") +
         " beyond 2 makes the vertices chatter (their velocity flips every step while the frames look at rest): "
         "lower " +
         key + " below " + formatNumber(2.0 * median / h) + " or the timestep" +
         (viscousFriction ? "" : ", or set contact.implicit");
}

std::vector<std::string> contactStepWarnings(const Scene& scene, const TetMesh& mesh,
                                             const Eigen::SparseMatrix<double>& mass, double h) {
  const double k = scene.contact.parameters.stiffness;
  std::vector<std::string> warnings;
  if (scene.contact.implicit) return warnings;  // linearized in the step: stable at any omega h
  const double median = medianBoundaryMass(mesh, mass);
  if (median == 0.0) return warnings;
  if (std::string damping = contactDampingWarning(scene, median, h); !damping.empty()) {
    warnings.push_back(std::move(damping));
  }
  const double omegaH = std::sqrt(k / median) * h;
  if (omegaH > 2.0) {
    warnings.push_back(
        scene.sourceName + ": contact.stiffness: " + formatNumber(k) + " on a boundary vertex of median lumped mass " +
        formatNumber(median) + " gives omega h = " + formatNumber(omegaH) + " at integrator.timestep " +
        formatNumber(h) +
        "; penalty contact is explicit, and beyond omega h = 2 its spring is unstable on its own and can add "
        "energy at impacts: lower contact.stiffness below " +
        formatNumber(4.0 * median / (h * h)) + " or the timestep" +
        (scene.integrator.name == "async"
             ? ", or set contact.implicit (substepStatePrediction only helps the fast regions)"
             : ", or set contact.implicit with \"backward-euler\""));
  }
  return warnings;
}

}  // namespace

TetMesh buildSceneMesh(const Scene& scene, std::vector<std::string>* warnings) {
  return applyMaterialOverrides(scene, loadMesh(scene, warnings));
}

ProblemSettings problemSettings(const Scene& scene) {
  ProblemSettings settings;
  settings.mass = scene.mass;
  settings.forceModel = scene.forceModel;
  settings.hyperelastic = scene.hyperelastic;
  settings.tangent = scene.tangent;
  settings.rayleighAlpha = scene.rayleighAlpha;
  settings.rayleighBeta = scene.rayleighBeta;
  settings.gravity = scene.gravity;
  settings.implicitContact = scene.contact.implicit;
  return settings;
}

std::shared_ptr<const Problem> buildProblem(const Scene& scene, std::vector<std::string>* warnings) {
  auto mesh = std::make_shared<const TetMesh>(buildSceneMesh(scene, warnings));
  std::vector<int> fixed = collectFixedVertices(scene, *mesh);
  std::vector<VertexLoad> loads = collectLoads(scene, *mesh, requireFrameTiming(scene).timestep);
  const ProblemSettings settings = problemSettings(scene);
  std::shared_ptr<const PenaltyContact> contact = buildSceneContact(scene, *mesh);
  return std::make_shared<const Problem>(mesh, std::move(fixed), settings, std::move(loads), std::move(contact));
}

std::shared_ptr<const Problem> recordedSceneProblem(const SimulationFileHeader& header, const std::string& fileName,
                                                    std::vector<std::string>* warnings) {
  if (header.scenePath.empty()) {
    throw Error(fileName +
                " does not record its scene (written before format version 2, or by a program that gave none): "
                "give --scene SCENE.json or --mesh FILE");
  }
  std::shared_ptr<const Problem> problem;
  try {
    problem = buildProblem(loadScene(header.scenePath), warnings);
  } catch (const Error& error) {
    throw Error(fileName + " was written from the scene " + header.scenePath +
                ", which cannot be used now: " + error.what() + " (give --scene or --mesh)");
  }
  if (problemFingerprint(*problem) != header.sceneFingerprint) {
    throw Error(fileName + " was written from the scene " + header.scenePath +
                ", which now builds another mesh or other fixed vertices than the run had: give --scene or --mesh");
  }
  return problem;
}

IntegratorContext integratorContext(const Scene& scene) { return integratorContext(scene, requireFrameTiming(scene)); }

IntegratorContext integratorContext(const Scene& scene, const FrameTiming& timing) {
  IntegratorContext context;
  context.timestep = timing.timestep;
  context.frameRate = timing.frameRate;
  context.massType = scene.mass;
  context.hasContact = scene.contact.enabled();
  context.sourceName = scene.sourceName;
  context.optionsPath = "integrator.options";
  return context;
}

namespace {}  // namespace

void requireMultirateForRegionOutput(const Scene& scene, const Integrator& integrator) {
  if (recordsRegionRatios(scene) && integrator.multirate() == nullptr) {
    throwSceneError(scene, "output.regions",
                    "records the fast regions of a multirate integrator, but \"" + scene.integrator.name +
                        "\" is single-rate (use \"async\" with regions, or leave output.regions out)");
  }
}

namespace {

void requireKnownIntegrator(const Scene& scene, const IntegratorRegistry& registry) {
  if (registry.find(scene.integrator.name) != nullptr) return;
  std::string known;
  for (const std::string& name : registry.names()) known += (known.empty() ? "" : ", ") + name;
  throwSceneError(scene, "integrator.name",
                  "unknown integrator \"" + scene.integrator.name + "\" (known: " + known + ")");
}

// What the builder leaves out and what the user should know before the run.
void noteSkippedAndWarnings(const Scene& scene, Simulation& simulation) {
  const Problem& problem = *simulation.problem;
  simulation.skipped = problem.skipped();
  if (simulation.contact) {
    for (std::string& warning :
         contactStepWarnings(scene, problem.mesh(), problem.massMatrix(), simulation.timing.timestep)) {
      simulation.warnings.push_back(std::move(warning));
    }
  }
  if (scene.output.vtuFolder.empty()) simulation.skipped.emplace_back("vtu output (output.vtu not set)");
  if (!scene.output.velocities) simulation.skipped.emplace_back("velocity output (output.velocities = false)");
}

// A timestep above an explicit integrator's stable limit: the integrator names the limit,
// which may not divide the frame interval, so the scene's advice is the steps per frame
// that do give a stable step. The limit comes from the same integrator built with the
// option force (its stableTimestepEstimate()); "" when that cannot be had.
std::string stableStepsPerFrameAdvice(const Scene& scene, const IntegratorRegistry& registry,
                                      const IntegratorContext& context, const FrameTiming& timing) {
  nlohmann::json options = scene.integrator.options;
  options["force"] = true;
  double limit = 0.0;
  try {
    limit = registry.create(scene.integrator.name, context, options)->stableTimestepEstimate();
  } catch (const Error&) {
    return "";
  }
  if (!(limit > 0.0) || !std::isfinite(limit) || !(timing.frameInterval > 0.0)) return "";
  auto steps = static_cast<long long>(std::ceil(timing.frameInterval / limit));
  while (timing.frameInterval / static_cast<double>(steps) > limit) ++steps;
  return "; at frames.rate " + formatNumber(timing.frameRate) + " the stable steps per frame are " +
         std::to_string(steps) + " or more (integrator.stepsPerFrame: " + std::to_string(steps) +
         " gives a timestep of " + formatNumber(timing.frameInterval / static_cast<double>(steps)) + ")";
}

}  // namespace

Simulation buildSimulation(const Scene& scene, const IntegratorRegistry& registry) {
  Simulation simulation;
  // Cheap checks first, so a bad scene fails before the mesh is read and matrices built.
  simulation.timing = requireFrameTiming(scene);
  requireKnownIntegrator(scene, registry);

  simulation.problem = buildProblem(scene, &simulation.warnings);
  const Problem& problem = *simulation.problem;
  simulation.mesh = problem.sharedMesh();
  simulation.fixedVertices = problem.fixedVertices();
  simulation.contact = problem.contact();
  noteSkippedAndWarnings(scene, simulation);

  IntegratorContext context = integratorContext(scene, simulation.timing);
  context.mesh = problem.sharedMesh();
  context.system = problem.dynamicSystem();
  try {
    simulation.integrator = registry.create(scene.integrator.name, context, scene.integrator.options);
  } catch (const TimestepError& error) {
    throw TimestepError(error.what() + stableStepsPerFrameAdvice(scene, registry, context, simulation.timing));
  }
  requireMultirateForRegionOutput(scene, *simulation.integrator);
  applyInitialVelocities(scene, simulation);
  simulation.monitor.emplace(problem);
  for (const std::string& item : simulation.monitor->skipped()) simulation.skipped.push_back(item);
  return simulation;
}

std::vector<int> vertexStepRatios(const Integrator& integrator, int numVertices) {
  std::vector<int> ratios(static_cast<std::size_t>(numVertices), 1);
  const MultirateIntegrator* multirate = integrator.multirate();
  if (multirate == nullptr) return ratios;
  const std::vector<RegionSummary> regions = multirate->regionSummaries();
  for (int v = 0; v < numVertices; ++v) {
    const int region = multirate->regionOfVertex(v);
    if (region >= 0 && region < std::ssize(regions)) {
      ratios[static_cast<std::size_t>(v)] = regions[static_cast<std::size_t>(region)].ratio;
    }
  }
  return ratios;
}

std::optional<std::vector<int>> fixedRegionRatios(const Scene& scene, const Problem& problem) {
  const nlohmann::json& options = scene.integrator.options;
  if (!options.is_object() || !options.contains("regions") || !options.at("regions").is_array()) return std::nullopt;
  IntegratorContext context = integratorContext(scene);
  context.mesh = problem.sharedMesh();
  context.system.freeDofs = problem.freeDofs();
  // The regions alone: the other keys belong to the integrator and are checked when it runs.
  const AsyncSettings settings = parseAsyncSettings(context, nlohmann::json{{"regions", options.at("regions")}});
  const RegionPartition partition(problem.mesh(), problem.freeDofs(), settings.regions);
  std::vector<int> ratios(static_cast<std::size_t>(problem.mesh().numVertices()), 1);
  for (int v = 0; v < problem.mesh().numVertices(); ++v) {
    const int region = partition.regionOfVertex(v);
    if (region >= 0) ratios[static_cast<std::size_t>(v)] = partition.ratio(region);
  }
  return ratios;
}

void describeRegionOutput(const Scene& scene, const Simulation& simulation, SimulationFileHeader& header) {
  requireMultirateForRegionOutput(scene, *simulation.integrator);
  header.hasRegionRatios = recordsRegionRatios(scene);
}

void describeContactForceOutput(const Scene& scene, const Simulation& simulation, SimulationFileHeader& header) {
  if (scene.output.contactForces && !simulation.contact) {
    throw ValidationError(scene.sourceName +
                          ": output.contactForces: the scene has no contact (no ground, plane, "
                          "sphere, obstacle or contact between bodies) whose forces could be stored");
  }
  header.hasContactForces = scene.output.contactForces;
}

Eigen::VectorXd contactForces(const Simulation& simulation) {
  const Integrator& integrator = *simulation.integrator;
  Eigen::VectorXd forces = Eigen::VectorXd::Zero(integrator.displacement().size());
  if (simulation.contact) {
    simulation.contact->addForces(integrator.time(), integrator.displacement(), integrator.velocity(), forces);
  }
  return forces;
}

void appendSimulationFrame(SimulationWriter& writer, const Simulation& simulation,
                           const Eigen::VectorXd* contactForce) {
  const Integrator& integrator = *simulation.integrator;
  const SimulationFileHeader& header = writer.header();
  FrameArrays arrays;
  std::vector<int> ratios;
  Eigen::VectorXd forces;
  if (header.hasVelocities) arrays.velocity = &integrator.velocity();
  if (header.hasContactForces && contactForce == nullptr) forces = contactForces(simulation);
  if (header.hasContactForces) arrays.contactForce = contactForce != nullptr ? contactForce : &forces;
  if (header.hasRegionRatios) {
    ratios = vertexStepRatios(integrator, static_cast<int>(header.numVertices));
    arrays.regionRatios = &ratios;
  }
  writer.appendFrame(integrator.time(), integrator.displacement(), arrays);
}

void advanceFrame(Simulation& simulation, int frame) {
  if (!simulation.monitor) throw Error("advanceFrame: the simulation has no run monitor (use buildSimulation)");
  // Every frame starts a point a checkpoint may resume from (Integrator::restartPoint()).
  simulation.integrator->restartPoint();
  simulation.monitor->advanceFrame(*simulation.integrator, frame, simulation.timing.stepsPerFrame);
}

}  // namespace asyncfem
