// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/petscBackend/problemSettings.hpp>
#include <asyncfem/problem/loads.hpp>
#include <memory>

namespace asyncfem {

namespace {

PetscIntegratorKind integratorKind(const std::string& name) {
  if (name == "backward-euler") return PetscIntegratorKind::backwardEuler;
  if (name == "trapezoidal") return PetscIntegratorKind::trapezoidal;
  throw ValidationError("integrator \"" + name +
                        "\" is not available on the PETSc backend (it runs backward-euler and trapezoidal)");
}

PetscForceModelKind forceModelKind(const ProblemSettings& settings) {
  if (settings.forceModel == ForceModelType::linear) return PetscForceModelKind::linear;
  if (settings.forceModel == ForceModelType::corotational && settings.tangent == TangentKind::simple) {
    return PetscForceModelKind::corotational;
  }
  throw ValidationError("forceModel: only linear and corotational (simple tangent) are available on the PETSc backend");
}

}  // namespace

PetscSimulationSettings petscSettingsForProblem(const Problem& problem, const std::string& integratorName,
                                                double timestep) {
  if (problem.hasContact()) {
    throw ValidationError("contact: not supported on the PETSc backend (its forces depend on the state)");
  }
  const ProblemSettings& physics = problem.settings();
  PetscSimulationSettings settings;
  settings.integrator = integratorKind(integratorName);
  settings.forceModel = forceModelKind(physics);
  settings.massType = physics.mass;
  settings.timestep = timestep;
  settings.rayleighMass = physics.rayleighAlpha;
  settings.rayleighStiffness = physics.rayleighBeta;
  settings.fixedVertices = problem.heldVertices();
  settings.gravity = physics.gravity;
  // The windowed loads through Loads::addTo (gravity is the backend's own, settings.gravity).
  auto timeLoads = std::make_shared<Loads>();
  for (const VertexLoad& load : problem.windows()) timeLoads->addWindow(load);
  if (!timeLoads->empty()) {
    const Eigen::VectorXd rest = Eigen::VectorXd::Zero(problem.numDofs());  // loads of time only
    settings.timeDependentForce = [timeLoads, rest](double time, Eigen::VectorXd& forces) {
      timeLoads->addTo(time, rest, rest, forces);
    };
  }
  return settings;
}

}  // namespace asyncfem
