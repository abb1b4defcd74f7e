// SPDX-License-Identifier: BSD-3-Clause
// The two-level structured step: right-hand sides (A4), (A12), the Schur solve on L and
// the recovery of every region's substeps (docs/asynchronous-integrator.md, Eqs. A13-A15).
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/integrator/stepFormula.hpp>
#include <cmath>
#include <string>

#include "detail/multirateSupport.hpp"
#include "detail/parallelTasks.hpp"
#include "twoLevelStepSolver.hpp"

namespace asyncfem {

using detail::TwoLevelStepSolver;

using detail::FastRegion;
using detail::substepTime;

// b^L = hL (f_ext - f_int(u_0) - D v_0) - hL^2 K v_0 (Eq. A1 at hL); for linear forces
// hL (f_ext - alpha M v_0 - K (u_0 + (beta + hL) v_0)). Stable coupling: plus Eq. (A12).
void TwoLevelStepSolver::largeRightHandSide() {
  Impl& d = *impl_;
  const Eigen::VectorXd& u0 = displacement_;
  const Eigen::VectorXd& v0 = velocity_;
  const double hL = timestep();
  const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
  const bool massDamping = system_.damped() && alpha != 0.0;
  const stepFormula::RightHandSide recipe = stepFormula::backwardEuler::rightHandSide(hL, beta);
  if (massDamping) {
    d.massVelocity.resize(u0.size());
    d.massVelocity.noalias() = system_.mass * v0;
  }
  if (!d.rowProducts()) {
    d.stiffVelocity.resize(u0.size());
    d.stiffVelocity.noalias() = d.stiffness * v0;
    // The state-dependent part, once per large step: f_int(u_0) + D v_0.
    d.stateForce = d.internalForce;
    if (system_.damped()) {
      if (alpha != 0.0) d.stateForce += alpha * d.massVelocity;
      d.stateForce += beta * d.stiffVelocity;
    }
  } else {
    d.work = u0 + recipe.velocityStiffness * v0;
  }
  const std::vector<int>& large = partition_.largeDofs();
  d.rhsL.resize(static_cast<Eigen::Index>(large.size()));
  for (std::size_t k = 0; k < large.size(); ++k) {
    const int dof = large[k];
    const double external = d.externalL ? (*d.externalL)[dof] : 0.0;
    const double state = d.rowProducts() ? detail::columnDot(d.stiffness, dof, d.work) +
                                               (massDamping ? alpha * d.massVelocity[dof] : 0.0)
                                         : d.stateForce[dof] + hL * d.stiffVelocity[dof];
    d.rhsL[static_cast<Eigen::Index>(k)] = recipe.scale * (external - state);
  }
  if (options_.coupling == AsyncCoupling::stable) addInterfaceVelocityTerms();
}

// Stable coupling: b^L += (1 - theta) hL^2 (K^{IS} v^S_0 + K_I^{II} v^I_0) (Eq. A12).
void TwoLevelStepSolver::addInterfaceVelocityTerms() {
  Impl& d = *impl_;
  const Eigen::VectorXd& v0 = velocity_;
  for (int i = 0; i < partition_.numRegions(); ++i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& pos = partition_.interfacePositions(i);
    if (pos.empty()) continue;
    detail::gatherInto(v0, partition_.regionDofs(i), rb.xSum);           // scratch: v^S_0
    detail::gatherInto(v0, partition_.interfaceDofs(i), rb.yInterface);  // scratch: v^I_0
    rb.interfaceRow.resize(static_cast<Eigen::Index>(pos.size()));
    rb.interfaceRow.noalias() = rb.Kis * rb.xSum;
    rb.interfaceRow.noalias() += rb.interfaceStiffness * rb.yInterface;
    for (std::size_t k = 0; k < pos.size(); ++k)
      d.rhsL[pos[k]] += rb.coupling.interfaceWeight * rb.interfaceRow[static_cast<Eigen::Index>(k)];
  }
}

// Every region's b^S (|S| x m, Eq. A4): b_r = hS (f_ext(t_r) - f_int(u_0) - (D + r hS K) v_0),
// from its DOFs only.
void TwoLevelStepSolver::regionRightHandSides() {
  Impl& d = *impl_;
  const Eigen::VectorXd& u0 = displacement_;
  const Eigen::VectorXd& v0 = velocity_;
  const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
  const bool massDamping = system_.damped() && alpha != 0.0;
  detail::parallelTasks(partition_.numRegions(), detail::threadBudget(options_.threads), [&](int i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& s = partition_.regionDofs(i);
    rb.rhs.resize(static_cast<Eigen::Index>(s.size()), rb.ratio);
    for (std::size_t k = 0; k < s.size(); ++k) {
      const int dof = s[k];
      const auto row = static_cast<Eigen::Index>(k);
      double state = 0.0, stiffVelocity = 0.0;  // (f_int(u_0) + D v_0)_dof and (K v_0)_dof
      if (d.rowProducts()) {
        stiffVelocity = detail::columnDot(d.stiffness, dof, v0);
        state = detail::columnDot(d.stiffness, dof, u0) + beta * stiffVelocity +
                (massDamping ? alpha * d.massVelocity[dof] : 0.0);
      } else {
        stiffVelocity = d.stiffVelocity[dof];
        state = d.stateForce[dof];
      }
      for (int r = 1; r <= rb.ratio; ++r) {
        const double tau = r * rb.smallStep;
        rb.rhs(row, r - 1) = rb.smallStep * (rb.external(row, r - 1) - state - tau * stiffVelocity);
      }
    }
  });
}

// Forward substitution y = (H^{SS})^{-1} b^S per region and its term of b^{L*} = b^L -
// H^{LS} y (Eq. A7); Y from H^{LL*} (Eq. A13); the regions' unknowns recovered from Y.
void TwoLevelStepSolver::solveStructured() {
  Impl& d = *impl_;
  const bool damped = system_.damped();
  const int threads = detail::threadBudget(options_.threads);
  runOwnedTasks(threads, [&](int i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    rb.forwardSubstitute(rb.rhs, rb.y);
    if (rb.Mis.rows() > 0) rb.interfaceRowOf(rb.y, damped);
  });
  d.rhsSchur = d.rhsL;
  subtractOwnedInterfaceRows(d.rhsSchur);
  const auto apply = [this](const Eigen::VectorXd& y, Eigen::VectorXd& out) { applySchur(y, out); };
  d.lagged.recoverFromProbes = false;
  if (partition_.largeDofs().empty()) {
    d.Y.resize(0);
  } else if (d.schur.borrowing()) {
    solveOnWholeFactor();
  } else if (!d.lagged.lagging && d.contact.factorIsExact() && !d.contactStep.correctionsStale) {
    d.schur.solve(d.rhsSchur, d.Y);
  } else {
    // At least laggedSchurIterations, and as many as one rebuild costs (rent or buy).
    if (turnsLaggedFactor()) d.rotations.update(*system_.mesh, displacement_);
    const double affordable = d.lagged.rebuildFlops / std::max(d.lagged.iterationFlops, 1.0);
    const int budget =
        std::max(options_.keptFactors.laggedSchurIterations, static_cast<int>(std::min(affordable, 1000.0)));
    const detail::SchurSolver::Tracker track = [this, threads](double coefficient, bool reset) {
      sumProbeSubstitutions(threads, coefficient, reset);
    };
    const detail::SchurSolver::Refinement result =
        d.schur.refine(d.rhsSchur, d.Y, apply, options_.coupling == AsyncCoupling::stable, budget,
                       options_.keptFactors.laggedSchurTolerance, track);
    d.lagged.recoverFromProbes = result.converged;
    runStats_.schurIterations += result.iterations;
    d.lagged.rent += result.iterations * d.lagged.iterationFlops;
    if (result.converged && !result.zeroRightHandSide) {
      ++runStats_.laggedSteps;
      runStats_.largestSchurResidual = std::max(runStats_.largestSchurResidual, result.residual);
    }
    if (!result.converged) {
      // The old factor no longer preconditions well enough: rebuild now (exact solve). With
      // Z and C_i current (only L's contact blocks changed), H^{LL*} alone.
      Stopwatch rebuild;
      if (!d.lagged.lagging && !d.contactStep.correctionsStale) {
        refactorLargeSystem();
      } else {
        fullSchurRebuild();
      }
      runStats_.rebuildSeconds += rebuild.stop();
      d.schur.solve(d.rhsSchur, d.Y);
    }
  }
  runOwnedTasks(threads, [&](int i) { recoverRegion(i); });
  if (distributed()) shareRecoveries();
}

// X_m and sum_r X_r from the stored Z_m and sum_r Z_r, or every X_r by a second forward
// substitution with b^S - H^{SL} Y (block r of H^{SL} Y = B_r Y_I).
void TwoLevelStepSolver::recoverRegion(int i) {
  Impl& d = *impl_;
  FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
  const std::vector<int>& pos = partition_.interfacePositions(i);
  if (pos.empty()) {
    std::swap(rb.x, rb.y);
    rb.substituted = true;
    return;
  }
  detail::gatherInto(d.Y, pos, rb.yInterface);
  if (d.lagged.recoverFromProbes) {
    // X = y - (H^{SS})^{-1} H^{SL} Y, the substitution of H^{SL} Y summed along the lagged
    // solve's iterations (forward substitution is linear): no substitution of its own.
    rb.x = rb.y;
    rb.x -= rb.probeSum;
    rb.substituted = true;
    return;
  }
  // Implicit contact evaluates the force at every substep: x must hold them all, unless
  // the step may be certified free of contact (Eq. C6) with the bounds of Z.
  const bool endStates = !implicitContact() || (d.contactStep.certifying && rb.reach.size() == rb.y.rows());
  if (rb.dense.recovery && !observer_ && !d.lagged.lagging && !d.schur.borrowing() && endStates) {
    rb.xLast = rb.y.col(rb.ratio - 1);
    rb.xLast.noalias() -= rb.zLast * rb.yInterface;
    rb.xSum = rb.y.rowwise().sum();
    rb.xSum.noalias() -= rb.zSum * rb.yInterface;
    rb.substituted = false;
    return;
  }
  substituteRegion(i);
}

// Every X_r of region i by the forward substitution of b^S - H^{SL} Y (yInterface gathered).
void TwoLevelStepSolver::substituteRegion(int i) {
  Impl& d = *impl_;
  FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
  const bool damped = system_.damped();
  const detail::CouplingCoefficients& k = rb.coupling;
  rb.couplingProducts(damped);
  for (int r = 1; r <= rb.ratio; ++r) {
    rb.rhs.col(r - 1) -= k.bM[r - 1] * rb.massY + k.bK[r - 1] * rb.stiffY;
    if (damped) rb.rhs.col(r - 1) -= k.bD[r - 1] * rb.dampY;
  }
  rb.forwardSubstitute(rb.rhs, rb.x);
  rb.substituted = true;
}

// v^S_r = v^S_0 + X_r, u^S_m = u^S_0 + hS sum_r v^S_r; v^L = v^L_0 + Y, u^L = u^L_0 + hL v^L.
void TwoLevelStepSolver::assembleNewState(double t0, double t1) {
  Impl& d = *impl_;
  const Eigen::VectorXd& u0 = displacement_;
  const Eigen::VectorXd& v0 = velocity_;
  d.newU = u0;
  d.newV = v0;
  for (int i = 0; i < partition_.numRegions(); ++i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& s = partition_.regionDofs(i);
    const int m = rb.ratio;
    if (rb.substituted) {
      rb.xLast = rb.x.col(m - 1);
      rb.xSum = rb.x.rowwise().sum();
    }
    for (std::size_t k = 0; k < s.size(); ++k) {
      const auto row = static_cast<Eigen::Index>(k);
      d.newV[s[k]] = v0[s[k]] + rb.xLast[row];
      d.newU[s[k]] = u0[s[k]] + rb.smallStep * (m * v0[s[k]] + rb.xSum[row]);
    }
    if (!observer_ || !rb.owned) continue;
    // Substep states, only for an installed observer (x then holds every substep).
    const Eigen::VectorXd vS0 = detail::gather(v0, s), uS0 = detail::gather(u0, s);
    Eigen::VectorXd running = Eigen::VectorXd::Zero(rb.x.rows());
    for (int r = 1; r <= m; ++r) {
      running += rb.x.col(r - 1);
      const Eigen::VectorXd uS = uS0 + rb.smallStep * (double(r) * vS0 + running);
      const Eigen::VectorXd vS = vS0 + rb.x.col(r - 1);
      observer_(i, r, substepTime(t0, t1, r, m, rb.smallStep), uS, vS);
    }
  }
  const std::vector<int>& large = partition_.largeDofs();
  const double hL = timestep();
  for (std::size_t k = 0; k < large.size(); ++k) {
    d.newV[large[k]] = v0[large[k]] + d.Y[static_cast<Eigen::Index>(k)];
    d.newU[large[k]] = u0[large[k]] + hL * d.newV[large[k]];
  }
}

}  // namespace asyncfem
