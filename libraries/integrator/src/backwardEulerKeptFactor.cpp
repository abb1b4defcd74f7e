// SPDX-License-Identifier: BSD-3-Clause
// BackwardEuler's kept factor across checkpoints: what internalState() records of it and
// how setInternalState() factors the same matrix again (detail/keptFactor.hpp).
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/integrator/contactBlock.hpp>
#include <sstream>
#include <string>

#include "detail/freeSystem.hpp"
#include "detail/keptFactor.hpp"

namespace asyncfem {

using detail::KeptMatrix;
using detail::TimeInto;

void BackwardEuler::recordKeptMatrix() {
  // The factor is that of free_->systemMatrix as last assembled: the step's own matrix
  // (K at the step start u_k, or a linear model's constant K) or a Newton iteration's J
  // (K at the iterate in fullU_), each with the contact blocks of contact_ when it got them.
  detail::KeptFactorRecord& record = *keptRecord_;
  KeptMatrix& kept = record.kept;
  kept.kind = record.assembledKind;
  kept.timestep = timestep_;
  const bool newton = kept.kind == KeptMatrix::Kind::newton;
  kept.dampingAtIterate = newton && record.assembledDampingAtIterate;
  if (!linear_ && (!newton || !kept.dampingAtIterate)) {
    kept.stepStart = displacement_;
  } else {
    kept.stepStart.resize(0);
  }
  if (newton) {
    kept.iterate = fullU_;
  } else {
    kept.iterate.resize(0);
  }
  if (record.assembledWithContact) {
    kept.contact = contact_.couplings.empty() ? contact_ : boundCouplings(contact_);  // as assembled
  } else {
    kept.contact.clear();
  }
}

void BackwardEuler::rebuildKeptMatrix(const KeptMatrix& kept) {
  // The same evaluations and the same assembly calls as when it was first built, so the
  // same values bit for bit (the force models' tangents depend on u only). The step that
  // follows evaluates its own tangent into free_->stiffness again.
  detail::FreeSystem& free = *free_;
  if (kept.stepStart.size() != 0) free.evaluateForcesAndTangent(system_, kept.stepStart, free.stiffness, stats_);
  if (kept.kind == KeptMatrix::Kind::step) {
    assembleStepMatrix(kept.timestep, kept.contact);
    return;
  }
  free.evaluateForcesAndTangent(system_, kept.iterate, free.iterateStiffness, stats_);
  assembleNewtonMatrix(kept.timestep, kept.dampingAtIterate ? free.iterateStiffness : free.stiffness, kept.contact);
}

Eigen::VectorXd BackwardEuler::internalState() const {
  if (!reuse_) return {};
  detail::KeptFactorState state;
  state.rule = reuse_->ruleState();
  if (state.rule.hasFactor && !state.rule.refactorPending) state.matrix = keptRecord_->kept;
  state.previousSolution = dv_;
  return detail::encodeKeptFactorState(state);
}

void BackwardEuler::setInternalState(const Eigen::VectorXd& state) {
  if (!reuse_) {
    Integrator::setInternalState(state);  // nothing beyond (u, v, t): only an empty vector
    return;
  }
  detail::KeptFactorRecord& record = *keptRecord_;
  if (state.size() == 0) {
    // A checkpoint from before the kept factor was in checkpoints: factor afresh.
    reuse_->restoreRuleState({}, nullptr);
    record.kept = KeptMatrix{};
    record.restoredWithoutState = true;
    dv_.resize(0);
    return;
  }
  detail::KeptFactorState decoded =
      detail::decodeKeptFactorState(state, {system_.numDofs(), system_.freeDofs.numFree(), linear_}, name());
  const bool needsMatrix = decoded.matrix.kind != KeptMatrix::Kind::none;
  if (needsMatrix) rebuildKeptMatrix(decoded.matrix);
  const long long before = reuse_->stats().refactorizations;
  try {
    TimeInto timer(stats_.factorizationSeconds);
    reuse_->restoreRuleState(decoded.rule, needsMatrix ? &free_->systemMatrix : nullptr);
  } catch (const NumericalError& error) {
    free_->rethrowWithMeshDof(error);
  }
  stats_.factorizations += reuse_->stats().refactorizations - before;
  record.kept = std::move(decoded.matrix);
  record.restoredWithoutState = false;
  dv_ = std::move(decoded.previousSolution);
}

}  // namespace asyncfem
