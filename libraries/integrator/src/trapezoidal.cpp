// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/stepFormula.hpp>
#include <asyncfem/integrator/trapezoidal.hpp>
#include <string>

#include "detail/freeSystem.hpp"

namespace asyncfem {

using detail::TimeInto;

Trapezoidal::Trapezoidal(DynamicSystem system, double timestep, const IntegratorOptions& options)
    : Integrator(std::move(system), timestep), options_(options) {
  if (options_.maxIterations < 1) {
    throw ValidationError("trapezoidal needs maxIterations >= 1 (got " + std::to_string(options_.maxIterations) + ")");
  }
  linear_ = system_.forceModel->isLinear();
  {
    TimeInto timer(stats_.assemblySeconds);
    free_ = std::make_unique<detail::FreeSystem>(system_, options_.solver);
  }
  massSolver_ = std::make_unique<detail::FreeMassSolver>();
  massSolver_->setup(free_->mass, options_.solver, stats_);
  if (!system_.damped()) stats_.skipped.emplace_back("damping matrix (alpha = beta = 0)");
  if (linear_) {
    Eigen::VectorXd rest = Eigen::VectorXd::Zero(system_.numDofs());
    free_->evaluateForcesAndTangent(system_, rest, free_->stiffness, stats_);
    stats_.skipped.emplace_back("refactorization (constant system matrix)");
    assembleAndFactor();
  }
}

Trapezoidal::~Trapezoidal() = default;

RunReport Trapezoidal::report() const {
  RunReport report;
  report.factorNonZeros = free_->solver().stats().factorNonZeros;
  return report;
}

void Trapezoidal::setTimestep(double timestep) {
  const double previous = timestep_;
  Integrator::setTimestep(timestep);
  if (timestep != previous) factorizationStale_ = true;
}

void Trapezoidal::assembleAndFactor() {
  // M + h/2 D + h^2/4 K (Eq. A1t)
  const stepFormula::MatrixWeights weights =
      stepFormula::trapezoidal::systemMatrix(timestep_, system_.rayleighMass, system_.rayleighStiffness);
  free_->assemble({weights.mass, weights.stiffness}, {&free_->mass, &free_->stiffness}, stats_);
  free_->factorize(stats_);
  factorizationStale_ = false;
}

Eigen::VectorXd Trapezoidal::internalState() const {
  if (accelerationStale_) return {};
  return acceleration_;
}

void Trapezoidal::setInternalState(const Eigen::VectorXd& state) {
  if (state.size() == 0) {
    accelerationStale_ = true;
    return;
  }
  if (state.size() != system_.numDofs() || !state.allFinite()) {
    throw Error("trapezoidal: setInternalState: expected the acceleration, " + std::to_string(system_.numDofs()) +
                " finite values (got " + std::to_string(state.size()) + ")");
  }
  acceleration_ = state;
  zeroFixed(acceleration_);
  accelerationStale_ = false;
}

const Eigen::VectorXd& Trapezoidal::acceleration() {
  if (accelerationStale_) computeAcceleration();
  return acceleration_;
}

void Trapezoidal::computeAcceleration() {
  const FreeDofs& dofs = system_.freeDofs;
  detail::restrictTo(dofs, displacement_, u_);
  detail::restrictTo(dofs, velocity_, v_);
  evaluateExternalForce(time_, fullForce_);
  detail::restrictTo(dofs, fullForce_, rhs_);
  // M a_0 = f_ext(t) - f_int(u) - D v with D = alpha M + beta K(u)
  if (linear_) {
    TimeInto timer(stats_.forceSeconds);
    rhs_.noalias() -= free_->stiffness * (u_ + system_.rayleighStiffness * v_);
  } else {
    free_->evaluateForcesAndTangent(system_, displacement_, free_->stiffness, stats_);
    detail::restrictTo(dofs, free_->fullForces(), internal_);
    TimeInto timer(stats_.forceSeconds);
    rhs_ -= internal_;
    if (system_.rayleighStiffness != 0.0) rhs_.noalias() -= system_.rayleighStiffness * (free_->stiffness * v_);
  }
  if (system_.rayleighMass != 0.0) rhs_.noalias() -= system_.rayleighMass * (free_->mass * v_);
  massSolver_->solve(rhs_, a_, stats_);
  detail::expandTo(dofs, a_, acceleration_);
  accelerationStale_ = false;
}

void Trapezoidal::step() {
  free_->stepTime = stepEndTime();
  const double h = timestep_;
  const FreeDofs& dofs = system_.freeDofs;
  if (accelerationStale_) computeAcceleration();
  detail::restrictTo(dofs, displacement_, u_);
  detail::restrictTo(dofs, velocity_, v_);
  detail::restrictTo(dofs, acceleration_, a_);
  if (system_.externalForce) {
    evaluateExternalForce(stepEndTime(), fullForce_);
    detail::restrictTo(dofs, fullForce_, force_);
  } else {
    force_.setZero(u_.size());
  }
  linearizedRightHandSide();
  const double rhsNorm = rhs_.norm();
  free_->solve(rhs_, newA_, stats_);
  lastRelativeResidual_ = -1.0;
  lastIterations_ = !linear_ && options_.maxIterations > 1 ? newtonIterations(rhsNorm) : 1;

  // u_{k+1} = u + h v + h^2/4 (a + a_new), v_{k+1} = v + h/2 (a + a_new)
  work_ = a_ + newA_;
  u_ += h * v_ + stepFormula::trapezoidal::displacementWeight(h) * work_;
  v_ += stepFormula::trapezoidal::velocityWeight(h) * work_;
  detail::expandTo(dofs, u_, fullU_);
  detail::expandTo(dofs, v_, fullV_);
  detail::expandTo(dofs, newA_, fullA_);
  commitStep(fullU_, fullV_);
  acceleration_.swap(fullA_);
}

// b = f_ext - f_int(u) - K (beta (v + h/2 a) + h v + h^2/4 a) - alpha M (v + h/2 a) (Eq. A1t),
// with K and f_int at u_k (refactored for nonlinear models).
void Trapezoidal::linearizedRightHandSide() {
  const double h = timestep_;
  const double alpha = system_.rayleighMass;
  const double beta = system_.rayleighStiffness;
  detail::FreeSystem& free = *free_;
  const stepFormula::RightHandSide recipe = stepFormula::trapezoidal::rightHandSide(h, beta);
  if (linear_) {
    if (factorizationStale_) assembleAndFactor();
    TimeInto timer(stats_.forceSeconds);
    rhs_ = force_;
    work_ = u_ + recipe.velocityStiffness * v_ + recipe.accelerationStiffness * a_;
    rhs_.noalias() -= free.stiffness * work_;
  } else {
    free.evaluateForcesAndTangent(system_, displacement_, free.stiffness, stats_);
    detail::restrictTo(system_.freeDofs, free.fullForces(), internal_);
    assembleAndFactor();
    TimeInto timer(stats_.forceSeconds);
    rhs_ = force_ - internal_;
    work_ = recipe.velocityStiffness * v_ + recipe.accelerationStiffness * a_;
    rhs_.noalias() -= free.stiffness * work_;
  }
  if (alpha != 0.0) {
    TimeInto timer(stats_.forceSeconds);
    work_ = v_ + recipe.accelerationMass * a_;
    rhs_.noalias() -= alpha * (free.mass * work_);
  }
}

int Trapezoidal::newtonIterations(double rhsNorm) {
  const double h = timestep_;
  const double alpha = system_.rayleighMass;
  const double beta = system_.rayleighStiffness;
  detail::FreeSystem& free = *free_;
  const double scale = rhsNorm > 0.0 ? rhsNorm : 1.0;
  Eigen::VectorXd newVelocity, newDisplacement, residual, correction;
  for (int iterations = 1;; ++iterations) {
    newVelocity = v_ + (0.5 * h) * (a_ + newA_);
    newDisplacement = u_ + h * v_ + (0.25 * h * h) * (a_ + newA_);
    detail::expandTo(system_.freeDofs, newDisplacement, fullU_);
    const bool mayIterate = iterations < options_.maxIterations;
    if (mayIterate) {
      free.evaluateForcesAndTangent(system_, fullU_, free.iterateStiffness, stats_);
    } else {
      free.evaluateForces(system_, fullU_, stats_);
    }
    detail::restrictTo(system_.freeDofs, free.fullForces(), internal_);
    {
      // R = M a + D v_{k+1} + f_int(u_{k+1}) - f_ext,  D = alpha M + beta K(u_k)
      TimeInto timer(stats_.forceSeconds);
      residual = free.mass * newA_ + internal_ - force_;
      if (alpha != 0.0) residual.noalias() += alpha * (free.mass * newVelocity);
      if (beta != 0.0) residual.noalias() += beta * (free.stiffness * newVelocity);
    }
    lastRelativeResidual_ = residual.norm() / scale;
    if (lastRelativeResidual_ <= options_.tolerance) return iterations;
    if (!mayIterate) {
      detail::checkNewtonDiverged(name(), lastRelativeResidual_, iterations, residual, system_.freeDofs, stepEndTime());
      return iterations;
    }
    // J = (1 + h alpha/2) M + h beta/2 K(u_k) + h^2/4 K(u_{k+1}^{(i)})
    free.assemble({1.0 + (0.5 * h * alpha), 0.5 * h * beta, 0.25 * h * h},
                  {&free.mass, &free.stiffness, &free.iterateStiffness}, stats_);
    free.factorize(stats_);
    free.solve(-residual, correction, stats_);
    newA_ += correction;
  }
}

}  // namespace asyncfem
