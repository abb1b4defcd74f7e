// SPDX-License-Identifier: BSD-3-Clause
// Nonlinear forces: the factor of H^{LL*} kept as a preconditioner across large steps, its
// rent-or-buy price and the refreshes turned with the body (AsyncOptions::KeptFactors::laggedSchur;
// docs/asynchronous-integrator.md, "Lagged Schur factor").
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <cmath>
#include <string>

#include "detail/flopPrices.hpp"
#include "detail/multirateSupport.hpp"
#include "detail/parallelTasks.hpp"
#include "twoLevelStepSolver.hpp"

namespace asyncfem {

using detail::TwoLevelStepSolver;

using detail::FastRegion;
using detail::kBlockedFlopWeight;
using detail::kSolveCallFlops;

// A refresh (laggedSchurRotation): the kept corrections C_i turned with the body since the
// factor was built (Eq. T2) and H^{LL*} refactored from the current A^L, without Z. The
// next rebuild the rule asks for is a full one.
void TwoLevelStepSolver::refreshLaggedFactor() {
  Impl& d = *impl_;
  Stopwatch factor;
  d.rotations.update(*system_.mesh, displacement_);
  for (int i = 0; i < partition_.numRegions(); ++i) {
    d.rotations.turnBlock(partition_.interfaceDofs(i), d.regions[static_cast<std::size_t>(i)].correction);
  }
  d.schur.factor(d.largeSystem, partition_, d.regions, options_.schur, options_.coupling, schurReport_.asymmetry,
                 stats_);
  d.contact.noteFactored();
  stats_.factorizationSeconds += factor.stop();
  ++runStats_.laggedRefreshes;
  d.lagged.lastRebuildFull = false;
  keepLaggedFactor();
}

// After a factor of H^{LL*}: the rent-or-buy prices and, with laggedSchurRotation, the
// rotations measured from this state (where the factor's tangent was taken).
void TwoLevelStepSolver::keepLaggedFactor() {
  Impl& d = *impl_;
  priceLaggedFactor();
  if (!turnsLaggedFactor()) return;
  d.rotations.setReference(*system_.mesh, displacement_);
  const std::vector<int>& large = partition_.largeDofs();
  d.schur.setPreconditionerTransform(
      [&d, &large](Eigen::VectorXd& x, bool transpose) { d.rotations.rotate(large, x, transpose); });
}

bool TwoLevelStepSolver::turnsLaggedFactor() const {
  const Impl& d = *impl_;
  return options_.keptFactors.laggedSchur && options_.keptFactors.laggedSchurRotation && !d.model.linear &&
         system_.mesh && !options_.processes.largeSystemSolver && options_.method == AsyncSolveMethod::structured;
}

// The flop prices of the lagged factor's rent-or-buy rule, with the same weights as the
// quick set-up's (Eq. Q4): an iteration is one forward substitution per region, one solve
// with the kept factor and one product with A^L; a rebuild is Z (|I_i| substitutions per
// region, in blocks) and the factorization of H^{LL*}.
void TwoLevelStepSolver::priceLaggedFactor() {
  Impl& d = *impl_;
  const SparseSolver* schur = d.schur.solver();
  d.lagged.rent = 0.0;
  d.lagged.iterationFlops = kSolveCallFlops + 2.0 * static_cast<double>(d.largeSystem.nonZeros()) +
                            (schur != nullptr ? schur->stats().solveFlopsPerRhs : 0.0);
  d.lagged.rebuildFlops = schur != nullptr ? kBlockedFlopWeight * schur->stats().factorFlops : 0.0;
  for (std::size_t i = 0; i < d.regions.size(); ++i) {
    const FastRegion& rb = d.regions[i];
    const double substitution = rb.substitutionFlops;
    d.lagged.iterationFlops += substitution + rb.ratio * kSolveCallFlops;
    d.lagged.rebuildFlops +=
        kBlockedFlopWeight * substitution * static_cast<double>(partition_.interfaceDofs(static_cast<int>(i)).size());
  }
}

// The lagged solve's tracker (SchurSolver::Tracker): every region's probeSum follows
// (H^{SS})^{-1} H^{SL} Y as Y moves, from the substitutions applySchur made anyway.
void TwoLevelStepSolver::sumProbeSubstitutions(int threads, double coefficient, bool reset) {
  Impl& d = *impl_;
  runOwnedTasks(threads, [&](int i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    if (partition_.interfacePositions(i).empty()) return;
    if (reset) {
      rb.probeSum = rb.probeSolution;
    } else {
      rb.probeSum += coefficient * rb.probeSolution;
    }
  });
}

// out = H^{LL*} y for the current blocks: Â^L y minus, per region, the interface rows of
// H^{LS} (H^{SS})^{-1} H^{SL} y (one forward substitution per region).
void TwoLevelStepSolver::applySchur(const Eigen::VectorXd& y, Eigen::VectorXd& out) {
  Impl& d = *impl_;
  const bool damped = system_.damped();
  out.resize(y.size());
  out.noalias() = d.largeSystem * y;
  runOwnedTasks(detail::threadBudget(options_.threads), [&](int i) {
    FastRegion& rb = d.regions[static_cast<std::size_t>(i)];
    const std::vector<int>& pos = partition_.interfacePositions(i);
    if (pos.empty()) return;
    detail::gatherInto(y, pos, rb.yInterface);
    const detail::CouplingCoefficients& k = rb.coupling;
    rb.couplingProducts(damped);
    rb.probe.resize(rb.massY.size(), rb.ratio);
    for (int r = 1; r <= rb.ratio; ++r) {
      rb.probe.col(r - 1) = k.bM[r - 1] * rb.massY + k.bK[r - 1] * rb.stiffY;
      if (damped) rb.probe.col(r - 1) += k.bD[r - 1] * rb.dampY;
    }
    rb.forwardSubstitute(rb.probe, rb.probeSolution);
    rb.interfaceRowOf(rb.probeSolution, damped);
  });
  subtractOwnedInterfaceRows(out);
}

// Regions owned by one process (AsyncOptions::Processes::regionDistribution). Every process steps the
// same state and cuts every region's blocks (Â^L and the right-hand sides need them); only
// a region's owner factors A^S, computes Z and C_i, substitutes and recovers. The sums
// over processes below hand the others what they need, at the same points on every
// process, so all of them hold the same H^{LL*}, Y and new state and take the same
// decisions (lagged factor, rent or buy). A failure in a process's region work is held
// until the next sum, which carries it to every process, so all stop at the same point.

}  // namespace asyncfem
