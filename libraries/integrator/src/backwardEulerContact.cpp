// SPDX-License-Identifier: BSD-3-Clause
// Backward Euler's implicit-contact iteration for linear models: Newton on the step with the
// contact Jacobian, the residual's scale, and when a step retreats or stops
// (docs/scene-format.md, "contact.implicit").
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>

#include "detail/freeSystem.hpp"
#include "detail/keptFactor.hpp"
#include "detail/lowRankContact.hpp"

namespace asyncfem {

using detail::TimeInto;

int BackwardEuler::linearContactIterations(double rhsNorm, bool solvedWithContact,
                                           const Eigen::VectorXd* startInternal) {
  // Newton on R(dv) = M dv - h ( f_ext(u_{k+1}, v_{k+1}) - f_int - D v_{k+1} ) with the elastic
  // force linear in the step: K u_{k+1} (linear model, K constant) or, for the linearized
  // step of a nonlinear one, f_int(u_k) + K(u_k) (u_{k+1} - u_k) (startInternal). Only the
  // contact force and its blocks change between iterates.
  const double h = timestep_;
  const int allowed = std::max(options_.maxIterations, options_.contactIterations);
  const double scale = contactResidualScale(rhsNorm);
  Eigen::VectorXd newVelocity, newDisplacement, internal, residual, correction;
  for (int iterations = 1;; ++iterations) {
    newVelocity = v_ + dv_;
    newDisplacement = u_ + h * newVelocity;
    detail::expandTo(system_.freeDofs, newDisplacement, fullU_);
    detail::expandTo(system_.freeDofs, newVelocity, fullV_);
    evaluateImplicitExternalForce(fullU_, fullV_, force_);
    // No contact in the solve nor at its result: the force did not depend on the state.
    if (!solvedWithContact && contact_.empty()) return iterations;
    {
      TimeInto timer(stats_.forceSeconds);
      if (startInternal == nullptr) {
        internal.noalias() = free_->stiffness * newDisplacement;
      } else {
        work_ = newDisplacement - u_;
        internal = *startInternal;
        internal.noalias() += free_->stiffness * work_;
      }
    }
    iterateResidual(internal, free_->stiffness, newVelocity, residual);
    if (retreatContactStep(residual.norm() / scale, iterations, allowed, correction)) continue;
    if (stopContactIterations(residual.norm() / scale, iterations, allowed)) return iterations;
    if (startInternal == nullptr) {
      solveLinearStep(-residual, correction);
    } else {
      solveWithContactMatrix(-residual, correction);  // the step-start tangent, the iterate's blocks
    }
    dv_ += correction;
    solvedWithContact = !contact_.empty();
  }
}

double BackwardEuler::contactResidualScale(double rhsNorm) const {
  // |b_0| alone vanishes for a body resting on an obstacle (the forces balance), where the
  // residual of an exact solve is rounding: relative to the impulse of the external force
  // over the step too, the tolerance stays meaningful there.
  const double scale = std::max(rhsNorm, predictedImpulse_);
  return scale > 0.0 ? scale : 1.0;
}

bool BackwardEuler::retreatContactStep(double relativeResidual, int iterations, int allowed,
                                       const Eigen::VectorXd& correction) {
  // Where the contact set or the clamped normal damping switches, a full Newton update can
  // land on a larger residual and the iteration cycle; halving it back (at most 8 times,
  // each halving one iteration) until the residual norm decreases breaks the cycle.
  constexpr int kMaxHalvings = 8;
  if (iterations == 1) {
    contactPreviousResidual_ = std::numeric_limits<double>::infinity();
    contactHalvings_ = 0;
  }
  if (relativeResidual < contactPreviousResidual_ || contactHalvings_ >= kMaxHalvings || iterations >= allowed ||
      !std::isfinite(relativeResidual) || relativeResidual <= options_.tolerance) {
    contactPreviousResidual_ = relativeResidual;
    contactHalvings_ = 0;
    contactStepFraction_ = 1.0;
    return false;
  }
  contactStepFraction_ *= 0.5;
  dv_ -= contactStepFraction_ * correction;
  ++contactHalvings_;
  return true;
}

bool BackwardEuler::stopContactIterations(double relativeResidual, int iterations, int allowed) {
  lastRelativeResidual_ = relativeResidual;
  if (!std::isfinite(relativeResidual)) {
    throw NumericalError(name() + ": the step to t = " + std::to_string(stepEndTime()) +
                         " has a non-finite residual with implicit contact");
  }
  if (relativeResidual <= options_.tolerance) return true;
  if (iterations < allowed) return false;
  if (relativeResidual > 1.0) {
    throw NumericalError(name() + ": Newton with implicit contact diverged in the step to t = " +
                         std::to_string(stepEndTime()) + ": relative residual " + std::to_string(relativeResidual) +
                         " after " + std::to_string(iterations) + " iterations (contactIterations)");
  }
  ++unconvergedContactSteps_;
  largestUnconvergedResidual_ = std::max(largestUnconvergedResidual_, relativeResidual);
  return true;
}

}  // namespace asyncfem
