// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/asyncIntegrator/uncoupledMultirate.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/forceModel/linearForceModel.hpp>
#include <asyncfem/integrator/factory.hpp>
#include <asyncfem/sceneIO/asyncScene.hpp>
#include <asyncfem/sceneIO/jsonReader.hpp>
#include <asyncfem/sceneIO/multirateScene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <cmath>
#include <limits>
#include <sstream>

namespace asyncfem {

void IntegratorRegistry::add(const std::string& name, IntegratorFactory factory, std::vector<std::string> optionKeys) {
  factories_[name] = std::move(factory);
  optionKeys_[name] = std::move(optionKeys);
}

const std::vector<std::string>& IntegratorRegistry::optionKeys(const std::string& name) const {
  static const std::vector<std::string> none;
  const auto it = optionKeys_.find(name);
  return it == optionKeys_.end() ? none : it->second;
}

std::vector<std::string> switchIntegrator(Scene& scene, const IntegratorRegistry& registry, const std::string& name) {
  std::vector<std::string> dropped;
  if (name == scene.integrator.name) return dropped;
  scene.integrator.name = name;
  const std::vector<std::string>& known = registry.optionKeys(name);
  if (known.empty() || !scene.integrator.options.is_object()) return dropped;
  for (auto it = scene.integrator.options.begin(); it != scene.integrator.options.end();) {
    if (std::find(known.begin(), known.end(), it.key()) == known.end()) {
      dropped.push_back(it.key());
      it = scene.integrator.options.erase(it);
    } else {
      ++it;
    }
  }
  std::sort(dropped.begin(), dropped.end());
  return dropped;
}

const IntegratorFactory* IntegratorRegistry::find(const std::string& name) const {
  const auto it = factories_.find(name);
  return it == factories_.end() ? nullptr : &it->second;
}

std::vector<std::string> IntegratorRegistry::names() const {
  std::vector<std::string> result;
  for (const auto& [name, factory] : factories_) {
    result.push_back(name);
  }
  return result;
}

namespace {

std::string joined(const std::vector<std::string>& names) {
  std::string list;
  for (const std::string& name : names) {
    list += (list.empty() ? "" : ", ") + name;
  }
  return list;
}

// The options every single-rate integrator accepts (IntegratorOptions).
IntegratorOptions parseSingleRateOptions(const Scene& scene, const nlohmann::json& options) {
  JsonObjectReader reader(options, "integrator.options", scene.sourceName);
  IntegratorOptions result;
  if (const auto solver = reader.optionalString("solver")) {
    try {
      result.solver = parseSolverKind(*solver);
    } catch (const Error& error) {
      reader.fail("solver", error.what());
    }
  }
  result.maxIterations = reader.integer("maxIterations", result.maxIterations, 1, 1000);
  result.tolerance = reader.number("tolerance", result.tolerance);
  if (!(result.tolerance > 0.0)) {
    reader.fail("tolerance", "expected a number > 0");
  }
  result.maxFrequency = reader.number("maxFrequency", result.maxFrequency);
  if (result.maxFrequency < 0.0) {
    reader.fail("maxFrequency", "expected a number >= 0 (0: estimate it)");
  }
  result.force = reader.boolean("force", result.force);
  reader.finish();
  return result;
}

TetMesh loadMesh(const Scene& scene) {
  switch (scene.mesh.source) {
    case Scene::MeshSource::beam:
      return makeBeamMesh(scene.mesh.beam);
    case Scene::MeshSource::box:
      return makeBoxMesh(scene.mesh.box);
    case Scene::MeshSource::file:
      break;
  }
  try {
    return readMesh(scene.mesh.file);
  } catch (const Error& error) {
    throw ValidationError(scene.sourceName + ": mesh.file: " + error.what());
  }
}

std::string knownSets(const std::map<std::string, std::vector<int>>& sets) {
  std::vector<std::string> names;
  for (const auto& [name, members] : sets) {
    names.push_back(name);
  }
  return names.empty() ? "none" : joined(names);
}

// The vertices of a set of either kind (TetMesh::setVertices), with errors at the key.
std::vector<int> vertexSetAt(const Scene& scene, const TetMesh& mesh, const std::string& name,
                             const std::string& keyPath) {
  if (!mesh.vertexSets().count(name) && !mesh.elementSets().count(name)) {
    throwSceneError(scene, keyPath,
                    "unknown set \"" + name + "\" (vertex sets: " + knownSets(mesh.vertexSets()) +
                        "; element sets: " + knownSets(mesh.elementSets()) + ")");
  }
  std::vector<int> vertices = mesh.setVertices(name);
  if (vertices.empty()) {
    throwSceneError(scene, keyPath, "set \"" + name + "\" is empty");
  }
  return vertices;
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
    std::vector<int> elements;
    if (override.set == "allElements") {
      elements.resize(static_cast<std::size_t>(mesh.numElements()));
      for (int e = 0; e < mesh.numElements(); ++e) {
        elements[static_cast<std::size_t>(e)] = e;
      }
    } else {
      const auto it = mesh.elementSets().find(override.set);
      if (it == mesh.elementSets().end()) {
        throwSceneError(
            scene, keyPath,
            "unknown element set \"" + override.set + "\" (known: allElements, " + knownSets(mesh.elementSets()) + ")");
      }
      elements = it->second;
    }
    std::map<int, std::vector<int>> byMaterial;
    for (const int e : elements) {
      byMaterial[elementMaterials[static_cast<std::size_t>(e)]].push_back(e);
    }
    for (const auto& [materialIndex, members] : byMaterial) {
      Material material = materials[static_cast<std::size_t>(materialIndex)];
      material.density = override.density.value_or(material.density);
      material.youngsModulus = override.youngsModulus.value_or(material.youngsModulus);
      material.poissonRatio = override.poissonRatio.value_or(material.poissonRatio);
      const auto users =
          static_cast<std::size_t>(std::count(elementMaterials.begin(), elementMaterials.end(), materialIndex));
      if (users == members.size()) {
        materials[static_cast<std::size_t>(materialIndex)] = material;
        continue;
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
      for (const int e : members) {
        elementMaterials[static_cast<std::size_t>(e)] = newIndex;
      }
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

std::vector<int> collectFixedVertices(const Scene& scene, const TetMesh& mesh) {
  std::vector<int> fixed;
  for (std::size_t i = 0; i < scene.fixed.sets.size(); ++i) {
    const auto& members = vertexSetAt(scene, mesh, scene.fixed.sets[i], "fixed.sets[" + std::to_string(i) + "]");
    fixed.insert(fixed.end(), members.begin(), members.end());
  }
  for (std::size_t i = 0; i < scene.fixed.boxes.size(); ++i) {
    const Scene::Box& box = scene.fixed.boxes[i];
    std::size_t selected = 0;
    for (int v = 0; v < mesh.numVertices(); ++v) {
      const Eigen::Vector3d x = mesh.restPosition(v);
      if ((x.array() >= box.min.array()).all() && (x.array() <= box.max.array()).all()) {
        fixed.push_back(v);
        ++selected;
      }
    }
    if (selected == 0) {
      throwSceneError(scene, "fixed.boxes[" + std::to_string(i) + "]", "selects no vertex");
    }
  }
  if (scene.fixed.bouFile) {
    std::vector<int> fromFile;
    try {
      fromFile = readBou(*scene.fixed.bouFile, mesh.numVertices());
    } catch (const Error& error) {
      throwSceneError(scene, "fixed.bou", error.what());
    }
    fixed.insert(fixed.end(), fromFile.begin(), fromFile.end());
  }
  std::sort(fixed.begin(), fixed.end());
  fixed.erase(std::unique(fixed.begin(), fixed.end()), fixed.end());
  if (!fixed.empty() && static_cast<int>(fixed.size()) == mesh.numVertices()) {
    throwSceneError(scene, "fixed", "every vertex is fixed: nothing would move");
  }
  return fixed;
}

// One external load: the same force on each of its vertices while it is active.
struct VertexLoad {
  std::vector<int> vertices;
  Eigen::Vector3d perVertex = Eigen::Vector3d::Zero();
  bool leftOpen = false;  // window (start, end] instead of [start, end)
  double start = 0.0;
  double end = 0.0;

  bool active(double time) const { return leftOpen ? (time > start && time <= end) : (time >= start && time < end); }
};

// Relative to h: how close to a window bound a step time counts as on it. Round-off in
// k h and in the substep times t0 + r hS is ~1e-16 relative; 1e-9 is far above it and far
// below any deliberate offset from a step time.
constexpr double windowTolerance = 1e-9;

std::vector<VertexLoad> collectLoads(const Scene& scene, const TetMesh& mesh) {
  std::vector<VertexLoad> loads;
  for (std::size_t i = 0; i < scene.forces.size(); ++i) {
    const Scene::Force& force = scene.forces[i];
    const std::string keyPath = "forces[" + std::to_string(i) + "]";
    VertexLoad load;
    if (!force.set.empty()) {
      load.vertices = vertexSetAt(scene, mesh, force.set, keyPath + ".set");
    } else {
      for (std::size_t k = 0; k < force.vertices.size(); ++k) {
        const int v = force.vertices[k];
        if (v < 0 || v >= mesh.numVertices()) {
          throwSceneError(scene, keyPath + ".vertices[" + std::to_string(k) + "]",
                          "vertex " + std::to_string(v) + " out of range [0, " + std::to_string(mesh.numVertices()) +
                              ") (ids are 0-based)");
        }
      }
      load.vertices = force.vertices;
      std::sort(load.vertices.begin(), load.vertices.end());
      load.vertices.erase(std::unique(load.vertices.begin(), load.vertices.end()), load.vertices.end());
    }
    const double count = static_cast<double>(load.vertices.size());
    if (force.type == Scene::ForceType::pull) {
      load.perVertex = force.vector / count;
      // Acts at step times start <= t < end, where a step time within 1e-9 h of a bound
      // counts as the bound (docs/scene-format.md): step times are k h up to round-off, so
      // a window ending on a step time excludes that step whatever the round-off.
      const double tolerance = windowTolerance * scene.integrator.timestep;
      load.start = force.start - tolerance;
      load.end = force.end - tolerance;
    } else {
      // An impulse I is a force I / h over a window one step long. Integrators evaluate
      // f_ext at step starts, step ends or both (averaged); the window
      // (t + h/2, t + 3h/2] holds exactly one step time, far from its ends, so each of
      // them delivers exactly I, in the step after t.
      const double h = scene.integrator.timestep;
      load.perVertex = force.vector / (h * count);
      load.leftOpen = true;
      load.start = force.time + (0.5 * h);
      load.end = force.time + (1.5 * h);
    }
    if (load.perVertex.isZero(0.0)) {
      continue;
    }
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

}  // namespace

IntegratorRegistry defaultIntegratorRegistry() {
  IntegratorRegistry registry;
  // The keys each reads (docs/scene-format.md): switchIntegrator() drops the others.
  registry.add("async", asyncIntegratorFactory(),
               {"coupling", "schur", "method", "recovery", "regionSolver", "substepContact", "regions"});
  registry.add("multirate-uncoupled", uncoupledMultirateIntegratorFactory(),
               {"compoundSolver", "regionSolver", "regions"});
  for (const std::string& name : integratorNames()) {
    registry.add(
        name,
        [name](const Scene& scene, const TetMesh& /*mesh*/, DynamicSystem system, const nlohmann::json& options) {
          const IntegratorOptions parsed = parseSingleRateOptions(scene, options);
          return makeIntegrator(name, std::move(system), scene.integrator.timestep, parsed);
        },
        {"solver", "maxIterations", "tolerance", "maxFrequency", "force"});
  }
  return registry;
}

namespace {

// Penalty contact is explicit: its force is evaluated at one state per (large) step. A
// boundary vertex of lumped mass m on a penalty spring k oscillates at omega = sqrt(k / m),
// and an explicit spring alone is unstable beyond omega h = 2. The lightest vertices are
// held by their stiff (implicit) neighbours, so the median boundary vertex is the measure:
// measured with benchmarkAsync --study contact, omega h of 3.2 and 4.6 for it gained energy
// at impacts, 1.1 did not (docs/benchmarks.md). Warn from omega h > 2.
std::vector<std::string> contactStepWarnings(const Scene& scene, const TetMesh& mesh,
                                             const Eigen::SparseMatrix<double>& mass) {
  const double k = scene.contact.parameters.stiffness;
  const double h = scene.integrator.timestep;
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
  std::vector<std::string> warnings;
  if (masses.empty()) return warnings;
  std::nth_element(masses.begin(), masses.begin() + static_cast<std::ptrdiff_t>(masses.size() / 2), masses.end());
  const double median = masses[masses.size() / 2];
  const double omegaH = std::sqrt(k / median) * h;
  if (omegaH > 2.0) {
    warnings.push_back(
        scene.sourceName + ": contact.stiffness: " + formatNumber(k) + " on a boundary vertex of median lumped mass " +
        formatNumber(median) + " gives omega h = " + formatNumber(omegaH) + " at integrator.timestep " +
        formatNumber(h) +
        "; penalty contact is explicit, and beyond omega h = 2 its spring is unstable on its own and can add "
        "energy at impacts: lower contact.stiffness below " +
        formatNumber(4.0 * median / (h * h)) + " or the timestep" +
        (scene.integrator.name == "async" ? " (substepContact only helps the fast regions)" : ""));
  }
  return warnings;
}

}  // namespace

TetMesh buildSceneMesh(const Scene& scene) { return applyMaterialOverrides(scene, loadMesh(scene)); }

Simulation buildSimulation(const Scene& givenScene, const IntegratorRegistry& registry) {
  Simulation simulation;
  // The timestep every part below uses is the resolved one (from integrator.stepsPerFrame
  // when the scene gives it).
  const FrameTiming timing = resolveFrameTiming(givenScene);
  Scene scene = givenScene;
  scene.integrator.timestep = timing.timestep;

  // Cheap checks first, so a bad scene fails before the mesh is read and matrices built.
  const IntegratorFactory* factory = registry.find(scene.integrator.name);
  if (factory == nullptr) {
    throwSceneError(scene, "integrator.name",
                    "unknown integrator \"" + scene.integrator.name + "\" (known: " + joined(registry.names()) + ")");
  }
  if (scene.frames.count < 1) {
    throwSceneError(scene, "frames.count", "expected a count >= 1");
  }
  simulation.timestep = timing.timestep;
  simulation.frameInterval = timing.frameInterval;
  simulation.stepsPerFrame = timing.stepsPerFrame;
  simulation.numFrames = scene.frames.count;

  auto mesh = std::make_shared<TetMesh>(buildSceneMesh(scene));
  simulation.mesh = mesh;
  simulation.fixedVertices = collectFixedVertices(scene, *mesh);
  const std::vector<VertexLoad> loads = collectLoads(scene, *mesh);
  const BoundingBox box = boundingBox(*mesh);
  simulation.boundingBoxDiagonal = (box.max - box.min).norm();
  simulation.blowUpDisplacement = 1000.0 * simulation.boundingBoxDiagonal;

  DynamicSystem system;
  auto assembler = std::make_shared<const MatrixAssembler>(*mesh);
  if (scene.forceModel == Scene::ForceModelKind::linear) {
    system.forceModel = std::make_shared<LinearForceModel>(linearStiffnessMatrix(*mesh, *assembler));
    simulation.skipped.emplace_back("corotational rotations and per-step tangent (linear force model)");
  } else {
    const TangentKind tangent = scene.tangent == Scene::Tangent::exact ? TangentKind::exact : TangentKind::simple;
    system.forceModel = std::make_shared<CorotationalLinearFEM>(*mesh, assembler, tangent);
  }
  system.mass = massMatrix(*mesh, *assembler, scene.mass);
  system.freeDofs = FreeDofs::fromFixedVertices(mesh->numVertices(), simulation.fixedVertices);
  system.rayleighMass = scene.rayleighAlpha;
  system.rayleighStiffness = scene.rayleighBeta;

  // External force: gravity M g (precomputed once) plus the loads active at time t.
  Eigen::VectorXd gravityForce;
  if (!scene.gravity.isZero(0.0)) {
    const Eigen::VectorXd stackedGravity = scene.gravity.replicate(mesh->numVertices(), 1);
    gravityForce = system.mass * stackedGravity;
  } else {
    simulation.skipped.emplace_back("gravity load (gravity is zero)");
  }
  std::shared_ptr<const PenaltyContact> contact;
  if (scene.contact.enabled()) {
    contact = std::make_shared<PenaltyContact>(mesh->restPositions(), scene.contact.planes, scene.contact.spheres,
                                               scene.contact.parameters);
    simulation.contact = contact;
    simulation.warnings = contactStepWarnings(scene, *mesh, system.mass);
  } else {
    simulation.skipped.emplace_back("contact (no obstacles)");
  }
  // Energy check (advanceFrame): once the last load window has closed, with no contact,
  // the total energy with the potential of the constant loads can only stay or decrease.
  if (!contact) {
    double from = 0.0;
    Eigen::VectorXd constant =
        gravityForce.size() > 0 ? gravityForce : Eigen::VectorXd::Zero(static_cast<Eigen::Index>(mesh->numDofs()));
    for (const VertexLoad& load : loads) {
      if (std::isfinite(load.end)) {
        from = std::max(from, load.end);
        continue;
      }
      from = std::max(from, load.start);
      for (const int v : load.vertices) constant.segment<3>(3 * static_cast<Eigen::Index>(v)) += load.perVertex;
    }
    simulation.energyCheckFrom = from;
    simulation.constantLoad = std::move(constant);
  } else {
    simulation.skipped.emplace_back("energy blow-up check (contact forces do work)");
  }
  if (gravityForce.size() > 0 || !loads.empty() || contact) {
    system.externalForce = [gravityForce, loads, contact](double time, const Eigen::VectorXd& displacement,
                                                          const Eigen::VectorXd& velocity, Eigen::VectorXd& forces) {
      if (gravityForce.size() > 0) {
        forces += gravityForce;
      }
      for (const VertexLoad& load : loads) {
        if (!load.active(time)) {
          continue;
        }
        for (const int v : load.vertices) {
          forces.segment<3>(3 * static_cast<Eigen::Index>(v)) += load.perVertex;
        }
      }
      if (contact) contact->addForces(displacement, velocity, forces);
    };
  } else {
    simulation.skipped.emplace_back("external force evaluation (no gravity, no loads)");
  }
  if (scene.output.vtuFolder.empty()) {
    simulation.skipped.emplace_back("vtu output (output.vtu not set)");
  }
  if (!scene.output.velocities) {
    simulation.skipped.emplace_back("velocity output (output.velocities = false)");
  }

  try {
    simulation.integrator = (*factory)(scene, *mesh, std::move(system), scene.integrator.options);
  } catch (const ValidationError& error) {
    const std::string message = error.what();
    // Factories reading their options already name the key.
    if (message.rfind(scene.sourceName + ": ", 0) == 0) {
      throw;
    }
    throwSceneError(scene, message.find("timestep") != std::string::npos ? "integrator.timestep" : "integrator",
                    message);
  } catch (const NumericalError& error) {
    throw NumericalError(scene.sourceName + ": integrator: " + error.what());
  }
  return simulation;
}

namespace {

// Where a vertex lies, for messages: the asynchronous integrator's region (S_i with its
// name, or L), else "the mesh"; plus the first named vertex set holding it, if any.
std::string describeVertex(const Simulation& simulation, int vertex) {
  std::ostringstream out;
  out << "vertex " << vertex;
  // Both multirate integrators partition the mesh into L and fast regions.
  const RegionPartition* partition = nullptr;
  if (const auto* async = dynamic_cast<const AsyncBackwardEuler*>(simulation.integrator.get())) {
    partition = &async->partition();
  } else if (const auto* multirate = dynamic_cast<const UncoupledMultirate*>(simulation.integrator.get())) {
    partition = &multirate->partition();
  }
  const std::vector<int>* regionOfVertex = partition != nullptr ? &partition->vertexRegion() : nullptr;
  if (regionOfVertex != nullptr && vertex >= 0 && vertex < static_cast<int>(regionOfVertex->size())) {
    const int region = (*regionOfVertex)[static_cast<std::size_t>(vertex)];
    if (region >= 0) {
      out << " in fast region S_" << (region + 1) << " '" << partition->region(region).name << "'";
    } else {
      out << " in the large-step region L";
    }
  } else {
    out << " of the mesh";
  }
  if (simulation.mesh) {
    for (const auto& [name, members] : simulation.mesh->vertexSets()) {
      if (std::binary_search(members.begin(), members.end(), vertex)) {
        out << " (vertex set '" << name << "')";
        break;
      }
    }
  }
  return out.str();
}

// The vertex an integrator's NumericalError names ("... (vertex 17, ..."), or -1.
int vertexNamedIn(const std::string& message) {
  const std::string key = "(vertex ";
  const std::size_t at = message.find(key);
  if (at == std::string::npos) return -1;
  std::size_t position = at + key.size();
  long long vertex = 0;
  bool digits = false;
  while (position < message.size() && message[position] >= '0' && message[position] <= '9' && vertex < (1LL << 40)) {
    vertex = (10 * vertex) + (message[position] - '0');
    digits = true;
    ++position;
  }
  return digits && vertex <= std::numeric_limits<int>::max() ? static_cast<int>(vertex) : -1;
}

}  // namespace

void advanceFrame(Simulation& simulation, int frame) {
  Integrator& integrator = *simulation.integrator;
  for (int s = 0; s < simulation.stepsPerFrame; ++s) {
    // The time the step ends at, taken before the step (which advances time() on success).
    const double stepEnd = integrator.time() + simulation.timestep;
    const auto where = [&] {
      std::ostringstream out;
      out << "frame " << frame << " (step " << ((static_cast<long long>(frame) * simulation.stepsPerFrame) + s + 1)
          << ", t = " << formatNumber(stepEnd) << ")";
      return out.str();
    };
    try {
      integrator.step();
    } catch (const NumericalError& error) {
      const int vertex = vertexNamedIn(error.what());
      const std::string location = vertex >= 0 ? " [" + describeVertex(simulation, vertex) + "]" : "";
      throw NumericalError(where() + ": " + error.what() + location);
    }
    const Eigen::VectorXd& u = integrator.displacement();
    const Eigen::VectorXd& v = integrator.velocity();
    // The first vertex with a non-finite entry, and the one with the largest |u|.
    Eigen::Index firstNonFinite = -1;
    Eigen::Index largest = 0;
    double maxDisplacement = 0.0;
    for (Eigen::Index i = 0; i < u.size(); ++i) {
      if (!std::isfinite(u[i]) || !std::isfinite(v[i])) {
        firstNonFinite = i;
        break;
      }
      if (std::abs(u[i]) > maxDisplacement) {
        maxDisplacement = std::abs(u[i]);
        largest = i;
      }
    }
    if (firstNonFinite >= 0) {
      throw NumericalError(where() + ": the state is not finite (NaN or infinity), first at " +
                           describeVertex(simulation, static_cast<int>(firstNonFinite / 3)) +
                           "; the simulation is unstable");
    }
    if (maxDisplacement > simulation.blowUpDisplacement) {
      throw NumericalError(where() + ": blow-up: max |u| = " + formatNumber(maxDisplacement) + " at " +
                           describeVertex(simulation, static_cast<int>(largest / 3)) +
                           " exceeds 1000 x the bounding-box diagonal (" +
                           formatNumber(simulation.boundingBoxDiagonal) + "); the simulation is unstable");
    }
  }
  // Energy blow-up: after the loads, growth of the total energy to ten times its size is
  // an instability (a stable integrator keeps or dissipates it; explicit ones let it
  // oscillate by far less than that below their stable step).
  if (integrator.time() >= simulation.energyCheckFrom + 0.5 * simulation.timestep) {
    const Eigen::VectorXd& u = integrator.displacement();
    const double mechanical = integrator.mechanicalEnergy();
    const double energy = mechanical - simulation.constantLoad.dot(u);
    if (simulation.freeEnergyScale <= 0.0) {
      simulation.freeEnergy = energy;
      simulation.freeEnergyScale = std::max(mechanical, std::abs(energy));
      simulation.freeEnergyTime = integrator.time();
    } else if (energy - simulation.freeEnergy > 9.0 * simulation.freeEnergyScale) {
      Eigen::Index largest = 0;
      u.cwiseAbs().maxCoeff(&largest);
      std::ostringstream out;
      out << "frame " << frame << " (t = " << formatNumber(integrator.time())
          << "): energy blow-up: with no load changing since t = " << formatNumber(simulation.energyCheckFrom)
          << ", the total energy (kinetic + elastic - constant loads . u) grew from "
          << formatNumber(simulation.freeEnergy) << " at t = " << formatNumber(simulation.freeEnergyTime) << " to "
          << formatNumber(energy) << "; largest |u| = " << formatNumber(std::abs(u[largest])) << " at "
          << describeVertex(simulation, static_cast<int>(largest / 3)) << "; the simulation is unstable";
      throw NumericalError(out.str());
    }
  }
}

}  // namespace asyncfem
