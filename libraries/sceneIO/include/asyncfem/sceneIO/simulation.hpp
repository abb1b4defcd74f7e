// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/integrator/registry.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/runMonitor/runMonitor.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace asyncfem {

/// The integrators a scene can name: registerSingleRateIntegrators() (library
/// integrator: backward-euler, trapezoidal, central-differences, symplectic-euler) and
/// registerMultirateIntegrators() (library asyncIntegrator: async, multirate-uncoupled).
/// Each library fills the registry with its own; sceneIO knows none of their types.
IntegratorRegistry defaultIntegratorRegistry();

/// Makes scene run integrator `name` instead of its own: options belong to an integrator,
/// so the keys of integrator.options that `name` does not read are removed (when the
/// registry declares its keys) and returned, sorted; the shared ones stay. A `name` equal
/// to the scene's integrator changes nothing.
std::vector<std::string> switchIntegrator(Scene& scene, const IntegratorRegistry& registry, const std::string& name);

/// The mesh a scene runs on: its file or generator with the material overrides applied,
/// without assembling anything. Throws asyncfem::ValidationError naming the scene key.
/// When warnings is given, the mesh reader's warnings (default material, ignored
/// elements, reoriented elements, unused vertices) are appended to it as
/// "<scene>: mesh.file: <file>: <warning>".
TetMesh buildSceneMesh(const Scene& scene, std::vector<std::string>* warnings = nullptr);

/// The problem a scene describes (mesh, fixed vertices from sets, boxes and .bou, physics,
/// loads), with nothing assembled: matrices come when asked for (Problem). Throws
/// asyncfem::ValidationError "<scene>: <key path>: message" when the scene does not fit the
/// mesh (unknown set, vertex id out of range, a box selecting no vertex, every vertex
/// fixed). warnings: as for buildSceneMesh.
std::shared_ptr<const Problem> buildProblem(const Scene& scene, std::vector<std::string>* warnings = nullptr);

/// The physics settings a scene gives its Problem (mass, force model with its tangent and
/// hyperelastic options, Rayleigh damping, gravity): what buildProblem() passes on.
ProblemSettings problemSettings(const Scene& scene);

/// The problem of the scene an .afsim file recorded (header.scenePath, version 2), for
/// readers of the frames that were given no --scene or --mesh. Throws asyncfem::Error
/// naming fileName when the file records no scene, the scene cannot be loaded, or it now
/// builds another mesh or other fixed vertices than the run had (fingerprint).
/// warnings: as for buildSceneMesh.
std::shared_ptr<const Problem> recordedSceneProblem(const SimulationFileHeader& header, const std::string& fileName,
                                                    std::vector<std::string>* warnings = nullptr);

/// The context registry factories get for scene at the given timing (timestep, frame
/// rate), with its mass type, contact and names for messages; mesh and system are left
/// for the caller to fill. A program that asks about another timestep than the scene's
/// (proposeRegions --dt) passes a FrameTiming with that timestep.
IntegratorContext integratorContext(const Scene& scene, const FrameTiming& timing);
/// integratorContext(scene, requireFrameTiming(scene)).
IntegratorContext integratorContext(const Scene& scene);

/// A scene ready to run: the problem, the integrator (which owns the state, starting at
/// rest at t = 0, and the timestep), the run monitor and the frame timing.
struct Simulation {
  std::shared_ptr<const Problem> problem;
  /// The problem's mesh (shared, for the many callers that only need it).
  std::shared_ptr<const TetMesh> mesh;
  std::unique_ptr<Integrator> integrator;
  std::optional<RunMonitor> monitor;

  /// The scene's frame timing (requireFrameTiming) as the run was built with it: steps per
  /// frame and frame count for the run loop; timing.timestep is the integrator's timestep().
  FrameTiming timing;

  std::vector<int> fixedVertices;  ///< sorted, 0-based (the problem's)
  /// The penalty contact model when the scene has obstacles (for reports: penetration).
  std::shared_ptr<const PenaltyContact> contact;

  /// Work the scene made unnecessary and the builder therefore did not do; the
  /// integrator's own list is in integrator->stats().skipped.
  std::vector<std::string> skipped;
  /// Things that will run but that the user should know about (printed by the utilities):
  /// the mesh reader's warnings (buildSceneMesh), an explicit contact stiffness too high
  /// for the timestep.
  std::vector<std::string> warnings;
};

/// Builds what a scene describes, and only that: buildProblem(), the DynamicSystem, the
/// integrator from registry, the monitor and the frame timing. Throws
/// asyncfem::ValidationError "<scene>: <key path>: message" as buildProblem() does, for
/// timing that gives no whole number of steps per frame, and for unknown integrator names
/// or options (IntegratorRegistry::create()).
Simulation buildSimulation(const Scene& scene, const IntegratorRegistry& registry = defaultIntegratorRegistry());

/// Each vertex's step ratio to the large step in the partition the integrator uses now: 1
/// in the large-step region L, m_i in fast region S_i (MultirateIntegrator::regionOfVertex
/// and regionSummaries); all 1 for a single-rate integrator.
std::vector<int> vertexStepRatios(const Integrator& integrator, int numVertices);

/// Each vertex's step ratio under the scene's fixed regions (integrator.options.regions
/// given as an array of regions, resolved on problem's mesh as the multirate integrators
/// resolve them): the partition of every frame of such a run. nullopt when the scene has
/// none (single-rate, or proposed or run-time regions). Throws asyncfem::ValidationError
/// naming the key for regions that do not fit the mesh.
std::optional<std::vector<int>> fixedRegionRatios(const Scene& scene, const Problem& problem);

/// Throws asyncfem::ValidationError "<scene>: output.regions: ..." when the scene records
/// region ratios (recordsRegionRatios()) and integrator is single-rate; buildSimulation()
/// checks it.
void requireMultirateForRegionOutput(const Scene& scene, const Integrator& integrator);

/// Sets header.hasRegionRatios when a run of scene records them (recordsRegionRatios()),
/// after requireMultirateForRegionOutput().
void describeRegionOutput(const Scene& scene, const Simulation& simulation, SimulationFileHeader& header);

/// Sets header.hasContactForces from output.contactForces. Throws
/// asyncfem::ValidationError "<scene>: output.contactForces: ..." when the scene asks for
/// them but has no contact (no ground, plane, sphere, obstacle or body-body contact).
void describeContactForceOutput(const Scene& scene, const Simulation& simulation, SimulationFileHeader& header);

/// The force the scene's contact model exerts on every vertex (3n, N) at the simulation's
/// current time and state (displacement and velocity): the penalty springs, their damping
/// and friction, against obstacles and between surfaces (PenaltyContact::addForces). Zero
/// without contact. Backward Euler with implicit contact applies exactly this force in the
/// step that ended at this state; an explicit step applied the force of its start state.
Eigen::VectorXd contactForces(const Simulation& simulation);

/// Appends the simulation's current state (time, displacement) as the next frame of
/// writer, with the velocities, contact forces (contactForces()) and region ratios
/// (vertexStepRatios) its header asks for. contactForce: contactForces(simulation) where the
/// caller has it already (null: evaluated here when the header asks for it).
void appendSimulationFrame(SimulationWriter& writer, const Simulation& simulation,
                           const Eigen::VectorXd* contactForce = nullptr);

/// Advances the simulation by one frame (stepsPerFrame steps) under its RunMonitor, the
/// frame's start being a restart point of the integrator (Integrator::restartPoint(), which
/// no shipped integrator needs any more: kept factors live across frames, their state in
/// checkpoints):
/// throws asyncfem::NumericalError with the frame, step, time, vertex and region (as
/// fields and in the message) for a non-finite state, a blow-up or energy growth. The
/// state is then unusable; the caller must not store it.
void advanceFrame(Simulation& simulation, int frame);

}  // namespace asyncfem
