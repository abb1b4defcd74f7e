// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace asyncfem {

/// Creates the integrator a scene names. options is the scene's `integrator.options`
/// object; a factory reads the keys it knows with a JsonObjectReader at path
/// "integrator.options" and rejects the rest (JsonObjectReader::finish()), so that errors
/// name the key. The timestep is scene.integrator.timestep.
using IntegratorFactory = std::function<std::unique_ptr<Integrator>(
    const Scene& scene, const TetMesh& mesh, DynamicSystem system, const nlohmann::json& options)>;

/// Integrator name -> factory. defaultIntegratorRegistry() holds the single-rate
/// integrators of library `integrator` and the asynchronous integrator ("async"); other
/// libraries add theirs with add() before buildSimulation():
///
///     IntegratorRegistry registry = defaultIntegratorRegistry();
///     registry.add("async", makeAsyncFromScene);
///     Simulation simulation = buildSimulation(scene, registry);
class IntegratorRegistry {
 public:
  /// Adds (or replaces) the factory for name, with the keys of integrator.options it reads
  /// (empty: not declared, so switchIntegrator() keeps every option).
  void add(const std::string& name, IntegratorFactory factory, std::vector<std::string> optionKeys = {});
  /// The factory for name, or nullptr.
  const IntegratorFactory* find(const std::string& name) const;
  /// The option keys declared for name (empty if none were, or name is unknown).
  const std::vector<std::string>& optionKeys(const std::string& name) const;
  /// Registered names, sorted.
  std::vector<std::string> names() const;

 private:
  std::map<std::string, IntegratorFactory> factories_;
  std::map<std::string, std::vector<std::string>> optionKeys_;
};

/// Makes scene run integrator `name` instead of its own: options belong to an integrator,
/// so the keys of integrator.options that `name` does not read are removed (when the
/// registry declares its keys) and returned, sorted; the shared ones stay. A `name` equal
/// to the scene's integrator changes nothing.
std::vector<std::string> switchIntegrator(Scene& scene, const IntegratorRegistry& registry, const std::string& name);

/// "backward-euler", "trapezoidal", "central-differences", "symplectic-euler", each
/// reading the options keys solver, maxIterations, tolerance, maxFrequency, force (see
/// docs/scene-format.md and IntegratorOptions), and "async" (asyncScene.hpp).
IntegratorRegistry defaultIntegratorRegistry();

/// A scene ready to run: the mesh, the integrator (which owns the DynamicSystem and the
/// state, starting at rest at t = 0) and the frame timing.
struct Simulation {
  /// Shared so that force models and integrators holding references keep a stable object.
  std::shared_ptr<const TetMesh> mesh;
  std::unique_ptr<Integrator> integrator;

  double timestep = 0.0;       ///< h of the integrator
  double frameInterval = 0.0;  ///< 1 / frames.rate
  int stepsPerFrame = 0;       ///< frameInterval / h, an integer
  int numFrames = 0;

  std::vector<int> fixedVertices;  ///< sorted, 0-based
  /// The penalty contact model when the scene has obstacles (for reports: penetration).
  std::shared_ptr<const PenaltyContact> contact;
  /// Diagonal of the rest bounding box, and the blow-up limit on max |u| (1000 times it).
  double boundingBoxDiagonal = 0.0;
  double blowUpDisplacement = 0.0;
  /// Energy check of advanceFrame: from this time on no load changes and no contact acts,
  /// so the total energy E = kinetic + elastic - constantLoad . u cannot grow (infinity:
  /// never checked, e.g. with contact). constantLoad: gravity plus pulls without an end.
  double energyCheckFrom = std::numeric_limits<double>::infinity();
  Eigen::VectorXd constantLoad;
  /// Set by advanceFrame at the first frame of that free phase: E there, the scale growth
  /// is measured against (max of kinetic + elastic and |E|) and the time.
  double freeEnergy = 0.0, freeEnergyScale = -1.0, freeEnergyTime = 0.0;

  /// Work the scene made unnecessary and the builder therefore did not do (corotational
  /// machinery for a linear scene, gravity, ...); the integrator's own list is in
  /// integrator->stats().skipped.
  std::vector<std::string> skipped;
  /// Things that will run but that the user should know about (printed by the utilities),
  /// e.g. an explicit contact stiffness too high for the timestep.
  std::vector<std::string> warnings;
};

/// The mesh a scene runs on: its file or generator with the material overrides applied,
/// as buildSimulation builds it, without assembling anything (for tools that only need
/// positions). Throws asyncfem::ValidationError as buildSimulation does for the mesh.
TetMesh buildSceneMesh(const Scene& scene);

/// Builds what a scene describes, and only that: the mesh (file or generator) with the
/// material overrides, the fixed vertices (sets, boxes, .bou), consistent or lumped mass,
/// a LinearForceModel (constant K) or a CorotationalLinearFEM, Rayleigh alpha and beta,
/// the external force (gravity M g, pulls in their windows, impulses; empty when there is
/// none), the integrator from registry and the frame timing.
///
/// Throws asyncfem::ValidationError "<scene>: <key path>: message" when the scene does
/// not fit the mesh (unknown set, vertex id out of range, a box selecting no vertex,
/// every vertex fixed) or the timing does not (frames.rate and integrator.timestep must
/// give an integer number of steps per frame), and for unknown integrator names or
/// options; errors of the mesh reader are prefixed with the scene and key.
Simulation buildSimulation(const Scene& scene, const IntegratorRegistry& registry = defaultIntegratorRegistry());

/// Advances the simulation by one frame (stepsPerFrame steps). frame is the 0-based frame
/// index used in messages. After every step it checks that u and v are finite and that
/// max |u| <= blowUpDisplacement; after the frame, once no load changes (energyCheckFrom),
/// that the total energy has not grown to ten times its size at the start of that free
/// phase. Otherwise (or if the integrator itself fails numerically) it throws
/// asyncfem::NumericalError naming the frame, the step and the time. The state is then unusable; the caller must not
/// store it.
void advanceFrame(Simulation& simulation, int frame);

}  // namespace asyncfem
