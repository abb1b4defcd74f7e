// SPDX-License-Identifier: BSD-3-Clause
#include "detail/explicitCore.hpp"

#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/stableTimestep.hpp>
#include <limits>
#include <sstream>

namespace asyncfem::detail {

ExplicitCore::ExplicitCore(const DynamicSystem& system, const IntegratorOptions& options, IntegratorStats& stats)
    : free_(system, options.solver), linear_(system.forceModel->isLinear()), force_(options.force) {
  // K at rest: the constant K of linear models, the tangent at rest of nonlinear ones
  // (what the stable-timestep estimate uses).
  const Eigen::VectorXd rest = Eigen::VectorXd::Zero(system.numDofs());
  free_.evaluateForcesAndTangent(system, rest, free_.stiffness, stats);
  massSolver_.setup(free_.mass, options.solver, stats);
  if (massSolver_.diagonal()) stats.skipped.emplace_back("mass factorization (diagonal mass matrix)");
  if (!system.damped()) stats.skipped.emplace_back("damping matrix (alpha = beta = 0)");
  maxFrequency_ = options.maxFrequency > 0.0 ? options.maxFrequency : estimateMaxFrequency(free_.stiffness, free_.mass);
}

double ExplicitCore::stableTimestep() const {
  return maxFrequency_ > 0.0 ? stableTimestepFromFrequency(maxFrequency_) : std::numeric_limits<double>::infinity();
}

void ExplicitCore::checkTimestep(double timestep, const std::string& methodName) const {
  const double limit = stableTimestep();
  if (timestep > limit && !force_) {
    std::ostringstream message;
    message.precision(6);
    message << "timestep " << timestep << " exceeds the estimated stable timestep " << limit << " of " << methodName
            << " (2 / omega_max, omega_max = " << maxFrequency_
            << " rad/s, undamped bound); reduce the timestep to at most " << limit
            << ", or set the option force to run anyway (scene key integrator.options.force: true; "
               "IntegratorOptions::force)";
    throw TimestepError(message.str());
  }
}

void ExplicitCore::acceleration(const DynamicSystem& system, double time, const Eigen::VectorXd& fullDisplacement,
                                const Eigen::VectorXd& fullVelocity, const Eigen::VectorXd& dampingVelocity,
                                Eigen::VectorXd& acceleration, IntegratorStats& stats) {
  const FreeDofs& dofs = system.freeDofs;
  if (system.externalForce) {
    fullForce_.setZero(system.numDofs());
    system.externalForce(time, fullDisplacement, fullVelocity, fullForce_);
    restrictTo(dofs, fullForce_, rhs_);
  } else {
    rhs_.setZero(dofs.numFree());
  }
  const double alpha = system.rayleighMass;
  const double beta = system.rayleighStiffness;
  if (linear_) {
    TimeInto timer(stats.forceSeconds);
    restrictTo(dofs, fullDisplacement, u_);
    rhs_.noalias() -= free_.stiffness * u_;
    if (beta != 0.0) rhs_.noalias() -= beta * (free_.stiffness * dampingVelocity);
  } else {
    // D = alpha M + beta K(u): the tangent is only needed for stiffness damping.
    if (beta != 0.0) {
      free_.evaluateForcesAndTangent(system, fullDisplacement, free_.stiffness, stats);
    } else {
      free_.evaluateForces(system, fullDisplacement, stats);
    }
    restrictTo(dofs, free_.fullForces(), internal_);
    TimeInto timer(stats.forceSeconds);
    rhs_ -= internal_;
    if (beta != 0.0) rhs_.noalias() -= beta * (free_.stiffness * dampingVelocity);
  }
  if (alpha != 0.0) rhs_.noalias() -= alpha * (free_.mass * dampingVelocity);
  massSolver_.solve(rhs_, acceleration, stats);
}

}  // namespace asyncfem::detail
