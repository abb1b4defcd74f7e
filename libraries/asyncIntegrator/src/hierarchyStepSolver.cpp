// SPDX-License-Identifier: BSD-3-Clause
// The hierarchy step solver: partitions whose regions touch or nest, or any partition with
// AsyncSolveMethod::hierarchy (docs/asynchronous-integrator.md, "Nested and touching
// regions", Eqs. N1-N14; the step system itself is detail::HierarchySystem).
#include "hierarchyStepSolver.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <cmath>
#include <cstdio>
#include <string>

namespace asyncfem::detail {

HierarchyStepSolver::HierarchyStepSolver(const StepContext& context)
    : StepSolver(context), linear_(context.system.forceModel->isLinear()) {}

// The step system's layout and checks (element tangents, element masses); linear forces
// also build and factor it now, so the first step costs a steady one (nonlinear forces
// rebuild it at every large step, at the step's start state).
void HierarchyStepSolver::setUp() {
  try {
    stepSystem_ = std::make_unique<HierarchySystem>(*system_.mesh, system_, partition_, options_.nestedSolve);
  } catch (const AsyncOptionError&) {
    throw;
  } catch (const ValidationError& e) {
    // The structured solve asked for by name: the option is what the partition refuses.
    if (options_.nestedSolve != NestedSolve::structured) throw;
    throw AsyncOptionError("nestedSolve", e.what());
  }
  runStats_.fastDofs = runStats_.interfaceDofs = 0;
  for (int i = 0; i < partition_.numRegions(); ++i) {
    runStats_.fastDofs += static_cast<int>(partition_.regionDofs(i).size());
    runStats_.interfaceDofs += static_cast<int>(partition_.interfaceDofs(i).size());
  }
  runStats_.largeDofs = static_cast<int>(partition_.largeDofs().size());
  factorsCurrent_ = false;
  if (linear_) {
    stepSystem_->build(displacement_, timestep(), stats_);
    factorsCurrent_ = true;
  }
}

StepEnd HierarchyStepSolver::step(double t0, double t1) {
  if (!factorsCurrent_) {
    Stopwatch watch;
    stepSystem_->build(displacement_, timestep(), stats_);
    factorsCurrent_ = linear_;
    const double rebuild = watch.stop();
    if (runStats_.steps == 0 && !linear_) {
      runStats_.setupSeconds += rebuild;
    } else {
      runStats_.rebuildSeconds += rebuild;
      ++runStats_.rebuilds;
    }
  }
  Stopwatch forces;
  internalForce_.resize(displacement_.size());
  system_.forceModel->internalForces(displacement_, internalForce_);
  // f_ext where some DOF's step ends (Eq. N3): t_0 + k hL / units, the last one at t_1.
  if (system_.externalForce) {
    const long long units = partition_.units();
    for (const long long unit : stepSystem_->stepEndUnits()) {
      Eigen::VectorXd& f = unitForces_[unit];
      f.setZero(system_.numDofs());
      system_.externalForce(
          unit == units ? t1 : t0 + static_cast<double>(unit) * (timestep() / static_cast<double>(units)),
          displacement_, velocity_, f);
    }
  }
  stats_.forceSeconds += forces.stop();
  stepSystem_->step(displacement_, velocity_, internalForce_, unitForces_, newU_, newV_, stats_);
  if (implicitContact()) solveContact(t0, t1);
  return {newU_, newV_};
}

// Implicit contact (Eqs. N13-N14): Newton on the step system from step()'s solution, until
// the residual is at most contactTolerance or contactIterations solves are spent.
void HierarchyStepSolver::solveContact(double t0, double t1) {
  const double hL = timestep();
  const long long units = partition_.units();
  HierarchySystem::StateForce force;
  force.force = system_.externalForce;
  force.jacobian = system_.externalForceJacobian;
  force.timeOf = [t0, t1, hL, units](long long unit) {
    return unit == units ? t1 : t0 + static_cast<double>(unit) * (hL / static_cast<double>(units));
  };
  const HierarchySystem::StateForceSolve result =
      stepSystem_->solveWithStateForce(displacement_, velocity_, internalForce_, force, options_.contact.tolerance,
                                       options_.contact.iterations, newU_, newV_, stats_);
  ++runStats_.contactSteps;
  runStats_.contactIterations += result.solves;
  runStats_.contactStepSystemFactorizations += result.factorizations;
  const std::string where = result.worstDof >= 0 ? " (vertex " + std::to_string(result.worstDof / 3) + ")" : "";
  if (!std::isfinite(result.residual)) {
    throw NumericalError("async integrator: the step to t = " + std::to_string(t1) +
                         " has a non-finite state or external force with implicit contact" + where);
  }
  if (result.converged) return;
  if (result.residual > 1.0) {
    throw NumericalError(
        "async integrator: implicit contact did not converge in the step to t = " + std::to_string(t1) +
        ": relative residual " + std::to_string(result.residual) + " after " + std::to_string(result.solves) +
        " solves, largest at" + where + ": its contact springs may be too stiff for its step (raise its ratio)");
  }
  ++runStats_.unconvergedContactSteps;
  runStats_.largestContactResidual = std::max(runStats_.largestContactResidual, result.residual);
}

void HierarchyStepSolver::reportLines(std::vector<std::string>& lines) const {
  std::string levels;
  for (const int count : partition_.levels()) levels += (levels.empty() ? "" : ", ") + std::to_string(count);
  char line[256];
  std::snprintf(line, sizeof line,
                "nested async regions: steps per large step %s; step system %lld unknowns; set-up %.3f s",
                levels.c_str(), stepSystem_->unknowns(), runStats_.setupSeconds);
  lines.emplace_back(line);
  lines.push_back("nested async regions: " + stepSystem_->solveDescription());
  lines.push_back(steadyStepLine(runStats_));
  const AsyncRunStats& r = runStats_;
  if (r.contactSteps == 0) return;
  lines.push_back(contactLine(
      r, "; Newton on the step system, Eqs. N13-N14", "solves", options_.contact.iterations,
      "the step system factored " + std::to_string(r.contactStepSystemFactorizations) + " times with contact blocks"));
}

}  // namespace asyncfem::detail
