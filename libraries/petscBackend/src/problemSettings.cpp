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

}  // namespace

PetscForceModelKind petscForceModelKind(ForceModelType type) {
  switch (type) {
    case ForceModelType::linear:
      return PetscForceModelKind::linear;
    case ForceModelType::corotational:
      return PetscForceModelKind::corotational;
    case ForceModelType::stvk:
      return PetscForceModelKind::stvk;
    case ForceModelType::neoHookean:
      return PetscForceModelKind::neoHookean;
    case ForceModelType::mooneyRivlin:
      return PetscForceModelKind::mooneyRivlin;
  }
  throw ValidationError("forceModel \"" + toString(type) + "\" is not available on the PETSc backend");
}

PetscNewtonSettings petscNewtonSettings(const IntegratorOptions& options) {
  if (options.rayleighStiffnessAtIterate) {
    throw ValidationError(
        "integrator.options.rayleighStiffnessAtIterate: not supported on the PETSc backend (Rayleigh damping keeps "
        "K(u_k) of the step start)");
  }
  PetscNewtonSettings newton;
  newton.maxIterations = options.maxIterations;
  newton.tolerance = options.tolerance;
  newton.lineSearch = options.lineSearch;
  return newton;
}

PetscSimulationSettings petscSettingsForProblem(const Problem& problem, const std::string& integratorName,
                                                double timestep, const IntegratorOptions& options) {
  if (problem.hasContact()) {
    throw ValidationError("contact: not supported on the PETSc backend (its forces depend on the state)");
  }
  const ProblemSettings& physics = problem.settings();
  PetscSimulationSettings settings;
  settings.integrator = integratorKind(integratorName);
  settings.forceModel = petscForceModelKind(physics.forceModel);
  settings.tangent = physics.tangent;
  settings.hyperelastic = physics.hyperelastic;
  settings.newton = petscNewtonSettings(options);
  if (settings.newton.maxIterations > 1 && settings.integrator == PetscIntegratorKind::trapezoidal &&
      settings.forceModel != PetscForceModelKind::linear) {
    throw ValidationError(
        "integrator.options.maxIterations: Newton iterations run with backward-euler only on the PETSc backend "
        "(the trapezoidal rule takes the linearized step, maxIterations 1)");
  }
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
