// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/integrator/stepFormula.hpp>
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

BackwardEuler::BackwardEuler(DynamicSystem system, double timestep, const IntegratorOptions& options)
    : Integrator(std::move(system), timestep), options_(options) {
  if (options_.maxIterations < 1) {
    throw ValidationError("backward Euler needs maxIterations >= 1 (got " + std::to_string(options_.maxIterations) +
                          ")");
  }
  if (!(options_.tolerance >= 0.0)) {
    throw ValidationError("backward Euler needs a Newton tolerance >= 0 (got " + std::to_string(options_.tolerance) +
                          ")");
  }
  if (options_.contactIterations < 1) {
    throw ValidationError("backward Euler needs contactIterations >= 1 (got " +
                          std::to_string(options_.contactIterations) + ")");
  }
  if (options_.reuseFactor && !(options_.pcgTolerance > 0.0 && options_.pcgTolerance < 1.0)) {
    throw ValidationError("backward Euler needs a PCG tolerance in (0, 1) (got " +
                          std::to_string(options_.pcgTolerance) + ")");
  }
  if (options_.reuseFactor && options_.pcgRefactorIterations < 1) {
    throw ValidationError("backward Euler needs pcgRefactorIterations >= 1 (got " +
                          std::to_string(options_.pcgRefactorIterations) + ")");
  }
  linear_ = system_.forceModel->isLinear();
  implicitExternal_ = static_cast<bool>(system_.externalForceJacobian);
  // Couplings only where the low-rank update can take them (the constant K of a linear
  // model); the nonlinear path assembles per-vertex blocks as before.
  coupledContact_ = implicitExternal_ && linear_ && static_cast<bool>(system_.externalForceCoupledJacobian);
  lowRank_ = std::make_unique<detail::LowRankContactSolver>();
  // With implicit contact a linear model's matrix changes with the contact set too.
  if (options_.reuseFactor && (!linear_ || implicitExternal_)) {
    FactorReuseOptions reuseOptions;
    reuseOptions.relativeTolerance = options_.pcgTolerance;
    reuseOptions.refactorAfterIterations = options_.pcgRefactorIterations;
    reuseOptions.maxIterations = std::max(25, 3 * options_.pcgRefactorIterations);
    reuseOptions.factorCostInIterations = options_.pcgFactorCost;
    reuseOptions.singlePrecisionPreconditioner = options_.pcgSinglePrecision;
    reuse_ = std::make_unique<FactorReusingSolver>(options_.solver, reuseOptions);
    keptRecord_ = std::make_unique<detail::KeptFactorRecord>();
  }
  {
    TimeInto timer(stats_.assemblySeconds);
    free_ = std::make_unique<detail::FreeSystem>(system_, options_.solver);
  }
  if (!system_.damped()) stats_.skipped.emplace_back("damping matrix (alpha = beta = 0)");
  if (implicitExternal_ && options_.lineSearch && options_.maxIterations > 1) {
    stats_.skipped.emplace_back(
        "line search (implicit contact: the step equations are no potential's gradient; Newton updates taken in full)");
  }
  if (linear_) {
    // f_int(u) = K u with K constant: evaluate K once (at rest) and keep it.
    Eigen::VectorXd rest = Eigen::VectorXd::Zero(system_.numDofs());
    free_->evaluateForcesAndTangent(system_, rest, free_->stiffness, stats_);
    stats_.skipped.emplace_back(implicitExternal_ ? "refactorization while no vertex is in contact"
                                                  : "refactorization (constant system matrix)");
    if (options_.maxIterations > 1) {
      stats_.skipped.emplace_back("Newton iterations (linear force model: the linearized step is exact)");
    }
    assembleAndFactor();
  }
}

BackwardEuler::~BackwardEuler() = default;

void BackwardEuler::setTimestep(double timestep) {
  const double previous = timestep_;
  Integrator::setTimestep(timestep);
  if (timestep != previous) factorizationStale_ = true;
}

void BackwardEuler::assembleSystemMatrix(bool withContact) {
  static const VertexJacobian noContact;
  assembleStepMatrix(timestep_, withContact ? contact_ : noContact);
  if (keptRecord_) {
    keptRecord_->assembledKind = detail::KeptMatrix::Kind::step;
    keptRecord_->assembledWithContact = withContact;
    keptRecord_->assembledDampingAtIterate = false;
  }
}

void BackwardEuler::assembleStepMatrix(double h, const VertexJacobian& contact) {
  const stepFormula::MatrixWeights weights =
      stepFormula::backwardEuler::systemMatrix(h, system_.rayleighMass, system_.rayleighStiffness);
  free_->assemble({weights.mass, weights.stiffness}, {&free_->mass, &free_->stiffness}, stats_);
  addContactBlocks(h, contact);
}

void BackwardEuler::assembleNewtonMatrix(double h, const Eigen::SparseMatrix<double>& damping,
                                         const VertexJacobian& contact) {
  // J = (1 + h alpha) M + h beta K_D + h^2 K(u_{k+1}^{(i)}), K_D the damping stiffness
  detail::FreeSystem& free = *free_;
  free.assemble({1.0 + (h * system_.rayleighMass), h * system_.rayleighStiffness, h * h},
                {&free.mass, &damping, &free.iterateStiffness}, stats_);
  addContactBlocks(h, contact);
}

void BackwardEuler::addContactBlocks(double h, const VertexJacobian& contact) {
  // The contact force linearized at its last evaluation (the prediction or an iterate):
  // f ~ f_i - (h K_c + C_c) (dv - dv_i), so the step's matrix gains h^2 K_c + h C_c.
  if (!contact.empty()) free_->addVertexBlocks(system_.freeDofs, contact, h * h, h, stats_);
}

void BackwardEuler::assembleAndFactor() {
  assembleSystemMatrix(false);
  free_->factorize(stats_);
  factorizationStale_ = false;
  factorHasContact_ = false;
}

const FactorReuseStats* BackwardEuler::factorReuseStats() const { return reuse_ ? &reuse_->stats() : nullptr; }

RunReport BackwardEuler::report() const {
  RunReport report;
  report.factorNonZeros = free_->solver().stats().factorNonZeros;
  if (keptRecord_ && keptRecord_->restoredWithoutState) {
    std::ostringstream caveat;
    caveat << "the checkpoint holds no kept-factor state (written before checkpoint format version 3), so the resumed "
              "run factors at its first step; its frames match an uninterrupted run to about the PCG tolerance ("
           << options_.pcgTolerance << "), not bit for bit";
    report.resumeCaveat = caveat.str();
  }
  if (implicitExternal_) {
    std::ostringstream text;
    text << "implicit contact: " << contactSteps_ << " of " << stats_.steps
         << " steps predicted contact; Newton on the step equations with the contact at each iterate, "
         << unconvergedContactSteps_ << " steps stopped at "
         << std::max(options_.maxIterations, options_.contactIterations) << " iterations unconverged";
    if (residualSteps_ > 0) {
      text << " (" << std::setprecision(3)
           << static_cast<double>(residualStepSolves_) / static_cast<double>(residualSteps_) << " solves per step in "
           << residualSteps_ << " steps that iterated)";
    }
    if (linear_) {
      text << "; " << lowRankSolves_ << " contact solves by a low-rank update of the kept factor ("
           << lowRank_->cachedVertices() << " vertices' columns cached)";
    }
    if (coupledContact_) {
      text << "; surface pairs with their off-diagonal blocks (" << boundedCouplingSolves_
           << " solves took their per-vertex bounds instead)";
    }
    if (unconvergedContactSteps_ > 0) {
      text << " (largest relative residual " << std::setprecision(3) << largestUnconvergedResidual_ << ")";
    }
    report.lines.push_back(text.str());
  }
  if (linear_) return report;
  std::ostringstream text;
  if (!reuse_) {
    text << "linear solves: exact, one factorization per Newton iteration (reuseFactor off)";
  } else {
    const FactorReuseStats& reuse = reuse_->stats();
    const long long steps = std::max<long long>(stats_.steps, 1);
    text << "linear solves: kept factor as PCG preconditioner (reuseFactor, relative residual " << options_.pcgTolerance
         << (reuse.singlePrecisionPreconditioner ? ", applied in single precision" : "")
         << "): " << reuse.refactorizations << " factorizations in " << stats_.steps << " steps, "
         << std::setprecision(3) << static_cast<double>(reuse.pcgIterations) / static_cast<double>(steps)
         << " PCG iterations per step; the kept factor's state goes into checkpoints, so a resumed run continues "
            "bit for bit";
  }
  report.lines.push_back(text.str());
  return report;
}

void BackwardEuler::assembleForReuse() {
  assembleSystemMatrix(true);
  updateReusedMatrix();
}

void BackwardEuler::updateReusedMatrix() {
  const long long before = reuse_->stats().refactorizations;
  try {
    TimeInto timer(stats_.factorizationSeconds);
    reuse_->setMatrix(free_->systemMatrix);
  } catch (const NumericalError& error) {
    free_->rethrowWithMeshDof(error);
  }
  stats_.factorizations += reuse_->stats().refactorizations - before;
  if (reuse_->stats().refactorizations != before) recordKeptMatrix();
}

void BackwardEuler::solveWithReuse(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution) {
  const long long before = reuse_->stats().refactorizations;
  {
    TimeInto timer(stats_.solveSeconds);
    // solution still holds the previous solve's result (dv of the previous step): a
    // starting point PCG takes when it is closer than 0. A PCG run that does not converge
    // refactors, which may fail like any factorization.
    try {
      reuse_->solve(rhs, solution, solution);
    } catch (const NumericalError& error) {
      free_->rethrowWithMeshDof(error);
    }
  }
  stats_.factorizations += reuse_->stats().refactorizations - before;
  if (reuse_->stats().refactorizations != before) recordKeptMatrix();  // PCG gave up: the matrix was factored
  ++stats_.solvedRightHandSides;
}

void BackwardEuler::step() {
  free_->stepTime = stepEndTime();
  if (linear_) {
    stepLinear();
  } else {
    stepNonlinear();
  }
}

void BackwardEuler::restrictStepStart(Eigen::VectorXd& force) {
  const FreeDofs& dofs = system_.freeDofs;
  detail::restrictTo(dofs, displacement_, u_);
  detail::restrictTo(dofs, velocity_, v_);
  if (implicitExternal_) {
    // Linearized at the predicted state (u_k + h v_k, v_k): a vertex about to reach an
    // obstacle is already in the step's contact set, so the spring is never skipped for a
    // step (the class comment has the equations).
    fullPredicted_ = displacement_ + timestep_ * velocity_;
    zeroFixed(fullPredicted_);
    evaluateImplicitExternalForce(fullPredicted_, velocity_, force);
    predictedImpulse_ = timestep_ * force.norm();
    if (!contact_.empty()) ++contactSteps_;
  } else if (system_.externalForce) {
    evaluateExternalForce(stepEndTime(), fullForce_);
    detail::restrictTo(dofs, fullForce_, force);
  } else {
    force.setZero(u_.size());
  }
}

void BackwardEuler::evaluateImplicitExternalForce(const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                                                  Eigen::VectorXd& force) {
  {
    TimeInto timer(stats_.forceSeconds);
    fullForce_.setZero(system_.numDofs());
    system_.externalForce(stepEndTime(), displacement, velocity, fullForce_);
    contact_.clear();
    if (coupledContact_) {
      system_.externalForceCoupledJacobian(stepEndTime(), displacement, velocity, contact_);
    } else {
      system_.externalForceJacobian(stepEndTime(), displacement, velocity, contact_);
    }
  }
  detail::restrictTo(system_.freeDofs, fullForce_, force);
}

void BackwardEuler::finishStep() {
  if (implicitExternal_ && lastRelativeResidual_ >= 0.0) {
    ++residualSteps_;
    residualStepSolves_ += lastIterations_;
  }
  v_ += dv_;
  u_ += timestep_ * v_;
  detail::expandTo(system_.freeDofs, u_, fullU_);
  detail::expandTo(system_.freeDofs, v_, fullV_);
  commitStep(fullU_, fullV_);
}

void BackwardEuler::stepLinear() {
  const double h = timestep_;
  const double alpha = system_.rayleighMass;
  const double beta = system_.rayleighStiffness;
  if (factorizationStale_) lowRank_->clear();  // a new timestep: a new M + h D + h^2 K
  if (factorizationStale_ || factorHasContact_) assembleAndFactor();
  restrictStepStart(force_);
  rhs_ = force_;
  {
    // Fixed DOFs are zero, so the free rows of K u are K_ff u_f:
    // b = h ( f_ext - K (u + (beta + h) v) - alpha M v ) (Eq. A1, stepFormula).
    TimeInto timer(stats_.forceSeconds);
    const stepFormula::RightHandSide recipe = stepFormula::backwardEuler::rightHandSide(h, beta);
    work_ = u_ + recipe.velocityStiffness * v_;
    // A serial product on purpose: an OpenMP one leaves spinning threads that compete
    // with the solver's BLAS threads in the back-substitution right after it.
    rhs_.noalias() -= free_->stiffness * work_;
    if (alpha != 0.0) rhs_.noalias() -= alpha * (free_->mass * v_);
    rhs_ *= recipe.scale;
  }
  const bool predictedContact = !contact_.empty();
  solveLinearStep(rhs_, dv_);
  lastIterations_ = 1;
  lastRelativeResidual_ = -1.0;
  if (implicitExternal_) lastIterations_ = linearContactIterations(rhs_.norm(), predictedContact, nullptr);
  finishStep();
}

void BackwardEuler::solveLinearStep(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution) {
  if (contact_.empty()) {
    if (factorHasContact_) assembleAndFactor();
    free_->solve(rhs, solution, stats_);
    return;
  }
  // K constant, the contact blocks not: M + h D + h^2 K is kept factored, and a solve with
  // contact updates it by the blocks' low rank (Woodbury) where that is cheaper than a
  // factorization; else it solves its own matrix (kept-factor PCG with reuseFactor, or a
  // factorization that the next contact-free solve replaces).
  if (options_.contactLowRank && lowRank_->pays(*free_, system_.freeDofs, contact_)) {
    if (factorHasContact_) assembleAndFactor();
    const double h = timestep_;
    lowRank_->solve(*free_, system_.freeDofs, contact_, h * h, h, rhs, solution, stats_);
    ++lowRankSolves_;
    return;
  }
  solveWithContactMatrix(rhs, solution);
}

void BackwardEuler::solveWithContactMatrix(const Eigen::VectorXd& rhs, Eigen::VectorXd& solution) {
  if (!contact_.couplings.empty()) ++boundedCouplingSolves_;
  assembleSystemMatrix(true);
  if (reuse_) {
    updateReusedMatrix();
    solveWithReuse(rhs, solution);
  } else {
    free_->factorize(stats_);
    factorHasContact_ = true;
    free_->solve(rhs, solution, stats_);
  }
}

void BackwardEuler::stepNonlinear() {
  const double h = timestep_;
  const double alpha = system_.rayleighMass;
  const double beta = system_.rayleighStiffness;
  detail::FreeSystem& free = *free_;
  restrictStepStart(force_);
  const bool predictedContact = !contact_.empty();

  // Linearized step: tangent and forces at u_k.
  free.evaluateForcesAndTangent(system_, displacement_, free.stiffness, stats_);
  Eigen::VectorXd internal;
  detail::restrictTo(system_.freeDofs, free.fullForces(), internal);
  if (reuse_) {
    assembleForReuse();
  } else {
    assembleSystemMatrix(true);
    free.factorize(stats_);
  }
  {
    TimeInto timer(stats_.forceSeconds);
    const stepFormula::RightHandSide recipe = stepFormula::backwardEuler::rightHandSide(h, beta);
    rhs_ = force_ - internal;
    work_ = recipe.velocityStiffness * v_;
    rhs_.noalias() -= free.stiffness * work_;
    if (alpha != 0.0) rhs_.noalias() -= alpha * (free.mass * v_);
    rhs_ *= recipe.scale;
  }
  const double rhsNorm = rhs_.norm();
  if (reuse_) {
    solveWithReuse(rhs_, dv_);
  } else {
    free.solve(rhs_, dv_, stats_);
  }
  lastRelativeResidual_ = -1.0;
  lastLineSearchHalvings_ = 0;
  if (options_.lineSearch && options_.maxIterations > 1 && !implicitExternal_) {
    // The linearized step starts from dv = 0 with the slope estimated by its own
    // right-hand side (the linearization of -R(0)).
    Eigen::VectorXd start = Eigen::VectorXd::Zero(dv_.size());
    const Eigen::VectorXd step = dv_;
    dv_ = start + backtrack(start, step, incrementalPotential(start), -rhs_.dot(step)) * step;
  }
  if (options_.maxIterations > 1) {
    lastIterations_ = newtonIterations(rhsNorm, internal);
  } else if (implicitExternal_) {
    // The linearized step asked for: elasticity stays linearized at u_k, contact iterates.
    lastIterations_ = linearContactIterations(rhsNorm, predictedContact, &internal);
  } else {
    lastIterations_ = 1;
  }
  finishStep();
}

void BackwardEuler::iterateResidual(const Eigen::VectorXd& internal,
                                    const Eigen::SparseMatrix<double>& dampingStiffness,
                                    const Eigen::VectorXd& newVelocity, Eigen::VectorXd& residual) {
  // R = M dv - h ( f_ext - f_int(u_{k+1}) - D v_{k+1} )
  const double h = timestep_;
  const double alpha = system_.rayleighMass;
  const double beta = system_.rayleighStiffness;
  TimeInto timer(stats_.forceSeconds);
  residual = free_->mass * dv_;
  residual.noalias() -= h * (force_ - internal);
  if (alpha != 0.0) residual.noalias() += (h * alpha) * (free_->mass * newVelocity);
  if (beta != 0.0) residual.noalias() += (h * beta) * (dampingStiffness * newVelocity);
}

int BackwardEuler::newtonIterations(double rhsNorm, Eigen::VectorXd& internal) {
  const double h = timestep_;
  const double beta = system_.rayleighStiffness;
  detail::FreeSystem& free = *free_;
  const bool lineSearch = options_.lineSearch && options_.maxIterations > 1 && !implicitExternal_;
  const bool dampingAtIterate = options_.rayleighStiffnessAtIterate && beta != 0.0;
  const double scale = implicitExternal_ ? contactResidualScale(rhsNorm) : (rhsNorm > 0.0 ? rhsNorm : 1.0);
  const int allowed =
      implicitExternal_ ? std::max(options_.maxIterations, options_.contactIterations) : options_.maxIterations;
  Eigen::VectorXd newVelocity, newDisplacement, residual, correction;
  for (int iterations = 1;; ++iterations) {
    newVelocity = v_ + dv_;
    newDisplacement = u_ + h * newVelocity;
    detail::expandTo(system_.freeDofs, newDisplacement, fullU_);
    if (implicitExternal_) {
      // The contact force and its derivatives at the iterate: Newton on the step equations
      // with the contact set of the iterate.
      detail::expandTo(system_.freeDofs, newVelocity, fullV_);
      evaluateImplicitExternalForce(fullU_, fullV_, force_);
    }
    const bool mayIterate = iterations < allowed;
    if (mayIterate || dampingAtIterate) {
      free.evaluateForcesAndTangent(system_, fullU_, free.iterateStiffness, stats_);
    } else {
      free.evaluateForces(system_, fullU_, stats_);
    }
    detail::restrictTo(system_.freeDofs, free.fullForces(), internal);
    // D = alpha M + beta K(u_k), or beta K(u_{k+1}^{(i)}) with rayleighStiffnessAtIterate.
    const Eigen::SparseMatrix<double>& dampingStiffness = dampingAtIterate ? free.iterateStiffness : free.stiffness;
    iterateResidual(internal, dampingStiffness, newVelocity, residual);
    if (implicitExternal_) {
      if (retreatContactStep(residual.norm() / scale, iterations, allowed, correction)) continue;
      if (stopContactIterations(residual.norm() / scale, iterations, allowed)) return iterations;
      solveNewtonCorrection(dampingStiffness, residual, correction);
      dv_ += correction;
      continue;
    }
    lastRelativeResidual_ = residual.norm() / scale;
    if (lastRelativeResidual_ <= options_.tolerance) return iterations;
    if (!mayIterate) {
      detail::checkNewtonDiverged(name(), lastRelativeResidual_, iterations, residual, system_.freeDofs, stepEndTime());
      return iterations;
    }
    solveNewtonCorrection(dampingStiffness, residual, correction);
    // With D at the iterate R is not the potential's gradient, so Phi is no merit
    // function for these updates: they are taken in full, as Vega FEM does.
    if (lineSearch && !dampingAtIterate) {
      correction *= backtrack(dv_, correction, incrementalPotential(dv_), residual.dot(correction));
    }
    dv_ += correction;
  }
}

void BackwardEuler::solveNewtonCorrection(const Eigen::SparseMatrix<double>& dampingStiffness,
                                          const Eigen::VectorXd& residual, Eigen::VectorXd& correction) {
  detail::FreeSystem& free = *free_;
  assembleNewtonMatrix(timestep_, dampingStiffness, contact_);
  if (keptRecord_) {
    keptRecord_->assembledKind = detail::KeptMatrix::Kind::newton;
    keptRecord_->assembledWithContact = true;
    keptRecord_->assembledDampingAtIterate = &dampingStiffness == &free.iterateStiffness;
  }
  if (reuse_) {
    updateReusedMatrix();
    solveWithReuse(-residual, correction);
  } else {
    free.factorize(stats_);
    free.solve(-residual, correction, stats_);
  }
}

double BackwardEuler::incrementalPotential(const Eigen::VectorXd& dv) {
  // Phi(dv) = 1/2 dv^T M dv + E(u_k + h (v_k + dv)) - h f_ext^T dv + h dv^T D (v_k + dv / 2),
  // D = alpha M + beta K(u_k): its gradient is the residual R(dv) of the step equations.
  const double h = timestep_;
  const double alpha = system_.rayleighMass;
  const double beta = system_.rayleighStiffness;
  work_ = u_ + h * (v_ + dv);
  detail::expandTo(system_.freeDofs, work_, fullU_);
  double energy = 0.0;
  {
    TimeInto timer(stats_.forceSeconds);
    energy = system_.forceModel->elasticEnergy(fullU_);
  }
  work_ = v_ + 0.5 * dv;
  double damping = 0.0;
  if (alpha != 0.0) damping += alpha * dv.dot(free_->mass * work_);
  if (beta != 0.0) damping += beta * dv.dot(free_->stiffness * work_);
  return (0.5 * dv.dot(free_->mass * dv)) + energy - (h * force_.dot(dv)) + (h * damping);
}

double BackwardEuler::backtrack(const Eigen::VectorXd& dv, const Eigen::VectorXd& step, double potential,
                                double slope) {
  // Armijo: accept t once Phi(dv + t step) <= Phi(dv) + 1e-4 t slope, halving t up to
  // kMaxHalvings times; differences below 1e-12 |Phi| are rounding and count as no
  // increase. If no t passes, the one with the lowest potential is taken, so the
  // potential never rises by more than rounding.
  constexpr int kMaxHalvings = 12;
  const double roundingAllowance = 1e-12 * std::abs(potential);
  // A predicted decrease below the potential's own rounding cannot be checked (a neo-Hookean
  // energy at small strain is only accurate to about 1e-10 of itself): the iterate is
  // converged to rounding, and the update is taken in full.
  if (std::abs(slope) <= roundingAllowance) return 1.0;
  double t = 1.0;
  double bestT = 1.0;
  double bestPotential = std::numeric_limits<double>::infinity();
  for (int halving = 0; halving <= kMaxHalvings; ++halving) {
    const double trial = incrementalPotential(dv + t * step);
    if (std::isfinite(trial) && trial <= potential + (1e-4 * t * std::min(slope, 0.0)) + roundingAllowance) {
      return t;
    }
    if (std::isfinite(trial) && trial < bestPotential) {
      bestPotential = trial;
      bestT = t;
    }
    ++lastLineSearchHalvings_;
    t *= 0.5;
  }
  return bestPotential < std::numeric_limits<double>::infinity() ? bestT : t;
}

}  // namespace asyncfem
