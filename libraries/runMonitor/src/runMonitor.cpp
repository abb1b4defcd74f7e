// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Dense>
#include <algorithm>
#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/multirateIntegrator.hpp>
#include <asyncfem/runMonitor/runMonitor.hpp>
#include <asyncfem/simulationIO/crc32.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>

namespace asyncfem {

namespace {

std::string formatNumber(double value, int precision = 6) {
  std::ostringstream out;
  out.precision(precision);
  out << value;
  return out.str();
}

/// Up to eight Jacobian determinants of one element.
using ElementJacobians = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 8, 1>;

/// Element e's Jacobian determinants at positions rest + u (at rest when displacement is
/// null): det (x1 - x0, x2 - x0, x3 - x0) of a tetrahedron, the eight corner Jacobians of a
/// hexahedron. det F of the element is their ratio to the rest values.
ElementJacobians elementJacobians(const TetMesh& mesh, int e, const Eigen::VectorXd* displacement) {
  const int corners = mesh.verticesPerElement();
  Eigen::Matrix<double, 3, 8> x;
  for (int a = 0; a < corners; ++a) {
    const int v = mesh.elementVertex(e, a);
    x.col(a) = mesh.restPositions().col(v);
    if (displacement != nullptr) x.col(a) += displacement->segment<3>(3 * static_cast<Eigen::Index>(v));
  }
  if (corners == 8) return hexahedron::cornerJacobians(x);
  Eigen::Matrix3d edges;
  for (int c = 1; c < 4; ++c) edges.col(c - 1) = x.col(c) - x.col(0);
  return ElementJacobians::Constant(1, edges.determinant());
}

bool isHyperelastic(ForceModelType type) {
  return type == ForceModelType::stvk || type == ForceModelType::neoHookean || type == ForceModelType::mooneyRivlin;
}

template <typename T>
std::uint32_t crcOf(const T& value, std::uint32_t crc) {
  return crc32(&value, sizeof(value), crc);
}

}  // namespace

RunMonitor::RunMonitor(const Problem& problem, Settings settings) : mesh_(&problem.mesh()), settings_(settings) {
  const BoundingBox box = boundingBox(problem.mesh());
  boundingBoxDiagonal_ = (box.max - box.min).norm();
  blowUpDisplacement_ = settings_.blowUpFactor * boundingBoxDiagonal_;
  if (settings_.energyCheck) {
    // Contact's forces do no net work with its penalty potential in the energy (only its
    // damping, clamp and friction act on their own, and they dissipate).
    const Loads& loads = *problem.loads();
    energyCheckFrom_ = loads.lastWindowChange();
    constantLoad_ = loads.constantPart(problem.numDofs());
    contact_ = problem.contact();
    if (contact_) {
      // A body that starts at rest under gravity starts the free phase at zero energy: the
      // work of its constant loads over the body's size sets the scale instead.
      for (Eigen::Index dof = 0; dof + 2 < constantLoad_.size(); dof += 3)
        loadWorkScale_ += constantLoad_.segment<3>(dof).norm();
      loadWorkScale_ *= boundingBoxDiagonal_;
    }
  }
  const ProblemSettings& physics = problem.settings();
  if (isHyperelastic(physics.forceModel) && !physics.hyperelastic.inversionHandlingEnabled()) {
    inversionCheckModel_ = toString(physics.forceModel);
    inversionAdvice_ =
        physics.forceModel == ForceModelType::stvk &&
                physics.hyperelastic.stvkFormulation == StVKFormulation::greenStrain
            ? "set forceModel.stvkFormulation to \"principal-stretches\" and forceModel.inversionThreshold (e.g. 0.5) "
              "or reduce the step or the load"
            : "set forceModel.inversionThreshold (e.g. 0.1) or reduce the step or the load";
    restJacobians_.reserve(static_cast<std::size_t>(mesh_->numElements()) * (mesh_->isHexahedral() ? 8 : 1));
    for (int e = 0; e < mesh_->numElements(); ++e) {
      const ElementJacobians rest = elementJacobians(*mesh_, e, nullptr);
      restJacobians_.insert(restJacobians_.end(), rest.data(), rest.data() + rest.size());
    }
  }
}

std::vector<std::string> RunMonitor::skipped() const {
  std::vector<std::string> skipped;
  if (!settings_.energyCheck) skipped.emplace_back("energy blow-up check (switched off)");
  return skipped;
}

Eigen::VectorXd RunMonitor::state() const {
  if (!haveFreeEnergy_) return {};
  return Eigen::Vector3d(freeEnergy_, freeEnergyScale_, freeEnergyTime_);
}

void RunMonitor::setState(const Eigen::VectorXd& state) {
  if (state.size() != 0 && state.size() != 3) {
    throw Error("RunMonitor::setState: expected 0 or 3 values (the energy reference), got " +
                std::to_string(state.size()));
  }
  haveFreeEnergy_ = state.size() == 3;
  if (haveFreeEnergy_) {
    freeEnergy_ = state[0];
    freeEnergyScale_ = state[1];
    freeEnergyTime_ = state[2];
  }
}

std::string RunMonitor::describeVertex(const Integrator& integrator, int vertex) const {
  std::ostringstream out;
  out << "vertex " << vertex;
  const std::vector<RegionSummary> regions = regionSummaries(integrator);
  if (!regions.empty()) {
    const int region = regionOfVertex(integrator, vertex);
    if (region >= 0 && region < static_cast<int>(regions.size())) {
      out << " in fast region S_" << (region + 1) << " '" << regions[static_cast<std::size_t>(region)].name << "'";
    } else {
      out << " in the large-step region L";
    }
  } else {
    out << " of the mesh";
  }
  for (const auto& [name, members] : mesh_->vertexSets()) {
    if (std::binary_search(members.begin(), members.end(), vertex)) {
      out << " (vertex set '" << name << "')";
      break;
    }
  }
  return out.str();
}

NumericalErrorLocation RunMonitor::locate(const Integrator& integrator, long long frame, long long step, double time,
                                          int vertex) const {
  NumericalErrorLocation location;
  location.frame = frame;
  location.step = step;
  location.time = time;
  location.vertex = vertex;
  if (vertex >= 0) {
    location.region = regionOfVertex(integrator, vertex);
    const std::vector<RegionSummary> regions = regionSummaries(integrator);
    if (location.region >= 0 && location.region < static_cast<int>(regions.size())) {
      location.regionName = regions[static_cast<std::size_t>(location.region)].name;
    }
  }
  return location;
}

void RunMonitor::advanceFrame(Integrator& integrator, long long frame, int stepsPerFrame) {
  for (int s = 0; s < stepsPerFrame; ++s) checkedStep(integrator, frame, (frame * stepsPerFrame) + s + 1);
  checkEnergy(integrator, frame);
}

void RunMonitor::checkedStep(Integrator& integrator, long long frame, long long step) const {
  // The time the step ends at, taken before the step (which advances time() on success).
  const double stepEnd = integrator.time() + integrator.timestep();
  const std::string where =
      "frame " + std::to_string(frame) + " (step " + std::to_string(step) + ", t = " + formatNumber(stepEnd) + ")";
  try {
    integrator.step();
  } catch (const NumericalError& error) {
    // Keep what the integrator knew (DOF, vertex) and add frame, step and region.
    NumericalErrorLocation location = error.location();
    const NumericalErrorLocation here = locate(integrator, frame, step, stepEnd, location.vertex);
    location.frame = here.frame;
    location.step = here.step;
    if (!location.hasTime()) location.time = here.time;
    location.region = here.region;
    location.regionName = here.regionName;
    const std::string vertex =
        location.vertex >= 0 ? " [" + describeVertex(integrator, location.vertex) + "]" : std::string();
    throw NumericalError(where + ": " + error.what() + vertex, location);
  }
  checkState(integrator, frame, step, stepEnd, where);
}

void RunMonitor::checkState(const Integrator& integrator, long long frame, long long step, double stepEnd,
                            const std::string& where) const {
  const Eigen::VectorXd& u = integrator.displacement();
  const Eigen::VectorXd& v = integrator.velocity();
  Eigen::Index largest = 0;
  double maxDisplacement = 0.0;
  for (Eigen::Index i = 0; i < u.size(); ++i) {
    if (!std::isfinite(u[i]) || !std::isfinite(v[i])) {
      const int vertex = static_cast<int>(i / 3);
      NumericalErrorLocation location = locate(integrator, frame, step, stepEnd, vertex);
      location.dof = static_cast<int>(i);
      throw NumericalError(where + ": the state is not finite (NaN or infinity), first at " +
                               describeVertex(integrator, vertex) + "; the simulation is unstable",
                           location);
    }
    if (std::abs(u[i]) > maxDisplacement) {
      maxDisplacement = std::abs(u[i]);
      largest = i;
    }
  }
  if (maxDisplacement > blowUpDisplacement_) {
    const int vertex = static_cast<int>(largest / 3);
    NumericalErrorLocation location = locate(integrator, frame, step, stepEnd, vertex);
    location.dof = static_cast<int>(largest);
    throw NumericalError(where + ": blow-up: max |u| = " + formatNumber(maxDisplacement) + " at " +
                             describeVertex(integrator, vertex) + " exceeds " + formatNumber(settings_.blowUpFactor) +
                             " x the bounding-box diagonal (" + formatNumber(boundingBoxDiagonal_) +
                             "); the simulation is unstable",
                         location);
  }
  if (!inversionCheckModel_.empty()) checkInversion(integrator, frame, step, stepEnd, where);
}

void RunMonitor::checkInversion(const Integrator& integrator, long long frame, long long step, double stepEnd,
                                const std::string& where) const {
  const Eigen::VectorXd& u = integrator.displacement();
  const double* rest = restJacobians_.data();
  for (int e = 0; e < mesh_->numElements(); ++e) {
    const ElementJacobians deformed = elementJacobians(*mesh_, e, &u);
    // det F (at the worst corner of a hexahedron)
    const double j = (deformed.array() / Eigen::Map<const ElementJacobians>(rest, deformed.size()).array()).minCoeff();
    rest += deformed.size();
    if (j > 0.0) continue;
    const int vertex = mesh_->elementVertex(e, 0);
    NumericalErrorLocation location = locate(integrator, frame, step, stepEnd, vertex);
    throw NumericalError(where + ": element " + std::to_string(e) +
                             " (first vertex: " + describeVertex(integrator, vertex) +
                             ") inverted (J = det F = " + formatNumber(j) + ") under the " + inversionCheckModel_ +
                             " model, which has no inversion handling; " + inversionAdvice_,
                         location);
  }
}

void RunMonitor::checkEnergy(const Integrator& integrator, long long frame) {
  if (integrator.time() < energyCheckFrom_ + (0.5 * integrator.timestep())) return;
  const Eigen::VectorXd& u = integrator.displacement();
  const double mechanical = integrator.mechanicalEnergy();
  ++energyEvaluations_;
  const double penalty = contact_ ? contact_->energy(integrator.time(), u) : 0.0;
  const double energy = mechanical + penalty - constantLoad_.dot(u);
  if (!haveFreeEnergy_) {
    haveFreeEnergy_ = true;
    freeEnergy_ = energy;
    freeEnergyScale_ = std::max({mechanical + penalty, std::abs(energy), loadWorkScale_});
    freeEnergyTime_ = integrator.time();
    return;
  }
  if (energy - freeEnergy_ <= 9.0 * freeEnergyScale_) return;
  Eigen::Index largest = 0;
  u.cwiseAbs().maxCoeff(&largest);
  const int vertex = static_cast<int>(largest / 3);
  std::ostringstream out;
  out << "frame " << frame << " (t = " << formatNumber(integrator.time())
      << "): energy blow-up: with no load changing since t = " << formatNumber(energyCheckFrom_)
      << ", the total energy (kinetic + elastic" << (contact_ ? " + contact penalty" : "")
      << " - constant loads . u) grew from " << formatNumber(freeEnergy_) << " at t = " << formatNumber(freeEnergyTime_)
      << " to " << formatNumber(energy) << "; largest |u| = " << formatNumber(std::abs(u[largest])) << " at "
      << describeVertex(integrator, vertex) << "; the simulation is unstable";
  NumericalErrorLocation location = locate(integrator, frame, -1, integrator.time(), vertex);
  location.dof = static_cast<int>(largest);
  throw NumericalError(out.str(), location);
}

std::string CheckpointSchedule::describe() const {
  std::ostringstream out;
  if (everyFrames > 0) out << "every " << everyFrames << (everyFrames == 1 ? " frame" : " frames");
  if (everyFrames > 0 && everySeconds > 0.0) out << " or ";
  if (everySeconds > 0.0) out << (everyFrames > 0 ? "" : "every ") << everySeconds << " s of wall time";
  if (everyFrames <= 0 && everySeconds <= 0.0) out << "at the end only";
  return out.str();
}

std::uint32_t runFingerprint(const std::string& sceneText, const std::string& integratorName, double timestep,
                             double frameInterval, const Problem& problem) {
  std::uint32_t crc = crc32(sceneText.data(), sceneText.size());
  crc = crc32(integratorName.data(), integratorName.size(), crc);
  crc = crcOf(std::bit_cast<std::uint64_t>(timestep), crc);
  crc = crcOf(std::bit_cast<std::uint64_t>(frameInterval), crc);
  const TetMesh& mesh = problem.mesh();
  crc = crc32(mesh.restPositions().data(), sizeof(double) * static_cast<std::size_t>(mesh.restPositions().size()), crc);
  crc = crc32(mesh.connectivity().data(), sizeof(int) * static_cast<std::size_t>(mesh.connectivity().size()), crc);
  crc = crc32(mesh.elementMaterials().data(), sizeof(int) * mesh.elementMaterials().size(), crc);
  for (const Material& material : mesh.materials()) {
    crc = crcOf(std::bit_cast<std::uint64_t>(material.density), crc);
    crc = crcOf(std::bit_cast<std::uint64_t>(material.youngsModulus), crc);
    crc = crcOf(std::bit_cast<std::uint64_t>(material.poissonRatio), crc);
  }
  const std::vector<int>& fixed = problem.fixedVertices();
  return crc32(fixed.data(), sizeof(int) * fixed.size(), crc);
}

std::uint32_t problemFingerprint(const Problem& problem) {
  const TetMesh& mesh = problem.mesh();
  std::uint32_t crc =
      crc32(mesh.restPositions().data(), sizeof(double) * static_cast<std::size_t>(mesh.restPositions().size()));
  crc = crc32(mesh.connectivity().data(), sizeof(int) * static_cast<std::size_t>(mesh.connectivity().size()), crc);
  const std::vector<int>& fixed = problem.fixedVertices();
  return crc32(fixed.data(), sizeof(int) * fixed.size(), crc);
}

SimulationCheckpoint captureCheckpoint(const Integrator& integrator, std::int64_t frames, std::uint32_t fingerprint,
                                       const RunMonitor* monitor) {
  SimulationCheckpoint checkpoint;
  checkpoint.frames = frames;
  checkpoint.time = integrator.time();
  checkpoint.fingerprint = fingerprint;
  checkpoint.integrator = integrator.name();
  checkpoint.displacement = integrator.displacement();
  checkpoint.velocity = integrator.velocity();
  checkpoint.internalState = integrator.internalState();
  if (monitor != nullptr) checkpoint.monitorState = monitor->state();
  return checkpoint;
}

std::vector<std::string> runDifferences(const SimulationCheckpoint& checkpoint, const SimulationFileHeader& stored,
                                        const Integrator& integrator, const SimulationFileHeader& header,
                                        bool fingerprintDiffers) {
  return runDifferences(checkpoint, stored, integrator.name(), integrator.displacement().size(), header,
                        fingerprintDiffers);
}

std::vector<std::string> runDifferences(const SimulationCheckpoint& checkpoint, const SimulationFileHeader& stored,
                                        const std::string& integratorName, std::int64_t numDofs,
                                        const SimulationFileHeader& header, bool fingerprintDiffers) {
  std::vector<std::string> differences;
  const auto differ = [](double a, double b) {
    return std::bit_cast<std::uint64_t>(a) != std::bit_cast<std::uint64_t>(b);
  };
  const auto number = [](double value) { return formatNumber(value, 12); };
  if (checkpoint.integrator != integratorName) {
    differences.push_back("integrator (" + checkpoint.integrator + " there, " + integratorName + " here)");
  }
  if (differ(stored.timestep, header.timestep)) {
    differences.push_back("timestep (" + number(stored.timestep) + " there, " + number(header.timestep) + " here)");
  }
  if (differ(stored.frameInterval, header.frameInterval)) {
    differences.push_back("frame interval 1 / frames.rate (" + number(stored.frameInterval) + " there, " +
                          number(header.frameInterval) + " here)");
  }
  if (stored.numVertices != header.numVertices || checkpoint.displacement.size() != numDofs) {
    differences.push_back("mesh vertex count (" + std::to_string(stored.numVertices) + " there, " +
                          std::to_string(header.numVertices) + " here)");
  }
  if (stored.hasVelocities != header.hasVelocities) {
    differences.push_back(std::string("output.velocities (") + (stored.hasVelocities ? "true" : "false") + " there, " +
                          (header.hasVelocities ? "true" : "false") + " here)");
  }
  if (stored.hasContactForces != header.hasContactForces) {
    differences.push_back(std::string("output.contactForces (") + (stored.hasContactForces ? "true" : "false") +
                          " there, " + (header.hasContactForces ? "true" : "false") + " here)");
  }
  if (fingerprintDiffers && differences.empty()) {
    differences.emplace_back(
        "the scene file or the mesh it builds (a key other than frames.count and output, or the mesh file's vertices, "
        "elements, materials or fixed vertices)");
  }
  return differences;
}

SimulationCheckpoint checkpointToResume(const std::filesystem::path& output, const SimulationFileHeader& header,
                                        std::uint32_t fingerprint, std::int64_t requestedFrames,
                                        const std::string& integratorName, std::int64_t numDofs) {
  namespace fs = std::filesystem;
  const fs::path checkpointFile = checkpointPathFor(output);
  const std::string restart = "; run without --resume to start over";
  if (!fs::exists(output)) {
    throw Error("cannot resume: " + output.string() + " does not exist" + restart);
  }
  if (!fs::exists(checkpointFile)) {
    throw Error("cannot resume: no checkpoint " + checkpointFile.string() + " next to " + output.string() + restart);
  }
  SimulationCheckpoint checkpoint;
  try {
    checkpoint = readCheckpoint(checkpointFile);
  } catch (const Error& error) {
    // A damaged checkpoint leaves the output as it is; the message says what is wrong.
    throw Error("cannot resume: " + std::string(error.what()) + "; " + output.string() + " is left as it is" + restart);
  }
  SimulationReader reader(output);
  const SimulationFileHeader& stored = reader.header();
  const std::vector<std::string> differences =
      runDifferences(checkpoint, stored, integratorName, numDofs, header, checkpoint.fingerprint != fingerprint);
  if (!differences.empty()) {
    std::string list;
    for (const std::string& difference : differences) list += (list.empty() ? "" : "; ") + difference;
    throw Error("cannot resume: " + output.string() + " and " + checkpointFile.string() +
                " were written by a different run: " + list + restart);
  }
  if (checkpoint.frames > requestedFrames) {
    throw Error("cannot resume: " + output.string() + " already has " + std::to_string(checkpoint.frames) +
                " finished frames, more than the " + std::to_string(requestedFrames) +
                " requested (frames.count or --frames)");
  }
  if (reader.numFrames() < checkpoint.frames) {
    throw Error("cannot resume: " + output.string() + " holds " + std::to_string(reader.numFrames()) +
                " complete frames but its checkpoint says " + std::to_string(checkpoint.frames) + restart);
  }
  if (checkpoint.frames > 0) {
    // The last kept record must hold exactly the checkpoint's state.
    const SimulationFrame last = reader.readFrame(checkpoint.frames - 1);
    const auto bytes = static_cast<std::size_t>(last.displacement.size()) * sizeof(double);
    if (std::bit_cast<std::uint64_t>(last.time) != std::bit_cast<std::uint64_t>(checkpoint.time) ||
        std::memcmp(last.displacement.data(), checkpoint.displacement.data(), bytes) != 0) {
      throw Error("cannot resume: frame " + std::to_string(checkpoint.frames - 1) + " of " + output.string() +
                  " differs from the state in " + checkpointFile.string() + restart);
    }
  }
  return checkpoint;
}

std::int64_t resumeFromCheckpoint(const std::filesystem::path& output, const SimulationFileHeader& header,
                                  std::uint32_t fingerprint, std::int64_t requestedFrames, Integrator& integrator,
                                  RunMonitor* monitor) {
  const SimulationCheckpoint checkpoint = checkpointToResume(output, header, fingerprint, requestedFrames,
                                                             integrator.name(), integrator.displacement().size());
  integrator.setState(checkpoint.displacement, checkpoint.velocity, checkpoint.time);
  integrator.setInternalState(checkpoint.internalState);
  if (monitor != nullptr) monitor->setState(checkpoint.monitorState);
  return checkpoint.frames;
}

}  // namespace asyncfem
