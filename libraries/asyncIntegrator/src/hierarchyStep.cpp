// SPDX-License-Identifier: BSD-3-Clause
// AsyncBackwardEuler's hierarchy solve: partitions whose regions touch or nest, or any
// partition with AsyncSolveMethod::hierarchy (docs/asynchronous-integrator.md, "Nested and
// touching regions", Eqs. N1-N12; the step system itself is detail::HierarchySystem).
#include <algorithm>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <cmath>
#include <cstdio>
#include <string>

#include "asyncBackwardEulerImpl.hpp"

namespace asyncfem {

// The step system's layout and checks (element tangents, element masses); linear forces
// also build and factor it now, so the first step costs a steady one (nonlinear forces
// rebuild it at every large step, at the step's start state).
void AsyncBackwardEuler::setUpHierarchy() {
  Impl& d = *impl_;
  d.regions.clear();
  d.schurBlocks.clear();
  try {
    d.hierarchy = std::make_unique<detail::HierarchySystem>(*system_.mesh, system_, partition_, options_.nestedSolve);
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
  d.build.factorsCurrent = false;
  if (d.model.linear) {
    d.hierarchy->build(displacement_, timestep(), stats_);
    d.build.factorsCurrent = true;
  }
}

void AsyncBackwardEuler::stepHierarchy() {
  Impl& d = *impl_;
  Stopwatch whole;
  double rebuild = 0.0;
  if (!d.build.factorsCurrent) {
    Stopwatch watch;
    d.hierarchy->build(displacement_, timestep(), stats_);
    d.build.factorsCurrent = d.model.linear;
    rebuild = watch.stop();
    if (runStats_.steps == 0 && !d.model.linear) {
      runStats_.setupSeconds += rebuild;
    } else {
      runStats_.rebuildSeconds += rebuild;
      ++runStats_.rebuilds;
    }
  }
  Stopwatch forces;
  d.internalForce.resize(displacement_.size());
  system_.forceModel->internalForces(displacement_, d.internalForce);
  // f_ext where some DOF's step ends (Eq. N3): t_0 + k hL / units, the last one at t_1.
  if (system_.externalForce) {
    const double t0 = time(), t1 = stepEndTime();
    const long long units = partition_.units();
    for (const long long unit : d.hierarchy->stepEndUnits()) {
      evaluateExternalForce(
          unit == units ? t1 : t0 + static_cast<double>(unit) * (timestep() / static_cast<double>(units)),
          d.unitForces[unit]);
    }
  }
  stats_.forceSeconds += forces.stop();
  d.hierarchy->step(displacement_, velocity_, d.internalForce, d.unitForces, d.newU, d.newV, stats_);
  if (implicitContact()) solveHierarchyContact();
  commitStep(d.newU, d.newV);
  ++runStats_.steps;
  ++stepsKept_;
  runStats_.stepSeconds += whole.stop() - rebuild;
}

// Implicit contact (Eqs. N13-N14): Newton on the step system from step()'s solution, until
// the residual is at most contactTolerance or contactIterations solves are spent.
void AsyncBackwardEuler::solveHierarchyContact() {
  Impl& d = *impl_;
  const double t0 = time(), t1 = stepEndTime(), hL = timestep();
  const long long units = partition_.units();
  detail::HierarchySystem::StateForce force;
  force.force = system_.externalForce;
  force.jacobian = system_.externalForceJacobian;
  force.timeOf = [t0, t1, hL, units](long long unit) {
    return unit == units ? t1 : t0 + static_cast<double>(unit) * (hL / static_cast<double>(units));
  };
  const detail::HierarchySystem::StateForceSolve result =
      d.hierarchy->solveWithStateForce(displacement_, velocity_, d.internalForce, force, options_.contactTolerance,
                                       options_.contactIterations, d.newU, d.newV, stats_);
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

void AsyncBackwardEuler::hierarchyReportLines(std::vector<std::string>& lines) const {
  const Impl& d = *impl_;
  std::string levels;
  for (const int count : partition_.levels()) levels += (levels.empty() ? "" : ", ") + std::to_string(count);
  char line[256];
  std::snprintf(line, sizeof line,
                "nested async regions: steps per large step %s; step system %lld unknowns; set-up %.3f s",
                levels.c_str(), d.hierarchy->unknowns(), runStats_.setupSeconds);
  lines.emplace_back(line);
  lines.push_back("nested async regions: " + d.hierarchy->solveDescription());
  std::snprintf(line, sizeof(line), "async steady large step %.3f ms over %lld steps; rebuilds %lld (%.3f s)",
                1000.0 * runStats_.meanStepSeconds(), runStats_.steps, runStats_.rebuilds, runStats_.rebuildSeconds);
  lines.emplace_back(line);
  const AsyncRunStats& r = runStats_;
  if (r.contactSteps == 0) return;
  std::snprintf(line, sizeof(line),
                "async implicit contact: %lld solves over %lld steps (%.2f per step; Newton on the step system, "
                "Eqs. N13-N14); %lld steps stopped at %d solves unconverged (largest relative residual %.2e); the "
                "step system factored %lld times with contact blocks",
                r.contactIterations, r.contactSteps,
                static_cast<double>(r.contactIterations) / static_cast<double>(r.contactSteps),
                r.unconvergedContactSteps, options_.contactIterations, r.largestContactResidual,
                r.contactStepSystemFactorizations);
  lines.emplace_back(line);
}

const AsyncBackwardEuler::Impl& AsyncBackwardEuler::hierarchyImpl(const char* what) const {
  if (impl_->solver != AsyncStepSolver::hierarchy) {
    throw Error(std::string("async integrator: ") + what +
                " is defined for the hierarchy solve only (this partition "
                "runs the " +
                toString(impl_->solver) + " solver)");
  }
  return *impl_;
}

AsyncStepSolver AsyncBackwardEuler::stepSolver() const { return impl_->solver; }
long long AsyncBackwardEuler::stepSystemUnknowns() const {
  return hierarchyImpl("stepSystemUnknowns").hierarchy->unknowns();
}
bool AsyncBackwardEuler::hierarchyByLevel() const { return hierarchyImpl("hierarchyByLevel").hierarchy->structured(); }
Eigen::VectorXd AsyncBackwardEuler::stepVelocities(int freeDof) const {
  return hierarchyImpl("stepVelocities").hierarchy->velocities(freeDof);
}
Eigen::VectorXd AsyncBackwardEuler::stepDisplacements(int freeDof) const {
  return hierarchyImpl("stepDisplacements").hierarchy->displacements(freeDof);
}

}  // namespace asyncfem
